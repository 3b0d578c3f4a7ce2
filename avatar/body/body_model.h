#pragma once
// The IK body model built from a mapped avatar skeleton, and retargeting back onto it.
//
// Every IK joint sits exactly on an avatar bone's pivot, so IK pivots and render pivots coincide and retargeting is exact: an avatar bone takes the world rotation
// its IK joint made relative to rest, applied to the bone's own rest orientation (whatever its
// axes: VRM 1.0 rest rotations, Mixamo's arbitrary bone axes). Bones the IK model does not
// drive (twist helpers, end sites, spine bones standing for no vertebra, the bones of a
// non-site in the simplified spine) keep their rest local rotation, which is what the rigid IK
// segment between two IK joints assumes.
//
// The model is built at the avatar's canonical neutral pose (neutral_pose.h: arms hanging,
// forearms, thighs and shanks in line, whatever pose the avatar rests in), so q = 0 is neutral and
// the limb ranges below are anatomical ranges around it; `restConfiguration` is the q that puts the
// body in the avatar's rest pose (a solve starts from it). The ranges of a T-pose rig and of an
// A-pose mannequin are then the same body's.
//
// Joints (frames at the neutral pose: +Y along the bone towards its child, +X = +Y x forward,
// +Z = X x Y):
//   hips                  Free (6)
//   each spine site       the coupled spine's swing + torsion joints with the ranges and coupling
//                         rows of the vertebrae it stands for
//   head                  Ball, the Occ-C1 range
//   shoulder (clavicle)   Swing (2) about the bone axis, ±20°
//   upperArm              Ball; lowerArm: Revolute elbow (axis from the rest geometry, 1.7..150°
//                         from straight: never straight, never backwards)
//                         then Revolute forearm twist about the forearm (±80°); hand: Ball
//   upperLeg              Ball; lowerLeg: Revolute knee (1.7..140°); foot: Ball; toes: Revolute
// Segment masses and centres of mass: de Leva (1996) fractions scaled to the total mass,
// centres along each segment towards its child pivot.
//
// The spine sites carry the coupled spine of ik/spine (appendSpine on the avatar's own spine
// bones, see docs/avatars.md); `coupledSpine = false` gives one uncoupled Ball per site.
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "avatar/avatar_asset.h"
#include "ik/model.h"
#include "ik/solver.h"
#include "core/result.h"

namespace embody::avatar {

enum class SpineMode { Auto, Full, Simplified };
bool parseSpineMode(const std::string& text, SpineMode& out);  // "auto", "full", "simplified"

struct BodyModelOptions {
  SpineMode spine = SpineMode::Auto;
  double totalMass = 75.0;  // kg, distributed with de Leva's fractions
  bool addTasks = true;     // feet (0), centre of mass (1), head and hips (2), hands (3), as in PIK
  // Uniform scale from the avatar to the user (calibration.h): the IK model is built at the
  // user's size; retargeting divides the hips translation back, so the renderer draws the avatar
  // with this scale on its model matrix.
  double scale = 1.0;
  // true: the coupled spine (ik/spine: swing + torsion joints per site, coupling rows);
  // false: one uncoupled Ball joint per site with its vertebrae's summed ranges.
  bool coupledSpine = true;
};

struct BodyModel {
  ik::Model model;
  // Per IK joint: the avatar joint whose pivot it is (-1 never happens: every IK joint has one).
  std::vector<int> avatarJoint;
  // Per avatar joint: the IK joint that sets its world rotation (the last one at its pivot), -1
  // when the bone is not driven. Precomputed rest data for retargeting (model space).
  std::vector<int> ikJointOfAvatar;
  // Per IK joint: world rotation at the avatar's rest pose (q = restConfiguration).
  std::vector<Eigen::Quaterniond> ikRestRotation;
  std::vector<glm::quat> avatarRestGlobalRotation;  // per avatar joint
  std::vector<glm::vec3> avatarRestGlobalScale;     // per avatar joint (columns' lengths)
  // The configuration that reproduces the avatar's rest pose (q = 0 is the neutral pose):
  // limb Ball and hinge joints turned from neutral to rest, everything else 0. It is also the
  // model's JointDesc::neutral, so a fresh ik::Data starts there. A rest hinge bent backwards or
  // straight gives a value below its lower limit, as it is.
  Eigen::VectorXd restConfiguration;
  // The spine sites: avatar joint of each and the vertebral joints it stands for.
  std::vector<SpineBone> spineSites;
  double scale = 1.0;       // BodyModelOptions::scale
  int spineEqualities = 0;  // coupling rows the spine added (0 for the uncoupled spine)
  // The coupled spine's band between the thoracic and cervical regions: its inequality rows (both
  // sides of each component; empty for the uncoupled spine or a spine without a cervical site)
  // and their slack in the model (radians). The runtime widens it per frame (ik::Data::
  // setInequalityBound) when the head looks down.
  std::vector<int> neckBandRows;
  double bandSlack = 0.0;
  std::string spineModel;  // "full" (every vertebra a site), "bones" (the avatar's spine bones), "simplified"
  ik::JointId hips = -1, head = -1, leftHand = -1, rightHand = -1, leftFoot = -1, rightFoot = -1;
  // Task names follow runtime::PikBinding::byTaskNames: "head", "left_hand", "right_hand",
  // "hips" (disabled until a waist tracker drives it), "left_foot", "right_foot", plus "com".
  ik::TaskId headTask = -1, leftHandTask = -1, rightHandTask = -1, leftFootTask = -1, rightFootTask = -1,
             comTask = -1, hipsTask = -1;
};

// Fails when the avatar's humanoid mapping is not usable (missing required bones, listed).
Result<BodyModel> buildBodyModel(const AvatarAsset& avatar, const BodyModelOptions& options = {});

// IK configuration -> local transforms of the avatar's bones. `pose` is resized to the skeleton
// and starts from the rest pose; driven bones get rotations (and the hips a translation, divided
// by BodyModel::scale: avatar model space = IK world / scale).
// Allocation-free after the first call with a given skeleton.
void retarget(const BodyModel& body, const AvatarAsset& avatar, const ik::Data& data, SkeletonPose& pose);

}  // namespace embody::avatar
