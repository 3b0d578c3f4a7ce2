#pragma once
// The default avatar: a neutral mannequin generated in code (no asset file), used by `make demo`
// and whenever no avatar is given.
//
// - Skeleton: H-Anim (ISO/IEC 19774) joint names and the LOA-3 default joint centres of
//   /work/shared/reference/spine.md §4: humanoid_root, sacroiliac, l/r_hip, _knee, _ankle,
//   _metatarsal, all 24 vertebrae vl5 ... vl1, vt12 ... vt1, vc7 ... vc1, skullbase,
//   l/r_sternoclavicular, _shoulder, _elbow, _wrist. Rest rotations are identity, so a joint's
//   local frame is the model frame at rest.
// - Convention: +Y up, facing +Z (glTF), so the avatar's left side is +X; metres; height 1.75 m
//   (soles at y = 0). Standing naturally: arms hang about 10 degrees out from the body, palms in.
// - Mesh: swept elliptical tubes and ellipsoids, about 20k triangles, one neutral grey material.
//   Skin weights blend linearly between neighbouring bones over a few centimetres at every joint,
//   and the torso is weighted to the vertebra bones by height, so spine bending shows as a smooth
//   curve rather than a kink.
#include "avatar/avatar_asset.h"

namespace embody::avatar {

struct DefaultAvatarOptions {
  // Add finger bones (H-Anim 1.1 names l_thumb1..3, l_index1..3, l_middle1..3, l_ring1..3,
  // l_pinky1..3 and r_..., the 30 VRM humanoid finger bones) with a palm and five skinned
  // fingers in place of the mitten hand. The joints are appended after the standard ones, so
  // every other joint keeps its index; the fingers hang straight along the forearm at rest.
  bool fingers = false;
};

// Builds the mannequin, mapped (names: H-Anim) and with its first-person draw list.
AvatarAsset buildDefaultAvatar();
AvatarAsset buildDefaultAvatar(const DefaultAvatarOptions& options);

}  // namespace embody::avatar
