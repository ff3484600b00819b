#!/usr/bin/env bash
# Runs every libFuzzer target for N seconds each (default 60), one after another, starting from
# its seed corpus, and prints per target: executions, new corpus entries, crashes.
#
#   tests/fuzz/run-all.sh [seconds] [build dir, default build-fuzz] [targets, comma-separated]
#
# New inputs go to out/fuzz/corpus/<target>/ (the committed seeds in tests/fuzz/corpus/ are only
# read); crashing inputs to out/fuzz/crashes/<target>/, logs to out/fuzz/<target>.log. A crash
# stops that target (libFuzzer's rule) and the script goes on to the next; it exits 1 if any
# target crashed. Findings: uncaught exceptions other than amb::InputError, sanitizer reports,
# aborts, an input taking more than 10 s, more than 2 GB of memory.
set -uo pipefail
cd "$(dirname "$0")/../.."

seconds="${1:-60}"
build="${2:-build-fuzz}"
targets=(fuzz_replay fuzz_sweep fuzz_volume_settings fuzz_baseline_settings fuzz_oracle fuzz_reference
         fuzz_anchor_store fuzz_cubemap fuzz_bench_manifest fuzz_run_report fuzz_exit_status)
json_targets=" fuzz_replay fuzz_sweep fuzz_volume_settings fuzz_baseline_settings fuzz_oracle"
json_targets+=" fuzz_reference fuzz_bench_manifest fuzz_run_report "
if [[ -n "${3:-}" ]]; then
  IFS=, read -r -a targets <<<"$3"
fi

if [[ ! "$seconds" =~ ^[0-9]+$ ]] || ((seconds < 1)); then
  echo "run-all: seconds must be a positive integer, got '$seconds'" >&2
  exit 2
fi
for t in "${targets[@]}"; do
  if [[ ! -x "$build/bin/$t" ]]; then
    echo "run-all: $build/bin/$t is missing; build the fuzzers first (README: Fuzzing and sanitizers)" >&2
    exit 2
  fi
done

# Leaks are findings too, but not the ones of the system libraries (tests/lsan.supp).
export LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"

work=out/fuzz
failed=0
printf '%-24s %8s %14s %10s %8s\n' target seconds executions new_units crashes
for t in "${targets[@]}"; do
  mkdir -p "$work/corpus/$t" "$work/crashes/$t"
  before=$(find "$work/corpus/$t" -type f | wc -l)
  crashes_before=$(find "$work/crashes/$t" -type f | wc -l)
  dict=()
  # JSON targets: the dictionary, and inputs up to 8 kB (libFuzzer's default limit is the
  # largest seed, a few hundred bytes for the settings).
  [[ "$json_targets" == *" $t "* ]] && dict=(-dict=tests/fuzz/json.dict -max_len=8192)
  "$build/bin/$t" "${dict[@]}" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$work/crashes/$t/" \
    "$work/corpus/$t" "tests/fuzz/corpus/$t" >"$work/$t.log" 2>&1
  rc=$?
  execs=$(awk '/stat::number_of_executed_units/ {print $2}' "$work/$t.log" | tail -n 1)
  after=$(find "$work/corpus/$t" -type f | wc -l)
  crashes=$(($(find "$work/crashes/$t" -type f | wc -l) - crashes_before))
  printf '%-24s %8s %14s %10s %8s\n' "$t" "$seconds" "${execs:-?}" "$((after - before))" "$crashes"
  if ((rc != 0)); then
    failed=1
    echo "  $t stopped (exit $rc): see $work/$t.log and $work/crashes/$t/" >&2
  fi
done
exit "$failed"
