#!/usr/bin/env bash
# make-figures.sh — every picture the docs show and docs/RESULTS.md, made again from the current
# build in one command, and the README's results table taken from that RESULTS.md.
#
#   scripts/make-figures.sh [--short] [--out DIR | --docs] [--work DIR] [--bin AMBIENCE] [--no-soak]
#                           [--no-tune] [--resume]
#
#   (no option)  the full setting: the frames at 640x360 and full reference resolution, the
#                viewer's panel after 150 frames, the one-hour soak, a 40-trial `ambience tune`
#                study (docs/TUNING.md "Tuning with Optuna"; about half an hour on an idle
#                2-core machine), and a reference bench of every method on the first 900
#                frames of three replays; writes
#                docs/*.png|jpg, docs/RESULTS.md and the table between the results markers
#                of README.md
#   --short      the same steps in a few frames at a quarter of the pixels, a 2-trial tune of
#                30-frame runs, and a 60-frame bench on the highway alone (for CI: checks that
#                every step runs, in a few minutes); no
#                soak; writes into out/figures-short/ unless --out or --docs says otherwise
#   --out DIR    write the pictures, RESULTS.md and a copy of README.md with its table rewritten
#                into DIR instead (docs/ and README.md are left alone)
#   --docs       write into docs/ and README.md (the default of the full setting)
#   --work DIR   where the runs go (default out/figures or out/figures-short; DIR/work with --out)
#   --bin FILE   the ambience executable (default build/bin/ambience)
#   --no-soak    leave docs/soak-memory.png as it is (the soak alone takes about 10 minutes)
#   --no-tune    leave docs/tune-front.png as it is (the tune study alone takes about half an
#                hour); RESULTS.md says which pictures an earlier run made
#   --resume     keep the compare runs, the tune study and the bench already in the work folder
#                that ran with the same options and are newer than the executable (a run stopped
#                half way goes on where it was; RESULTS.md says what was kept)
#
# Needs what setup.sh installs: oiiotool (openimageio-tools) for the mosaics, xvfb-run for the
# viewer, python3 for RESULTS.md. Runs kept in the work folder are reused where ambience reuses
# them (the bench's oracle caches), so a second full run is faster.
# Exit code: 0 done, 1 a step failed (its log's tail on stderr), 2 bad arguments, 77 no
# offscreen GL platform.
set -euo pipefail
# The whole script is one block, read before it runs: editing the file meanwhile is safe.
{
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
short=0 out="" docs=0 work="" bin="$root/build/bin/ambience" soak=1 tune=1 resume=0

usage() {
  echo "make-figures.sh: $1 (usage: make-figures.sh [--short] [--out DIR | --docs]" \
    "[--work DIR] [--bin FILE] [--no-soak] [--no-tune] [--resume])" >&2
  exit 2
}
while [[ $# -gt 0 ]]; do
  case "$1" in
    --short) short=1; shift ;;
    --out) [[ $# -ge 2 ]] || usage "--out needs a folder"; out="$2"; shift 2 ;;
    --work) [[ $# -ge 2 ]] || usage "--work needs a folder"; work="$2"; shift 2 ;;
    --bin) [[ $# -ge 2 ]] || usage "--bin needs a file"; bin="$2"; shift 2 ;;
    --docs) docs=1; shift ;;
    --no-soak) soak=0; shift ;;
    --no-tune) tune=0; shift ;;
    --resume) resume=1; shift ;;
    -h|--help) sed -n '2,35p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) usage "unknown argument '$1'" ;;
  esac
done
[[ -n $out && $docs == 1 ]] && usage "--out and --docs exclude each other"
if ((short && !docs)) && [[ -z $out ]]; then
  out="$root/out/figures-short/docs" work="${work:-$root/out/figures-short/work}"
fi
[[ -x "$bin" ]] || usage "the ambience executable '$bin' is missing (build it, or pass --bin)"
bin="$(realpath "$bin")"
for tool in oiiotool xvfb-run; do
  command -v "$tool" >/dev/null || usage "$tool is missing (setup.sh installs it)"
done
python=python3
[[ -x /usr/bin/python3 ]] && python=/usr/bin/python3

if [[ -n $out ]]; then
  mkdir -p "$out"
  dest="$(realpath "$out")"
  readme_out="$dest/README.md"
  work="${work:-$dest/work}"
else
  dest="$root/docs"
  readme_out="$root/README.md"
  work="${work:-$root/out/figures$( ((short)) && echo -short || true)}"
fi
mkdir -p "$work"
work="$(realpath "$work")"
setting=full
if ((short)); then soak=0 setting=short; fi

# Commands are recorded as a reader would type them from the repository's root: the
# executable as build/bin/ambience, the work folder relative to the root when inside it.
shown_work="$work"
[[ $work == "$root"/* ]] && shown_work="${work#"$root"/}"
show() {
  local words=() w
  for w in "$@"; do
    w="${w//"$bin"/build/bin/ambience}"
    w="${w//"$work"/$shown_work}"
    w="${w//"$root"\//}"
    words+=("$w")
  done
  echo "${words[*]}"
}

start_all=$SECONDS
step() { echo "make-figures: $*"; }
fail() { echo "make-figures: $*" >&2; exit 1; }
# run LOG CMD...: the command's output to LOG; its tail on failure.
run() {
  local log="$1"; shift
  if ! "$@" >"$log" 2>&1; then
    tail -n 15 "$log" >&2
    fail "failed: $(show "$@") (log: $log)"
  fi
}

# Skipped (exit 77), not failed, only where there is no offscreen GL platform.
if ! why=$("$bin" probe --at 0,0 --size 4 --out "$work/platform-check.exr" 2>&1 >/dev/null); then
  if grep -qiE "platform|GL entry points" <<<"$why"; then
    echo "make-figures: skipped, no offscreen GL platform: $why" >&2
    exit 77
  fi
  fail "ambience probe failed: $why"
fi

# --- the setting -----------------------------------------------------------------------------
# The reference is lit by its own bounce field (lighting/BounceField.h): the full setting with
# the commands' own lattices (bench 256 m within 500 m, compare 128 m within 600 m), the short
# one with a lattice of a point or two, small faces.
if ((short)); then
  size=320x180 grid=96 refsize=32 drive_frame=30 static_frame=30 view_frames=20
  light_args=(--bounce-spacing 256 --bounce-reach 128 --bounce-face 8)
  bench_args=(--replays highway-drive --max-frames 60 --reference-every 3 --screen-witnesses 2)
  tune_args=(--params scheduler.horizon_s=1:6,store.reachCells --replays highway-drive
             --eval-replays hairpin-flight-held-out --oracle self --max-frames 30 --trials 2)
else
  size=640x360 grid=16 refsize=64 drive_frame=600 static_frame=300 view_frames=150
  light_args=()
  # Screen witnesses at the bench's default (32 a reference frame).
  bench_args=(--replays highway-drive,mountain-drive,low-flight --max-frames 900)
  # The study of docs/TUNING.md "Tuning with Optuna": the keys the old descent stepped over, in
  # the region its three rounds reach (clipped to the schema's ranges).
  tune_args=(--params "scheduler.horizon_s=0.375:10,scheduler.corridorCells=0.5:32,store.blendTime_s=0.125:8,scheduler.finestRingCells=0.125:8,scheduler.coarseRingCells=0.25:8,store.reachCells=1:4,nearField.captureRadius_m=5:40,nearField.radius_m=8:60"
             --max-frames 450 --trials 40 --jobs 2)
fi
tune_args+=(--seed 1 --out "$work/tune")
bench_args+=(--oracle reference "${light_args[@]}" --out "$work/bench")

kept=()
frames_tsv="$work/frames.tsv"
printf 'picture\tpanel\tcompare.json\tcommand\n' >"$frames_tsv"

# Settings files for the switches the pictures compare (read by --config as any settings file).
echo '{"nearField": {"enabled": false}}' >"$work/near-off.json"
echo '{"nearField": {"vertexDetail": false}}' >"$work/no-vertex-detail.json"

# Two static views made with the project's own path code: a valley in the western hills (the
# spot with the most horizon above the broad slope, found by a one-off search) and the shipped
# ravine-dusk view made at 15 h.
step "replays (gully, ravine by day)"
make_static() {
  local name="$1"; shift
  local cmd=("$bin" replay make --mode static "$@" --duration 12 --name "$name"
             --out "$work/$name.json")
  run "$work/$name-make.log" "${cmd[@]}"
  printf '%s\t%s\t%s\t%s\n' "$name.json" "the static view the $name frames play" "-" \
    "$(show "${cmd[@]}")" >>"$frames_tsv"
}
make_static gully --at -4284,150 --height 50 --heading 30 --pitch -25 --time 15
make_static ravine-day --at -4866,4537 --height 28 --heading 180 --pitch -50 --time 15

# compare NAME PICTURE PANEL [ambience compare options]: one compare run into work/compare/NAME.
compare() {
  local name="$1" picture="$2" panel="$3"; shift 3
  local dir="$work/compare/$name"
  mkdir -p "$dir"
  local cmd=("$bin" compare "$@" --size "$size" --grid "$grid" --reference-size "$refsize"
             "${light_args[@]}" --out "$dir")
  local t=$SECONDS
  # The run's own command line beside it, so that --resume keeps only a run of these options.
  if ((resume)) && [[ $dir/compare.json -nt $bin && -f $dir.cmd ]] &&
     [[ $(cat "$dir.cmd") == "${cmd[*]}" ]]; then
    step "compare $name: kept (--resume)"
    kept+=("$name")
  else
    rm -f "$dir/compare.json"
    run "$dir.log" "${cmd[@]}"
    echo "${cmd[*]}" >"$dir.cmd"
    step "compare $name: $((SECONDS - t)) s"
  fi
  printf '%s\t%s\t%s\t%s\n' "$picture" "$panel" "$dir/compare.json" "$(show "${cmd[@]}")" \
    >>"$frames_tsv"
}
c="$work/compare"

step "frames ($setting setting: $size, a reference sample every $grid pixels)"
compare highway compare-highway.png "method, reference, error" --frame "$drive_frame"
compare highway-near-off near-field-ambient.png "near field off" \
  --frame "$drive_frame" --config "$work/near-off.json"
compare gully gully-ambient.jpg "near field on; reference" \
  --replay "$work/gully.json" --frame "$static_frame"
compare gully-near-off gully-ambient.jpg "near field off" \
  --replay "$work/gully.json" --frame "$static_frame" --config "$work/near-off.json"
compare ravine-dusk ravine-dusk-ambient.jpg "default; reference" \
  --replay "$root/replays/ravine-dusk.json" --frame "$static_frame"
compare ravine-dusk-near-off ravine-dusk-ambient.jpg "near field off" \
  --replay "$root/replays/ravine-dusk.json" --frame "$static_frame" --config "$work/near-off.json"
compare ravine-dusk-no-vd ravine-dusk-ambient.jpg "no vertex detail" \
  --replay "$root/replays/ravine-dusk.json" --frame "$static_frame" \
  --config "$work/no-vertex-detail.json"
compare ravine-day ravine-day-ambient.jpg "default; reference" \
  --replay "$work/ravine-day.json" --frame "$static_frame"
compare ravine-day-no-vd ravine-day-ambient.jpg "no vertex detail" \
  --replay "$work/ravine-day.json" --frame "$static_frame" --config "$work/no-vertex-detail.json"

# The pictures: mosaics of the ambient term alone (ambient.png), the reference's
# (ambient-reference.png) and the error per pixel (error.png), 0 to 0.5.
step "mosaics"
mosaic() {  # LAYOUT OUT.{png,jpg} IN...
  local layout="$1" target="$2"; shift 2
  local compression=(--compression zip:9)
  [[ $target == *.jpg ]] && compression=(--compression jpeg:85)
  run "$work/mosaic.log" oiiotool "$@" --mosaic "$layout" "${compression[@]}" -o "$target"
}
run "$work/mosaic.log" oiiotool "$c/highway/compare.png" --compression zip:9 \
  -o "$dest/compare-highway.png"
mosaic 1x3 "$dest/near-field-ambient.png" "$c/highway-near-off/ambient.png" \
  "$c/highway/ambient.png" "$c/highway/ambient-reference.png"
mosaic 1x2 "$dest/near-field-error.png" "$c/highway-near-off/error.png" "$c/highway/error.png"
mosaic 1x3 "$dest/gully-ambient.jpg" "$c/gully-near-off/ambient.png" "$c/gully/ambient.png" \
  "$c/gully/ambient-reference.png"
mosaic 2x2 "$dest/ravine-dusk-ambient.jpg" "$c/ravine-dusk-near-off/ambient.png" \
  "$c/ravine-dusk-no-vd/ambient.png" "$c/ravine-dusk/ambient.png" \
  "$c/ravine-dusk/ambient-reference.png"
mosaic 3x1 "$dest/ravine-day-ambient.jpg" "$c/ravine-day-no-vd/ambient.png" \
  "$c/ravine-day/ambient.png" "$c/ravine-day/ambient-reference.png"

# The viewer with its tuning panel, in a window under Xvfb (software GL, so the draw's time
# in the panel is llvmpipe's).
step "viewer ($view_frames frames under xvfb-run)"
t=$SECONDS
view_cmd=("$bin" view --replay "$root/replays/highway-drive.json" --frames "$view_frames"
          --debug-overlay --window-shot "$dest/tuning-panel.png")
run "$work/view.log" xvfb-run -a -s "-screen 0 1280x720x24 -noreset" "${view_cmd[@]}"
printf '%s\t%s\t%s\t%s\n' tuning-panel.png "the viewer" "-" \
  "xvfb-run -a -s '-screen 0 1280x720x24' $(show "${view_cmd[@]}")" >>"$frames_tsv"
step "viewer: $((SECONDS - t)) s"

# The one-hour soak and its memory plot (docs/SOAK.md).
if ((soak)); then
  step "soak (60 simulated minutes, about 10 minutes)"
  t=$SECONDS
  soak_cmd=("$root/tests/soak.sh" 60 --bin "$bin" --out "$work/soak" --plot "$dest/soak-memory.png")
  run "$work/soak.log" "${soak_cmd[@]}"
  printf '%s\t%s\t%s\t%s\n' soak-memory.png "the soak" "-" "$(show "${soak_cmd[@]}")" \
    >>"$frames_tsv"
  step "soak: $((SECONDS - t)) s"
fi

# resumed NAME RESULT CMD...: true (and the step said kept) when --resume keeps what CMD made last
# time in the work folder: RESULT newer than the executable, from the same command line.
resumed() {
  local name="$1" result="$2"; shift 2
  if ((resume)) && [[ $result -nt $bin && -f $work/$name.cmd ]] &&
     [[ $(cat "$work/$name.cmd") == "$*" ]]; then
    step "$name: kept (--resume)"
    kept+=("$name")
    return 0
  fi
  return 1
}
# fresh NAME CMD...: CMD run into work/NAME.log, its command line kept for a later --resume.
fresh() {
  local name="$1" t=$SECONDS; shift
  run "$work/$name.log" "$@"
  echo "$*" >"$work/$name.cmd"
  step "$name: $((SECONDS - t)) s"
}

# The tune study's front (docs/TUNING.md "Tuning with Optuna"). A study folder is resumed by
# the same command, so a fresh one is started unless --resume keeps it.
if ((tune)); then
  step "tune: $(show "$bin" tune "${tune_args[@]}")"
  tune_cmd=("$bin" tune "${tune_args[@]}")
  if ! resumed tune "$work/tune/summary.md" "${tune_cmd[@]}"; then
    rm -rf "$work/tune"
    fresh tune "${tune_cmd[@]}"
  fi
  cp "$work/tune/front.png" "$dest/tune-front.png"
  printf '%s\t%s\t%s\t%s\n' tune-front.png "the tune study's front" "-" "$(show "${tune_cmd[@]}")" \
    >>"$frames_tsv"
else
  step "tune: not run (--no-tune): $dest/tune-front.png left as it is"
fi

# The bench behind docs/RESULTS.md and the README's table.
step "bench: $(show "$bin" bench "${bench_args[@]}")"
t=$SECONDS
bench_cmd=("$bin" bench "${bench_args[@]}")
timing=()
if ! resumed bench "$work/bench/results.csv" "${bench_cmd[@]}"; then
  rm -f "$work/bench/results.csv"
  fresh bench "${bench_cmd[@]}"
  timing=(--bench-seconds "$((SECONDS - t))")
fi

step "docs: $dest/RESULTS.md, $readme_out"
[[ $readme_out == "$root/README.md" ]] || cp "$root/README.md" "$readme_out"
commit="$(git -C "$root" rev-parse --short=12 HEAD 2>/dev/null || echo unknown)"
git -C "$root" diff --quiet HEAD -- . ':!docs' ':!README.md' 2>/dev/null || commit="$commit (with local changes)"
soak_log=()
((soak)) && soak_log=(--soak-log "$work/soak.log")
not_run=()
((soak)) || not_run+=(soak-memory.png)
((tune)) || not_run+=(tune-front.png)
"$python" "$here/results-md.py" --bench "$work/bench" --frames "$frames_tsv" "${soak_log[@]}" \
  --command "$(show "${bench_cmd[@]}")" --setting "$setting" --commit "$commit" \
  "${timing[@]}" --kept "${kept[*]}" --not-run "${not_run[*]}" --total-seconds "$((SECONDS - start_all))" \
  --out "$dest/RESULTS.md" --readme "$readme_out"
step "done in $((SECONDS - start_all)) s ($setting setting)"
exit 0
}
