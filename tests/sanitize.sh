#!/usr/bin/env bash
# The sanitizer pass: builds build-asan/ (gcc, AMBIENCE_SANITIZE=ON: AddressSanitizer, leak
# checking and UndefinedBehaviorSanitizer), runs every test of world_test and lighting_test (the
# suites without GL), then two short runs of the app: the stress flight (a 250 m/s flight with
# a teleport) and the day time-lapse, headless. Any sanitizer report fails the pass.
#
#   tests/sanitize.sh [build dir, default build-asan]
#
# Environment (set here, override by exporting your own before the call):
#   ASAN_OPTIONS   detect_leaks=1, plus stack-use-after-return and init-order checks
#   LSAN_OPTIONS   suppressions=tests/lsan.supp (Mesa's own leaks only)
#   UBSAN_OPTIONS  halt_on_error=1:print_stacktrace=1 (the first report stops the program)
#   AMBIENCE_BACKEND  GL backend of the app runs (default osmesa: no driver state shared with
#                     the host; egl works too)
set -euo pipefail
cd "$(dirname "$0")/.."
root="$PWD"
dir="${1:-build-asan}"
jobs="$(nproc)"
backend="${AMBIENCE_BACKEND:-osmesa}"

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$root/tests/lsan.supp:print_suppressions=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}"

start=$SECONDS
step() { printf 'sanitize: [%3d s] %s\n' "$((SECONDS - start))" "$*"; }

if [[ ! -f "$dir/CMakeCache.txt" ]]; then
  launcher=()
  if command -v ccache >/dev/null; then
    launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  fi
  step "configuring $dir"
  cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DAMBIENCE_SANITIZE=ON "${launcher[@]}"
fi
if ! grep -q '^AMBIENCE_SANITIZE:BOOL=ON' "$dir/CMakeCache.txt"; then
  echo "sanitize: $dir is not a sanitizer build (AMBIENCE_SANITIZE is not ON)" >&2
  exit 2
fi
step "building world_test, lighting_test, ambience and its shaders"
cmake --build "$dir" -j "$jobs" --target world_test lighting_test ambience shaders

step "world_test"
"$dir/bin/world_test" --gtest_brief=1
step "lighting_test"
"$dir/bin/lighting_test" --gtest_brief=1

out="$(mktemp -d "${TMPDIR:-/tmp}/ambience-sanitize.XXXXXX")"
trap 'rm -rf "$out"' EXIT
step "stress flight, 300 frames ($backend)"
"$dir/bin/ambience" run --replay replays/stress-flight.json --max-frames 300 --no-frames \
  --no-video --backend "$backend" --out "$out/stress" --save-anchors "$out/stress.vdb"
step "day time-lapse, 600 frames ($backend), warm-started from the stress flight's anchors"
"$dir/bin/ambience" run --replay replays/day-timelapse.json --max-frames 600 --no-frames \
  --no-video --backend "$backend" --out "$out/timelapse" --load-anchors "$out/stress.vdb"
step "passed"
