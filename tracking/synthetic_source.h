#pragma once
// Built-in scripted motions for a standing user of a given height, deterministic closed-form
// functions of time (no randomness), each periodic. All six trackers are valid in every sample.
//   idle     weight shifting sway, breathing, small head turns
//   reach    the hands reach forward, sideways, overhead, low and across the body in turn
//   look     the head looks around (yaw +-60 deg, pitch +-25 deg) about the neck
//   bow      bending forward at the hips to 50 deg and back, arms hanging
//   figure8  both hands trace a figure eight in front of the chest (Raunhardt & Boulic 2008,
//            section 5.2.2), the head following them
//   squat    squatting 0.35 m (scaled) with the arms rising forward for balance
//   seated   sitting on a chair, leaning to reach forward and back, swaying (for seated mode)
#include <span>
#include <string_view>

#include "tracking/body_dimensions.h"
#include "tracking/pose_source.h"

namespace embody::tracking {

struct SyntheticMotionInfo {
  std::string_view name;         // without the "synthetic:" prefix
  std::string_view description;
  double period;                 // seconds
};

std::span<const SyntheticMotionInfo> syntheticMotions();

class SyntheticSource final : public PoseSource {
 public:
  // `motion` without the prefix; returns an error naming the known motions when unknown.
  static Result<std::unique_ptr<SyntheticSource>> create(std::string_view motion, float userHeight = 1.75f);

  std::string name() const override;
  TrackerMask trackers() const override { return TrackerMask::all(); }
  double duration() const override { return info_->period; }
  bool periodic() const override { return true; }
  PoseSample sample(double time) override;

  const BodyDimensions& body() const { return body_; }
  // The generator's shoulder joint at `time` (its hands stay within arm's reach of it).
  glm::vec3 shoulder(double time, Side side) const;

 private:
  SyntheticSource(const SyntheticMotionInfo* info, int kind, float userHeight);
  const SyntheticMotionInfo* info_;
  int kind_;
  BodyDimensions body_;
};

}  // namespace embody::tracking
