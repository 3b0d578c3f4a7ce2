#!/usr/bin/env bash
# Runs every benchmark executable, writing Google Benchmark JSON to out/bench/<area>.json.
set -euo pipefail
build=${1:-build}
mkdir -p out/bench
shopt -s nullglob
for exe in "$build"/bench/embody_bench_*; do
  [[ -x $exe ]] || continue
  area=${exe##*/embody_bench_}
  echo "== $area"
  "$exe" --benchmark_out="out/bench/$area.json" --benchmark_out_format=json ${BENCH_ARGS:-}
done
echo "results: $(pwd)/out/bench"
