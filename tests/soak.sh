#!/usr/bin/env bash
# Soak: a long simulated run of `ambience run` (a 60 s high-speed flight with two camera cuts,
# played back to back, the time of day at 24 hours per hour, so one simulated hour is a whole
# day), then a plot of resident memory, the C heap in use, anchors and store bytes against
# simulated time and a check that they stay bounded and that the anchor store never held a NaN
# or an infinity.
#
#   tests/soak.sh [MINUTES] [--bin AMBIENCE] [--out DIR] [--stride N] [--plot FILE.png]
#
#   MINUTES   simulated minutes (passes over the 60 s flight; default 60: one simulated hour)
#   --bin     the ambience executable (default build/bin/ambience)
#   --out     output folder (default out/soak-<MINUTES>min)
#   --stride  replay steps per frame (default 2: 30 frames per simulated second, as `run`)
#   --plot    the PNG (default <out>/soak-memory.png)
#
# Exit code: 0 when every check holds, 1 when one fails (the reason on stderr), 2 for bad
# arguments, 77 when no offscreen GL platform is available (ctest counts it as skipped).
set -euo pipefail

here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
minutes=60
bin="$root/build/bin/ambience"
out=""
stride=2
plot=""

usage() {
  echo "soak.sh: $1 (usage: soak.sh [MINUTES] [--bin FILE] [--out DIR] [--stride N]" \
    "[--plot FILE])" >&2
  exit 2
}
while [[ $# -gt 0 ]]; do
  case "$1" in
    --bin) [[ $# -ge 2 ]] || usage "--bin needs a file"; bin="$2"; shift 2 ;;
    --out) [[ $# -ge 2 ]] || usage "--out needs a folder"; out="$2"; shift 2 ;;
    --stride) [[ $# -ge 2 ]] || usage "--stride needs a number"; stride="$2"; shift 2 ;;
    --plot) [[ $# -ge 2 ]] || usage "--plot needs a file"; plot="$2"; shift 2 ;;
    -h|--help) sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) usage "unknown option '$1'" ;;
    *) minutes="$1"; shift ;;
  esac
done
[[ "$minutes" =~ ^[0-9]+$ ]] && (( minutes >= 1 && minutes <= 10000 )) ||
  usage "MINUTES must be a whole number from 1 to 10000, got '$minutes'"
[[ "$stride" =~ ^[0-9]+$ ]] && (( stride >= 1 && stride <= 60 )) ||
  usage "--stride must be a whole number from 1 to 60, got '$stride'"
[[ -x "$bin" ]] || usage "the ambience executable '$bin' is missing (build it, or pass --bin)"
out="${out:-out/soak-${minutes}min}"
plot="${plot:-$out/soak-memory.png}"
mkdir -p "$out"

# The stress flight's path (250 m/s, 120 m up) with two 4 km cuts and the sun moving 24x as
# fast: made by the project's own path code, so the soak needs no extra file.
replay="$out/soak-flight.json"
"$bin" replay make --mode fly --speed 250 --altitude 120 --clearance 40 --turn-radius 1500 \
  --flight-seed 7 --start 0,0 --heading 135 --cuts 2 --cut-jump 4000 --duration 60 \
  --time 6 --time-rate 24 --name soak-flight \
  --description "Soak: stress flight with two cuts, a day per simulated hour" --out "$replay"

# Skipped (not failed) only where there is no offscreen GL platform; any other error fails.
if ! why=$("$bin" probe --at 0,0 --size 4 --out "$out/platform-check.exr" 2>&1 >/dev/null); then
  if grep -qiE "platform|GL entry points" <<<"$why"; then
    echo "soak.sh: skipped: $why" >&2
    exit 77
  fi
  echo "soak.sh: $why" >&2
  exit 1
fi

start=$(date +%s)
"$bin" run --replay "$replay" --loop "$minutes" --stride "$stride" --no-frames --no-video \
  --backend auto --out "$out/run" | tee "$out/run.log"
wall=$(( $(date +%s) - start ))
echo "soak: $minutes simulated minutes in $wall s of wall time (stride $stride)"

# Debian's Python (the one python3-matplotlib installs into), else the first on PATH.
python=python3
[[ -x /usr/bin/python3 ]] && python=/usr/bin/python3
"$python" "$here/soak-plot.py" "$out/run/report.json" --replay "$replay" --plot "$plot" \
  --wall-s "$wall"
