#pragma once
// Where knees and elbows point. A leg (hip, knee, ankle) or an arm (shoulder, elbow, wrist) with
// its end placed still has one free turn about the line from its root to its end (the swivel).
// Trackers say nothing about it, and a solver that leaves it to the warm start lets knees drift
// inwards, cross, or bend backwards, and elbows flare. Each frame the runtime gives the knee and
// the elbow a position target on that circle of possible places, in an anatomical direction, at
// the lowest priority (it only uses the freedom every tracker task leaves):
//
//   knee    towards where its foot points (the knee over the toes)
//   elbow   down and a little back, turned outwards as the palm turns down (a pronated hand
//           lifts the elbow sideways, a supinated one lets it hang), outwards as the hand rises
//
// The target is never on the root-end line: the chain is taken as at most `maxExtension` of its
// length, so a straight limb is pulled slightly bent in the anatomical direction and a solver
// that must shorten it (a squat, a hand coming back) finds the hinge already bent the right way
// instead of stalling at the straight-limb singularity.
#include <Eigen/Core>

namespace embody::runtime {

struct LimbGeometry {
  double upper = 0.0, lower = 0.0;  // root -> middle joint and middle joint -> end, at rest
};

// The middle joint's place for a chain from `root` to `end` with the given segment lengths, in
// the direction `pole` (its part perpendicular to root -> end; when it has none, `fallback`'s).
Eigen::Vector3d poleTarget(const Eigen::Vector3d& root, const Eigen::Vector3d& end, const LimbGeometry& limb,
                           const Eigen::Vector3d& pole, const Eigen::Vector3d& fallback, double maxExtension = 0.999);

// The elbow's pole direction (avatar space): `up`, the body's `forward` and the arm's outward
// side (away from the body), the palm's normal (out of the palm) and the hand relative to the shoulder.
Eigen::Vector3d elbowPole(const Eigen::Vector3d& up, const Eigen::Vector3d& forward, const Eigen::Vector3d& outward,
                          const Eigen::Vector3d& palmNormal, const Eigen::Vector3d& shoulderToHand);

}  // namespace embody::runtime
