#!/usr/bin/env bash
# Regenerates the golden images in tests/golden/ ON PURPOSE (after an intended rendering change):
# runs the golden tests with EMBODY_UPDATE_GOLDENS=1 on lavapipe, which rewrites each
# <name>.png and records the driver string in <name>.driver.txt. Review the new images (and
# `git diff --stat tests/golden`) before committing them.
set -euo pipefail
build=${1:-build}
cmake --build "$build" --target embody_tests_engine -j "${JOBS:-2}"
EMBODY_UPDATE_GOLDENS=1 "$build/tests/embody_tests_engine" '[golden]'
echo "goldens written to $(pwd)/tests/golden; review them before committing"
