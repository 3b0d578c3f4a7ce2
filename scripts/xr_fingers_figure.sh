#!/bin/sh
# docs/figures/xr_fingers_{relaxed,fist}.png: the mannequin with fingers in `embody xr` against
# the headless runtime, left eye, hands held in front of the face with the trigger released (the
# runtime's relaxed hand, 12 degrees per finger joint) and squeezed (its fist, 72 degrees).
# Usage: scripts/xr_fingers_figure.sh [BUILD_DIR]   (default: build)
set -eu
build=${1:-build}
out=$(mktemp -d)
"$build/app/embody" avatar export-default --fingers "$out/fingers.glb" >/dev/null
for phase in relaxed:0 fist:1; do
  name=${phase%%:*}
  trigger=${phase#*:}
  # Head 1.6 m up looking 30 degrees down; grips 20 cm ahead, turned 70 degrees about their
  # forward axis and 30 degrees inwards (quaternions x, y, z, w).
  head='{"p":[0,1.6,0],"q":[-0.258819,0,0,0.965926]}'
  left='{"p":[-0.06,1.47,-0.2],"q":[0.148453,-0.212012,-0.554032,0.791240],"trigger":'$trigger'}'
  right='{"p":[0.06,1.47,-0.2],"q":[0.148453,0.212012,0.554032,0.791240],"trigger":'$trigger'}'
  printf '{"t":0,"head":%s,"left":%s,"right":%s}\n{"t":100,"head":%s,"left":%s,"right":%s}\n' \
    "$head" "$left" "$right" "$head" "$left" "$right" >"$out/$name.jsonl"
  mkdir -p "$out/$name"
  XR_RUNTIME_JSON="$PWD/$build/embody_headless_runtime.json" EMBODY_XR_POSES="$out/$name.jsonl" \
    EMBODY_XR_CAPTURE="$out/$name" EMBODY_XR_VIEW_SIZE=480x480 \
    "$build/app/embody" xr --avatar "$out/fingers.glb" --frames 90 --ik-budget-ms 5 | grep fingers
  cp "$out/$name/left_00089.png" "docs/figures/xr_fingers_$name.png"
done
rm -rf "$out"
echo "wrote docs/figures/xr_fingers_relaxed.png docs/figures/xr_fingers_fist.png"
