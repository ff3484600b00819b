#!/usr/bin/env bash
# install-test.sh — the installed program on its own (README "Install and package").
#
#   install-test.sh CMAKE BUILD_DIR BINDIR DATADIR
#
# Installs BUILD_DIR into a scratch prefix P with CMAKE (`cmake --install --prefix P`), checks
# what goes where (P/BINDIR/ambience, P/DATADIR/{shaders,replays,bench-plots.py}), then runs
# `P/BINDIR/ambience run --max-frames 30` with no --replay from a scratch folder (no source or
# build tree around it, AMBIENCE_SHADER_DIR unset) and checks its report: the installed default
# replay, 30 frames, anchors captured. Last, with the installed shaders moved away, the same run must
# fail naming a shader file: the shaders it drew with were the installed ones. In between,
# `P/BINDIR/ambience tune` must find its installed study script.
# Exit 0: passed; 1: failed; 77: no offscreen GL platform (ctest counts it as skipped).
set -euo pipefail

cmake="$1" build="$(cd "$2" && pwd)" bindir="$3" datadir="$4"
scratch="$(mktemp -d "${TMPDIR:-/tmp}/ambience-install-test.XXXXXX")"
trap 'rm -rf "$scratch"' EXIT
prefix="$scratch/prefix"
fail() { echo "install-test: $*" >&2; exit 1; }

# (1) install, and what goes where
"$cmake" --install "$build" --prefix "$prefix" >"$scratch/install.log"
for f in "$bindir/ambience" "$datadir/shaders/terrain.vert" "$datadir/shaders/terrain.frag" \
         "$datadir/shaders/conventions.glsl" "$datadir/replays/highway-drive.json" \
         "$datadir/bench-plots.py" "$datadir/ambience-tune.py"; do
  [[ -e "$prefix/$f" ]] || fail "$f not installed"
done
[[ -x "$prefix/$bindir/ambience" ]] || fail "$bindir/ambience is not executable"
if find "$prefix" \( -name '*.a' -o -name '*_test' -o -name '*.ok' \) | grep -q .; then
  fail "build-tree files installed: $(find "$prefix" \( -name '*.a' -o -name '*_test' -o -name '*.ok' \))"
fi

# (2) the installed program, from a folder with nothing of the project in or above it
work="$scratch/work"
mkdir -p "$work"
cd "$work"
unset AMBIENCE_SHADER_DIR
bin="$prefix/$bindir/ambience"
if ! why=$("$bin" probe --at 0,0 --size 4 --out "$work/platform-check.exr" 2>&1 >/dev/null); then
  if grep -qiE "platform|GL entry points" <<<"$why"; then
    echo "install-test: skipped, no offscreen GL platform: $why"
    exit 77
  fi
  fail "probe failed: $why"
fi
"$bin" run --max-frames 30 --no-video --out run >"$work/run.log" 2>&1 ||
  fail "run failed: $(tail -n 5 "$work/run.log")"
[[ -s run/report.json ]] || fail "no report written"
[[ -s run/contact-sheet.png ]] || fail "no contact sheet written"
frames=$(find run/frames -name '*.png' | wc -l)
((frames == 3)) || fail "expected 3 PNG frames (30 frames, every 10th), found $frames"
python=/usr/bin/python3
[[ -x $python ]] || python=python3
expected="$prefix/$datadir/replays/highway-drive.json"
"$python" - run/report.json "$expected" <<'PY' || fail "report check failed"
import json, os, sys
r = json.load(open(sys.argv[1]))
problems = []
if os.path.realpath(r.get("replay", "")) != os.path.realpath(sys.argv[2]):
    problems.append(f"replay {r.get('replay')!r}, expected the installed default {sys.argv[2]}")
if r.get("frameCount") != 30:
    problems.append(f"frameCount {r.get('frameCount')}, expected 30")
if not r.get("ambience", {}).get("anchorsEnd", 0) > 0:
    problems.append("no anchors at the end of the run")
for p in problems:
    print("install-test:", p, file=sys.stderr)
sys.exit(1 if problems else 0)
PY

# (3) the installed tune finds its study script and the installed replays (its wiring only:
# AMBIENCE_TUNE_FAKE stands in for the runs, which (2) has shown)
if /usr/bin/python3 -c "import optuna" 2>/dev/null; then
  AMBIENCE_TUNE_FAKE=1 "$bin" tune --oracle self --trials 2 --max-frames 10 --out tune \
    >"$work/tune.log" 2>&1 || fail "tune failed: $(tail -n 3 "$work/tune.log")"
  [[ -s tune/front/00.json && -s tune/summary.md && -s tune/trials.csv ]] ||
    fail "tune wrote no front/00.json, summary.md or trials.csv"
else
  echo "install-test: tune not checked, python3-optuna is missing"
fi

# (4) without the installed shaders the installed program cannot draw: it used no other copy
mv "$prefix/$datadir/shaders" "$scratch/shaders-away"
set +e
"$bin" run --max-frames 1 --frames none --no-video --out run-noshaders >"$work/noshaders.log" 2>&1
rc=$?
set -e
((rc == 2)) || fail "run without installed shaders exited $rc, expected 2: $(tail -n 3 "$work/noshaders.log")"
grep -q "shader" "$work/noshaders.log" || fail "run without shaders did not name a shader file"

echo "install-test: passed ($(find "$prefix" -type f | wc -l) files installed)"
