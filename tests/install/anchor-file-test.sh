#!/usr/bin/env bash
# anchor-file-test.sh — a saved anchor store read back by tools other than ours
# (README "Anchor files"; docs/ARCHITECTURE.md "Anchor store").
#
#   anchor-file-test.sh AMBIENCE INFO_SCRIPT
#
# `AMBIENCE run --save-anchors F.vdb` on the default replay (120 frames, no main view), then:
#   - OpenVDB's Python module (pyopenvdb, python3-openvdb) through INFO_SCRIPT
#     (scripts/anchor-store-info.py --expect-anchors N): the format and anchor count in the
#     file's metadata, every grid present with its type, one voxel per anchor in every grid it
#     can read, at the same places, with values in range;
#   - OpenImageIO's oiiotool (openimageio-tools): the float and vec3 grids it shows as
#     subimages are exactly the format's, each with N voxels;
# where N is the anchor count the run printed and wrote in its report. A missing tool is
# skipped with its reason; exit 77 (skipped) when neither is there or there is no offscreen GL.
set -euo pipefail

bin="$(realpath "$1")" info="$(realpath "$2")"
scratch="$(mktemp -d "${TMPDIR:-/tmp}/ambience-anchor-file-test.XXXXXX")"
trap 'rm -rf "$scratch"' EXIT
fail() { echo "anchor-file-test: $*" >&2; exit 1; }
cd "$scratch"

if ! why=$("$bin" probe --at 0,0 --size 4 --out platform-check.exr 2>&1 >/dev/null); then
  if grep -qiE "platform|GL entry points" <<<"$why"; then
    echo "anchor-file-test: skipped, no offscreen GL platform: $why"
    exit 77
  fi
  fail "probe failed: $why"
fi
"$bin" run --max-frames 120 --no-frames --save-anchors store.vdb --out run >run.log 2>&1 ||
  fail "run failed: $(tail -n 5 run.log)"
anchors=$(sed -nE 's/^ambience: ([0-9]+) anchors.*/\1/p' run.log)
[[ -n $anchors ]] || fail "the run printed no anchor count: $(cat run.log)"
((anchors > 0)) || fail "the run captured no anchors"
python=/usr/bin/python3
[[ -x $python ]] || python=python3
reported=$("$python" -c 'import json,sys; print(json.load(open(sys.argv[1]))["ambience"]["anchorsEnd"])' run/report.json)
[[ $reported == "$anchors" ]] || fail "report.json says $reported anchors at the end, the run printed $anchors"
echo "anchor-file-test: the run saved $anchors anchors"

checked=0
# (1) pyopenvdb
set +e
"$python" "$info" store.vdb --expect-anchors "$anchors" >info.log 2>&1
rc=$?
set -e
case $rc in
  0) checked=$((checked + 1)); echo "anchor-file-test: pyopenvdb: $(tail -n 1 info.log)" ;;
  77) echo "anchor-file-test: pyopenvdb check skipped: $(tail -n 1 info.log)" ;;
  *) cat info.log >&2; fail "pyopenvdb check failed (exit $rc)" ;;
esac

# (2) oiiotool: the float and vec3s grids, one subimage each
if command -v oiiotool >/dev/null; then
  oiiotool -a --info -v store.vdb >oiio.log 2>&1 || fail "oiiotool cannot read the store: $(tail -n 3 oiio.log)"
  expected=$( {
    for k in 0 1 2 3 4 5 6 7 8; do printf 'sh_current_%s\nsh_target_%s\nsh_blend_from_%s\n' "$k" "$k" "$k"; done
    printf '%s\n' age_s lifetime_s blend_elapsed_s presence since_birth_s capture_time_of_day_h
  } | sort)
  names=$(sed -nE 's/^ *openvdb:name: "(.*)"$/\1/p' oiio.log | sort)
  [[ $names == "$expected" ]] || fail "oiiotool's grids differ from the format's: $(diff <(echo "$expected") <(echo "$names") | tr '\n' ' ')"
  counts=$(sed -nE 's/^ *openvdb:file_voxel_count: ([0-9]+)$/\1/p' oiio.log | sort -u)
  [[ $counts == "$anchors" ]] || fail "oiiotool's voxel counts are $(echo $counts), expected $anchors each"
  checked=$((checked + 1))
  echo "anchor-file-test: oiiotool: $(wc -l <<<"$names") grids of $anchors voxels each"
else
  echo "anchor-file-test: oiiotool check skipped: no oiiotool (openimageio-tools)"
fi

((checked > 0)) || { echo "anchor-file-test: skipped, neither pyopenvdb nor oiiotool"; exit 77; }
echo "anchor-file-test: passed ($checked readers)"
