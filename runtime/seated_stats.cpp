#include "runtime/seated_stats.h"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <numbers>

namespace embody::runtime {

void SeatedStats::add(const AvatarBodySolver& solver) {
  const SeatedPose* seat = solver.seat();
  if (!seat || !(solver.scale() > 0.0)) return;
  ++frames_;
  const double toMetres = 1.0 / solver.scale();
  seatHeight_ = seat->seatHeight * toMetres;
  if (frames_ <= size_t(std::max(settleFrames_, 0))) return;
  ++measured_;
  const LowerBodyPosture p = solver.posture();
  const SeatedLegs& legs = solver.seatedLegs();
  constexpr double kDeg = 180.0 / std::numbers::pi;
  for (size_t s = 0; s < 2; ++s) {
    hipDrift_ = std::max(hipDrift_, (p.hip[s] - seat->hip[s]).norm() * toMetres);
    ankleDrift_ = std::max(ankleDrift_, (p.ankle[s] - seat->ankle[s]).norm() * toMetres);
    const double sole = (legs.up.dot(p.ankle[s]) - legs.floor - legs.ankleHeight(int(s))) * toMetres;
    soleMin_ = std::min(soleMin_, sole), soleMax_ = std::max(soleMax_, sole);
    kneeMin_ = std::min(kneeMin_, p.kneeFlexion[s] * kDeg), kneeMax_ = std::max(kneeMax_, p.kneeFlexion[s] * kDeg);
    hipMin_ = std::min(hipMin_, p.hipFlexion[s] * kDeg), hipMax_ = std::max(hipMax_, p.hipFlexion[s] * kDeg);
  }
  pitchMax_ = std::max(pitchMax_, p.pelvisPitch * kDeg);
  spineMax_ = std::max(spineMax_, p.spineFlexion * kDeg);
}

void SeatedStats::toJson(nlohmann::json& j) const {
  const bool any = measured_ > 0;
  auto range = [&](double lo, double hi) { return any ? nlohmann::json::array({lo, hi}) : nlohmann::json::array(); };
  j["seated"] = {{"frames", frames_},
                 {"measured_frames", measured_},
                 {"seat_height_m", seatHeight_},
                 {"hip_joint_drift_max_m", hipDrift_},
                 {"ankle_drift_max_m", ankleDrift_},
                 {"sole_height_m", range(soleMin_, soleMax_)},
                 {"knee_flexion_deg", range(kneeMin_, kneeMax_)},
                 {"hip_flexion_deg", range(hipMin_, hipMax_)},
                 {"pelvis_pitch_max_deg", pitchMax_},
                 {"spine_flexion_max_deg", spineMax_}};
}

}  // namespace embody::runtime
