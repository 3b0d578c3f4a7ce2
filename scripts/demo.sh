#!/usr/bin/env bash
# The main job on the embedded defaults. Until the runtime lands `embody demo`, this runs the
# environment check so `make demo` is honest about what exists.
set -euo pipefail
build=${1:-build}
bin="$build/app/embody"
mkdir -p out/demo
if "$bin" --help 2>/dev/null | grep -qE '^  demo '; then
  "$bin" demo --out out/demo
else
  echo "embody demo is not built yet; running 'embody doctor' instead (see README)."
  "$bin" doctor | tee out/demo/doctor.txt
fi
echo "results: $(pwd)/out/demo"
