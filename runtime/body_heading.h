#pragma once
// The inferred body's heading in three-point mode: where the pelvis and the feet face, from the
// head's heading (faceHeadingOf). Upright, the body faces where the head does: a user who turns turns
// the body at once (a spinning jump lagged by a fixed band dragged the hands and knees round,
// cmu_131_03). Bent over, a head that looks at one leg and then the other turns on the neck while
// the body stays: the body follows the head only as far as `neckTurn` leaves between them. Before,
// each look turned the bent body and swung its pelvis, 0.6 m behind the head, from side to side.
// Stateful: one per body; reset() with the warm start.
namespace embody::runtime {

class BodyHeading {
 public:
  void reset() { initialised_ = false; }
  // The body's heading (radians about up) for this frame's head heading, at most `neckTurn`
  // radians from it (0: the head's own). The first call after a reset returns the head's.
  double update(double headYaw, double neckTurn);

 private:
  double yaw_ = 0.0;
  bool initialised_ = false;
};

}  // namespace embody::runtime
