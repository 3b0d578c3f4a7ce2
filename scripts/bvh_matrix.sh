#!/usr/bin/env bash
# BVH import end to end (docs/tracking.md, "Every clip on three avatars"): each clip drives, with all
# its trackers and a fixed iteration count, (1) the default avatar, (2) a Mixamo-rigged glTF avatar
# built from the project's own Mixamo fixture (tests/tracking/fixtures/mixamo.bvh exported as a
# skinned .glb, so no third-party file is needed) and (3) the clip's own skeleton. Prints one
# markdown row per clip and avatar: frames, head and hand error p95 (the solved body against the
# trackers), how far the avatar's pelvis is turned off the pelvis tracker's orientation (p95,
# degrees: stats.json's trackers.hips.turn_error_p95_deg) and the frames in which the solved body
# stands the right way up (eyes above pelvis above ankles: stats.json's body.upright_frames).
# Contact sheets are in OUT/CLIP/AVATAR/.
#
# BVH_MATRIX_THREE_POINT=1 drives the head and hands only (--three-point: the pelvis and the feet
# inferred, the feet stepping); BVH_MATRIX_AVATAR=FILE adds one more avatar (e.g. a small one:
# session 23 found a change that only a short avatar's hands showed, docs/eval.md).
#
#   scripts/bvh_matrix.sh [BUILD] [OUT] CLIP.bvh...      (default: build out/bvh_matrix ../shared clips)
set -euo pipefail
build=${1:-build}
out=${2:-out/bvh_matrix}
shift $(( $# >= 2 ? 2 : $# )) || true
clips=("$@")
if [[ ${#clips[@]} -eq 0 ]]; then
  shopt -s nullglob
  clips=(../shared/assets/cmu_12_01_walk.bvh ../shared/mocap/*.bvh)
fi
embody=${EMBODY:-$build/app/embody}  # EMBODY=PATH: a copy, so rebuilding does not change a long run
fps=${BVH_MATRIX_FPS:-60}
iterations=${BVH_MATRIX_ITERATIONS:-10}
mode=()
[[ ${BVH_MATRIX_THREE_POINT:-0} == 1 ]] && mode=(--three-point)
extra=${BVH_MATRIX_AVATAR:-}
mkdir -p "$out"
mixamo="$out/mixamo_avatar.glb"
"$embody" render --avatar tests/tracking/fixtures/mixamo.bvh --motion tests/tracking/fixtures/mixamo.bvh \
  --ik-iterations 1 --frames 1 --size 32x32 --export "$mixamo" --out "$out/mixamo_export" >/dev/null

# The value of a numeric field of stats.json ("name": value), in millimetres.
mm() { grep -o "\"$1\": *[-0-9.e+]*" "$2" | head -1 | awk -F: '{ printf "%.1f", $2 * 1000 }'; }
field() { grep -o "\"$1\": *[-0-9.e+a-z]*" "$2" | head -1 | awk -F': *' '{ print $2 }'; }
# The pelvis tracker's turn error in degrees (stats.json trackers.hips), blank without one.
pelvisTurn() { sed -n '/"hips": {/,/}/p' "$1" | grep -o '"turn_error_p95_deg": *[0-9.e+-]*' | awk -F': *' '{ printf "%.1f", $2 }'; }

echo "| clip | avatar | frames | head p95 mm | hand p95 mm | pelvis turn p95 deg | upright frames | steps | re-seeds |"
echo "|---|---|---|---|---|---|---|---|---|"
for clip in "${clips[@]}"; do
  name=$(basename "$clip" .bvh)
  avatars=(default "$mixamo" "$clip")
  [[ -n $extra ]] && avatars+=("$extra")
  for avatar in "${avatars[@]}"; do
    case $avatar in default) label=default ;; "$mixamo") label=mixamo ;; "$clip") label=own ;; *) label=$(basename "${avatar%.*}") ;; esac
    dir="$out/$name/$label"
    mkdir -p "$out/$name"
    if ! "$embody" render --avatar "$avatar" --motion "$clip" --fps "$fps" --ik-iterations "$iterations" \
        "${mode[@]}" --size 160x160 --out "$dir" >"$dir.log" 2>&1; then
      echo "| $name | $label | $(grep -m1 error: "$dir.log" || tail -1 "$dir.log") | | | | | | |"
      continue
    fi
    s="$dir/stats.json"
    echo "| $name | $label | $(field frames "$s") | $(mm head_error_p95_m "$s") | $(mm hand_error_p95_m "$s") |" \
         "$(pelvisTurn "$s") | $(field upright_frames "$s") | $(field steps "$s") | $(field recoveries "$s") |"
  done
done
