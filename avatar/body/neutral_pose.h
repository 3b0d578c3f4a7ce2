#pragma once
// The canonical neutral pose of a humanoid skeleton: the pose the IK body model's limb joint
// limits are ranges around (body_model.h), whatever pose the avatar rests in.
//
// Rest poses differ (an A-pose mannequin, a T-pose rig, a motion clip whose rest is its first
// frame); a person's ranges of motion do not. Ranges written as boxes around the rest pose suit
// one kind of rest only, and a box moved in exponential-map coordinates is not the same range
// far from zero. So the body model is built AT this pose (q = 0 is neutral, the ranges are the
// anatomical ones around it) and a solve starts from the configuration that reproduces the rest.
//
// The neutral turns limb bones only, each about its own pivot (bone lengths, the trunk, the
// clavicles and every twist about a bone's own axis stay as at rest):
//   upper arm  hanging, kNeutralArmAbduction out to its side (the default mannequin's)
//   forearm    in line with the upper arm, turned about the elbow's hinge axis only
//   hand       in line with the forearm (the shortest turn)
//   thigh      straight down
//   shank      in line with the thigh, turned about the knee's hinge axis only
//   foot       its rest orientation in the world (rest poses stand the feet on the floor)
// The hinge axes come from the rest geometry: a limb bent at rest (by more than ~10 degrees)
// bends about that axis; a straight one about upper x forward (elbow: + flexes the forearm
// forward) or upper x -forward (knee: + flexes the shank back), turned with the upper bone.
#include <Eigen/Geometry>
#include <array>
#include <vector>

#include "avatar/skeleton.h"

namespace embody::avatar {

constexpr double kNeutralArmAbduction = 10.0 * 3.14159265358979323846 / 180.0;  // radians

// One limb: skeleton joints of the upper bone, the hinge bone (forearm / shank), the end bone
// (hand / foot) and the joint the end bone points at (a knuckle; -1: none). -1 where unmapped.
struct NeutralLimb {
  int upper = -1, hinge = -1, end = -1, endNext = -1;
  bool arm = false, left = false;
};

// Limbs in the order left arm, right arm, left leg, right leg.
using NeutralLimbs = std::array<NeutralLimb, 4>;

struct NeutralPose {
  std::vector<Eigen::Vector3d> position;     // per skeleton joint: world pivot (model space)
  std::vector<Eigen::Quaterniond> rotation;  // per skeleton joint: world rotation (columns normalised)
  // Per skeleton joint: the world rotation taking the joint from neutral to rest (identity for
  // every joint the neutral does not move).
  std::vector<Eigen::Quaterniond> restFromNeutral;
  std::array<Eigen::Vector3d, 4> hingeAxis;  // per limb: unit world hinge axis at neutral (zero: no hinge)
};

// `up` and `forward` are the avatar's (HumanoidMap). Deterministic; allocation per call.
NeutralPose computeNeutralPose(const Skeleton& skeleton, const NeutralLimbs& limbs, const Eigen::Vector3d& up,
                               const Eigen::Vector3d& forward);

}  // namespace embody::avatar
