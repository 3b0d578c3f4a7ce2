#pragma once
// Seated mode's pose numbers over a run: the "seated" object of `embody xr --seated --stats`
// (and `embody render --seated`). Distances in tracking metres (avatar metres / scale), angles in
// degrees. Frames are counted from when the seat is placed; the first `settleFrames` after that
// (the cold solve folding the legs onto the seat) are left out of the extremes.
#include <cstddef>
#include <nlohmann/json_fwd.hpp>

#include "runtime/avatar_body_solver.h"

namespace embody::runtime {

class SeatedStats {
 public:
  explicit SeatedStats(int settleFrames = 30) : settleFrames_(settleFrames) {}
  // After each solve of a seated solver (frames before the seat is placed are ignored).
  void add(const AvatarBodySolver& solver);

  size_t frames() const { return frames_; }
  // {"frames", "measured_frames", "seat_height_m", "hip_joint_drift_max_m" (hip joints from the
  //  seat), "ankle_drift_max_m" (ankles from their planted targets), "sole_height_m": [min, max]
  //  (ankles above their rest height, i.e. the soles above the floor), "knee_flexion_deg" and
  //  "hip_flexion_deg": [min, max], "pelvis_pitch_max_deg", "spine_flexion_max_deg"}
  void toJson(nlohmann::json& j) const;

 private:
  int settleFrames_;
  size_t frames_ = 0, measured_ = 0;
  double seatHeight_ = 0.0, hipDrift_ = 0.0, ankleDrift_ = 0.0;
  double soleMin_ = 1e9, soleMax_ = -1e9, kneeMin_ = 1e9, kneeMax_ = -1e9, hipMin_ = 1e9, hipMax_ = -1e9;
  double pitchMax_ = 0.0, spineMax_ = 0.0;
};

}  // namespace embody::runtime
