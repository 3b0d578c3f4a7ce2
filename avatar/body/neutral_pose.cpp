// The canonical neutral pose (see neutral_pose.h).
#include "avatar/body/neutral_pose.h"

#include <cmath>

namespace embody::avatar {
namespace {

using Eigen::Quaterniond;
using Eigen::Vector3d;

// A bone bent at rest by more than this (the sine of ~10 degrees) bends about that axis.
constexpr double kBentSine = 0.17;

// World transforms of a skeleton whose local rotations are `local` (translations and scales
// from the rest), in double precision; rotations with normalised columns.
class SkeletonFrames {
 public:
  explicit SkeletonFrames(const Skeleton& sk) : sk_(sk), n_(sk.joints.size()) {
    local_.reserve(n_);
    for (const Joint& j : sk.joints)
      local_.push_back(Quaterniond(j.rest.rotation.w, j.rest.rotation.x, j.rest.rotation.y, j.rest.rotation.z).normalized());
    update();
  }

  const Vector3d& position(int j) const { return position_[size_t(j)]; }
  const Quaterniond& rotation(int j) const { return rotation_[size_t(j)]; }
  Vector3d direction(int from, int to) const { return (position(to) - position(from)).normalized(); }
  bool distinct(int a, int b) const { return (position(b) - position(a)).norm() > 1e-5; }

  // Turns joint j (and everything below it) by the world rotation `turn` about its pivot.
  void turn(int j, const Quaterniond& turn) {
    const int p = sk_.joints[size_t(j)].parent;
    const Quaterniond parent = p >= 0 ? rotation(p) : Quaterniond::Identity();
    local_[size_t(j)] = (parent.conjugate() * turn * parent * local_[size_t(j)]).normalized();
    update();
  }

 private:
  const Skeleton& sk_;
  const size_t n_;
  std::vector<Quaterniond> local_;
  std::vector<Eigen::Affine3d> global_;
  std::vector<Vector3d> position_;
  std::vector<Quaterniond> rotation_;

  void update() {
    global_.resize(n_);
    position_.resize(n_);
    rotation_.resize(n_);
    for (size_t j = 0; j < n_; ++j) {
      const Transform& t = sk_.joints[j].rest;
      const Eigen::Affine3d m = Eigen::Translation3d(t.translation.x, t.translation.y, t.translation.z) * local_[j] *
                                Eigen::Scaling(double(t.scale.x), double(t.scale.y), double(t.scale.z));
      const int p = sk_.joints[j].parent;
      global_[j] = p >= 0 ? global_[size_t(p)] * m : m;
      position_[j] = global_[j].translation();
      Eigen::Matrix3d r = global_[j].linear();
      for (int c = 0; c < 3; ++c) r.col(c).normalize();
      rotation_[j] = Quaterniond(r).normalized();
    }
  }
};

// The shortest turn from `from` to `to`; past 120 degrees by way of `via`, so that a limb at
// rest far from its neutral (arms overhead) turns along a defined path.
Quaterniond shortestTurn(const Vector3d& from, const Vector3d& to, const Vector3d& via) {
  if (from.dot(to) > -0.5) return Quaterniond::FromTwoVectors(from, to);
  return Quaterniond::FromTwoVectors(via, to) * Quaterniond::FromTwoVectors(from, via);
}

// Signed angle from a to b about `axis` (both projected onto the plane normal to it).
double angleAbout(const Vector3d& a, const Vector3d& b, const Vector3d& axis) {
  const Vector3d pa = a - axis * axis.dot(a), pb = b - axis * axis.dot(b);
  return std::atan2(axis.dot(pa.cross(pb)), pa.dot(pb));
}

// The hinge axis of a limb whose upper bone points along dUpper and lower along dLower (see
// neutral_pose.h): the bend's own axis when bent, else upper x forward (arms) / x -forward (legs).
Vector3d hingeAxisOf(const Vector3d& dUpper, const Vector3d& dLower, const Vector3d& forward, const Vector3d& side,
                     bool arm) {
  Vector3d axis = dUpper.cross(arm ? forward : Vector3d(-forward));
  const Vector3d bent = dUpper.cross(dLower);
  if (bent.norm() > kBentSine) axis = bent.dot(axis) >= 0 ? bent : Vector3d(-bent);
  if (axis.norm() < 1e-6) axis = side;
  return axis.normalized();
}

// One limb to neutral: upper bone to its direction, hinge straightened about its axis, the end
// in line (hand) or back to its rest world orientation (foot). Returns the hinge axis.
Vector3d neutraliseLimb(SkeletonFrames& f, const NeutralLimb& limb, const Vector3d& up, const Vector3d& forward) {
  const Vector3d side = up.cross(forward).normalized();  // the avatar's left
  const Vector3d out = limb.left ? side : Vector3d(-side);
  if (limb.upper < 0 || limb.hinge < 0 || !f.distinct(limb.upper, limb.hinge)) return Vector3d::Zero();
  const Vector3d target = limb.arm ? Vector3d(-up * std::cos(kNeutralArmAbduction) + out * std::sin(kNeutralArmAbduction))
                                   : Vector3d(-up);
  f.turn(limb.upper, shortestTurn(f.direction(limb.upper, limb.hinge), target, limb.arm ? out : forward));
  if (limb.end < 0 || !f.distinct(limb.hinge, limb.end)) return Vector3d::Zero();
  const Vector3d dUpper = f.direction(limb.upper, limb.hinge);
  const Vector3d axis = hingeAxisOf(dUpper, f.direction(limb.hinge, limb.end), forward, side, limb.arm);
  f.turn(limb.hinge, Quaterniond(Eigen::AngleAxisd(-angleAbout(dUpper, f.direction(limb.hinge, limb.end), axis), axis)));
  if (limb.arm) {
    if (limb.endNext >= 0 && f.distinct(limb.end, limb.endNext))
      f.turn(limb.end, Quaterniond::FromTwoVectors(f.direction(limb.end, limb.endNext), f.direction(limb.hinge, limb.end)));
  }
  return axis;
}

}  // namespace

NeutralPose computeNeutralPose(const Skeleton& skeleton, const NeutralLimbs& limbs, const Vector3d& up,
                               const Vector3d& forward) {
  const Vector3d u = up.normalized();
  const Vector3d fwd = (forward - u * u.dot(forward)).normalized();
  const SkeletonFrames rest(skeleton);
  SkeletonFrames f(skeleton);
  NeutralPose out;
  for (size_t k = 0; k < limbs.size(); ++k) {
    const NeutralLimb& limb = limbs[k];
    out.hingeAxis[k] = neutraliseLimb(f, limb, u, fwd);
    // The foot keeps its rest orientation in the world: rest poses stand it on the floor.
    if (!limb.arm && limb.end >= 0) f.turn(limb.end, rest.rotation(limb.end) * f.rotation(limb.end).conjugate());
  }
  const size_t n = skeleton.joints.size();
  out.position.resize(n);
  out.rotation.resize(n);
  out.restFromNeutral.resize(n);
  for (size_t j = 0; j < n; ++j) {
    out.position[j] = f.position(int(j));
    out.rotation[j] = f.rotation(int(j));
    out.restFromNeutral[j] = (rest.rotation(int(j)) * f.rotation(int(j)).conjugate()).normalized();
  }
  return out;
}

}  // namespace embody::avatar
