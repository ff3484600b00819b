#!/usr/bin/env bash
# Rebuilds the seed corpora in tests/fuzz/corpus/<target>/ from the project's own files and
# outputs, kept small (each file under 64 kB):
#   fuzz_replay             the shipped replays cut to their first 8 samples, and 8 samples
#                           around the stress flight's camera cut
#   fuzz_volume_settings,   settings examples (empty, a few keys), and from the settings
#   fuzz_baseline_settings  schema every key at its default and at its costly end
#   fuzz_sweep              the README's sweep example and a two-point sweep
#   fuzz_oracle             the oracle of a 30-frame run measured every 10th frame
#   fuzz_reference          the reference of a 30-frame run (two entries, two screen witnesses)
#   fuzz_anchor_store       the anchor store after one frame (every grid, no anchor yet),
#                           behind the byte that selects the checksum handling in the target
#   fuzz_cubemap            4 x 4 cube maps from `ambience probe` as .png, .exr and .hdr, each
#                           behind the byte that selects its extension in the target
#   fuzz_bench_manifest     bench.json of an emitted two-method bench (paths made neutral)
#   fuzz_run_report         the report.json of a 30-frame measured run, on one line
#   fuzz_exit_status        exit statuses as runs write them (ok, failed, killed, old form)
#
#   tests/fuzz/make-corpus.sh [ambience executable, default build/bin/ambience]
set -euo pipefail
cd "$(dirname "$0")/../.."
ambience="${1:-build/bin/ambience}"
corpus=tests/fuzz/corpus
tmp="$(mktemp -d "${TMPDIR:-/tmp}/ambience-corpus.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT

mkdir -p "$corpus"/{fuzz_replay,fuzz_volume_settings,fuzz_baseline_settings,fuzz_sweep,fuzz_oracle,fuzz_reference,fuzz_anchor_store,fuzz_cubemap}
mkdir -p "$corpus"/{fuzz_bench_manifest,fuzz_run_report,fuzz_exit_status}

# Replays: the header lines as written and a window of sample lines (the writer puts one sample
# per line), so numbers keep their exact text.
python3 - "$corpus/fuzz_replay" replays/*.json <<'PY'
import os, sys
out_dir, files = sys.argv[1], sys.argv[2:]
def cut(lines, first, count):
    start = next(i for i, l in enumerate(lines) if l.strip().startswith('"samples"')) + 1
    rows = [l.rstrip().rstrip(',') for l in lines[start + first:start + first + count]]
    return ''.join(lines[:start]) + ',\n'.join(rows) + '\n  ]\n}\n'
for path in files:
    lines = open(path).read().splitlines(keepends=True)
    name = os.path.splitext(os.path.basename(path))[0]
    open(os.path.join(out_dir, name + '-8.json'), 'w').write(cut(lines, 0, 8))
    if name == 'stress-flight':
        start = next(i for i, l in enumerate(lines) if l.strip().startswith('"samples"')) + 1
        cut_row = next(i for i, l in enumerate(lines[start:]) if l.rstrip().rstrip(',').endswith('true]'))
        open(os.path.join(out_dir, name + '-cut.json'), 'w').write(cut(lines, cut_row - 4, 8))
PY

# Settings.
v="$corpus/fuzz_volume_settings"
echo '{}' >"$v/empty.json"
echo '{"store": {"blendTime_s": 1}, "scheduler": {"corridorCells": 4}}' >"$v/tuned.json"
b="$corpus/fuzz_baseline_settings"
echo '{}' >"$b/empty.json"
echo '{"gridSpacing_m": 24, "gridSize": 16}' >"$b/grid24.json"

# Sweeps.
s="$corpus/fuzz_sweep"
cat >"$s/readme.json" <<'JSON'
{"points": [{"label": "b1", "methods": ["volume"], "volume": {"store": {"blendTime_s": 1}},
  "baseline": {}, "facesPerFrame": 2}]}
JSON
cat >"$s/two-points.json" <<'JSON'
{"points": [{"label": "g24", "methods": ["grid"], "baseline": {"gridSpacing_m": 24}},
            {"label": "fine3", "methods": ["volume", "nearest"],
             "volume": {"scheduler": {"maxLevel": 4}}}]}
JSON

# Exit statuses as a local bench (seconds with decimals) and an emitted line (whole seconds)
# write them, and without the seconds.
e="$corpus/fuzz_exit_status"
printf '0 12.345\n' >"$e/ok.txt"
printf '2 3\n' >"$e/failed.txt"
printf '137 41\n' >"$e/killed.txt"
printf '0\n' >"$e/no-seconds.txt"

# Files the program writes: settings files of every key, a short run, measured, saving its
# anchors; a probe.
if [[ ! -x "$ambience" ]]; then
  echo "make-corpus: no $ambience; every-key settings, oracle, anchor store and cube-map seeds" \
    "left as they are" >&2
  exit 0
fi
# Every key the settings schema knows (lighting/SettingsSchema.h), at its default and at the
# costly end of its range: a key added to the schema is in the seeds.
for f in volume baseline; do
  "$ambience" settings --defaults "$f" >"$corpus/fuzz_${f}_settings/every-key.json"
  "$ambience" settings --worst-case "$f" >"$corpus/fuzz_${f}_settings/worst-case.json"
done
"$ambience" run --replay replays/highway-drive.json --max-frames 30 --no-frames --no-video \
  --measure-every 10 --oracle "$tmp/oracle.json" --out "$tmp/run" >/dev/null
"$ambience" run --replay replays/highway-drive.json --max-frames 30 --no-frames --no-video \
  --measure-every 10 --oracle-kind reference --reference "$tmp/reference.json" \
  --reference-every 1 --screen-witnesses 2 --out "$tmp/runr" >/dev/null
# A store with one anchor is over 300 kB (a leaf node of every payload grid); the store after
# one frame has no anchor yet but every grid, the metadata and the checksum, in 19 kB.
"$ambience" run --replay replays/highway-drive.json --max-frames 1 --no-frames --no-video \
  --save-anchors "$tmp/anchors.vdb" --out "$tmp/run1" >/dev/null
# An emitted bench (nothing run): its bench.json with the folder and replay paths made neutral.
"$ambience" bench --replays highway-drive,low-flight --methods volume,constant --max-frames 30 \
  --sweep "$s/two-points.json" --emit "$tmp/emit" >/dev/null
python3 - "$tmp/emit/bench.json" "$corpus/fuzz_bench_manifest/two-replays.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
d['command'] = 'ambience bench --replays highway-drive,low-flight --methods volume,constant'
for r in d['replays']:
    r['path'] = '/data/ambience/replays/' + r['name'] + '.json'
json.dump(d, open(sys.argv[2], 'w'), indent=1)
PY
# The report with every list cut to its first two items (it stays under the 8 kB the JSON
# targets' inputs may grow to), on one line.
python3 - "$tmp/run/report.json" "$corpus/fuzz_run_report/highway-30.json" <<'PY'
import json, sys
def cut(v):
    if isinstance(v, list):
        return [cut(x) for x in v[:2]]
    if isinstance(v, dict):
        return {k: cut(x) for k, x in v.items()}
    return v
d = cut(json.load(open(sys.argv[1])))
open(sys.argv[2], 'w').write(json.dumps(d, separators=(',', ':')) + '\n')
PY
# The fuzz target asks for the signature "fuzz"; keep the first 6 entries.
python3 - "$tmp/oracle.json" "$corpus/fuzz_oracle/highway-30.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
d['signature'] = 'fuzz'
d['entries'] = d['entries'][:6]
json.dump(d, open(sys.argv[2], 'w'))
PY
python3 - "$tmp/reference.json" "$corpus/fuzz_reference/highway-30.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
d['signature'] = 'fuzz'
d['entries'] = d['entries'][:2]
d['screen'] = d['screen'][:2]
json.dump(d, open(sys.argv[2], 'w'))
PY
# The first byte of an anchor-store input selects its checksum handling (fuzz_anchor_store.cpp).
printf '\x00' | cat - "$tmp/anchors.vdb" >"$corpus/fuzz_anchor_store/highway-1.vdb.bin"
for ext in png exr hdr; do
  "$ambience" probe --at 0,0 --size 4 --out "$tmp/probe.$ext" >/dev/null
done
printf '\x00' | cat - "$tmp/probe.png" >"$corpus/fuzz_cubemap/probe4.png.bin"
printf '\x01' | cat - "$tmp/probe.exr" >"$corpus/fuzz_cubemap/probe4.exr.bin"
printf '\x02' | cat - "$tmp/probe.hdr" >"$corpus/fuzz_cubemap/probe4.hdr.bin"

find "$corpus" -type f -size +64k -printf 'make-corpus: %p is over 64 kB\n'
du -sh "$corpus"
