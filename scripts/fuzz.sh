#!/usr/bin/env bash
# Runs each libFuzzer target (built by `make fuzz` in BUILD) for SECONDS, starting from the kept
# corpus (fuzz/corpus/<target>, read-only) with a working corpus in out/fuzz/<target>/corpus, and
# writes out/fuzz/summary.md: executions, coverage (edges, features), corpus size, crashes.
# Exit status 1 when any target found a crash (its input is in out/fuzz/<target>/).
#   scripts/fuzz.sh BUILD SECONDS TARGET...
set -uo pipefail
build=$1 seconds=$2
shift 2
here=$(cd "$(dirname "$0")/.." && pwd)
out="$here/out/fuzz"
mkdir -p "$out"
summary="$out/summary.md"
{
  echo "| target | seconds | executions | exec/s | coverage (edges) | features | corpus | crashes |"
  echo "|---|---|---|---|---|---|---|---|"
} >"$summary"
failed=0
for t in "$@"; do
  dir="$out/$t"
  mkdir -p "$dir/corpus"
  log="$dir/fuzz.log"
  echo "fuzz: $t for ${seconds}s"
  # No leak detection: a parser that returns an error may keep a static (e.g. the default avatar
  # fixture); every other ASan and UBSan report stops the run.
  ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    "$build/fuzz/embody_fuzz_$t" -max_total_time="$seconds" -print_final_stats=1 -rss_limit_mb=2048 \
    -timeout=10 -artifact_prefix="$dir/" "$dir/corpus" "$here/fuzz/corpus/$t" >"$log" 2>&1
  rc=$?
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*')
  ft=$(grep -o 'ft: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*')
  files=$(find "$dir/corpus" -type f | wc -l)
  crashes=$(find "$dir" -maxdepth 1 -name 'crash-*' -o -maxdepth 1 -name 'oom-*' -o -maxdepth 1 -name 'timeout-*' | wc -l)
  echo "| $t | $seconds | ${execs:-?} | ${rate:-?} | ${cov:-?} | ${ft:-?} | $files | $crashes |" >>"$summary"
  if [[ $rc -ne 0 || $crashes -ne 0 ]]; then
    failed=1
    echo "fuzz: $t FAILED (exit $rc); see $log and $dir/crash-*" >&2
    grep -m3 -E 'ERROR|SUMMARY|invariant broken|deadly signal' "$log" >&2
  fi
done
cat "$summary"
exit $failed
