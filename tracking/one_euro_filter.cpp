#include "tracking/one_euro_filter.h"

#include <algorithm>
#include <cmath>

namespace embody::tracking {

float oneEuroAlpha(float cutoffHz, float dt) {
  const float tau = 1.0f / (6.28318530718f * std::max(cutoffHz, 1e-3f));
  return 1.0f / (1.0f + tau / dt);
}

float NoiseEstimate::update(const glm::vec3& velocity, float dt) {
  if (steps_ >= 2) {
    const glm::vec3 d3 = (velocity - 2.0f * previous_[0] + previous_[1]) * dt;
    // The mean of the samples so far until there are a window's worth, then exponential.
    samples_ = std::min(samples_ + 1, 1 << 20);
    variance_ += std::max(dt / (window_ + dt), 1.0f / static_cast<float>(samples_)) * (glm::dot(d3, d3) / 60.0f - variance_);
  }
  previous_[1] = previous_[0];
  previous_[0] = velocity;
  steps_ = std::min(steps_ + 1, 2);
  return deviation();
}

float NoiseEstimate::deviation() const { return std::sqrt(std::max(variance_, 0.0f)); }

float oneEuroCutoff(const OneEuroParams& p, float speed, NoiseEstimate& estimate, const glm::vec3& velocity, float dt) {
  const float cutoff = p.minCutoff + p.beta * speed;
  if (!(p.referenceNoise > 0.0f)) return cutoff;
  const float noise = estimate.update(velocity, dt);
  // Capped where alpha is 1 to float precision at any tracking rate (and for a silent signal).
  constexpr float kMaxCutoff = 1e5f;
  const float ratio = p.referenceNoise / std::max(noise, p.referenceNoise / std::sqrt(kMaxCutoff));
  return cutoff * std::max(1.0f, ratio * ratio);
}

glm::vec3 OneEuroVec3::filter(const glm::vec3& x, float dt) {
  if (!primed_) {
    x_ = raw_ = x;
    velocity_ = glm::vec3(0.0f);
    primed_ = true;
    return x_;
  }
  if (!(dt > 0.0f)) return x_;
  const glm::vec3 rawVelocity = (x - raw_) / dt;
  velocity_ += oneEuroAlpha(p_.derivativeCutoff, dt) * (rawVelocity - velocity_);
  raw_ = x;
  const float cutoff = oneEuroCutoff(p_, glm::length(velocity_), noise_, rawVelocity, dt);
  x_ += oneEuroAlpha(cutoff, dt) * (x - x_);
  return x_;
}

glm::quat OneEuroQuat::filter(const glm::quat& qIn, float dt) {
  glm::quat q = qIn;
  if (primed_ && glm::dot(q, q_) < 0.0f) q = -q;  // same hemisphere: shortest path
  if (!primed_) {
    q_ = raw_ = q;
    velocity_ = glm::vec3(0.0f);
    primed_ = true;
    return q_;
  }
  if (!(dt > 0.0f)) return q_;
  // Angular velocity of the raw signal (world frame): axis * angle / dt of q * raw^-1.
  glm::quat d = q * glm::inverse(raw_);
  if (d.w < 0.0f) d = -d;
  const float angle = 2.0f * std::acos(std::clamp(d.w, -1.0f, 1.0f));
  const float s = std::sqrt(std::max(0.0f, 1.0f - d.w * d.w));
  const glm::vec3 omega = s > 1e-6f ? glm::vec3(d.x, d.y, d.z) / s * (angle / dt) : glm::vec3(0.0f);
  velocity_ += oneEuroAlpha(p_.derivativeCutoff, dt) * (omega - velocity_);
  raw_ = q;
  const float cutoff = oneEuroCutoff(p_, glm::length(velocity_), noise_, omega, dt);
  q_ = glm::normalize(glm::slerp(q_, q, oneEuroAlpha(cutoff, dt)));
  return q_;
}

PoseFilter::PoseFilter(const TrackerFilterParams& params) {
  for (auto id : kAllTrackers) setParams(id, params);
}

void PoseFilter::setParams(TrackerId id, const TrackerFilterParams& params) {
  position_[static_cast<size_t>(index(id))] = OneEuroVec3(params.position);
  orientation_[static_cast<size_t>(index(id))] = OneEuroQuat(params.orientation);
}

void PoseFilter::reset() {
  for (auto& f : position_) f.reset();
  for (auto& f : orientation_) f.reset();
  haveRaw_.fill(false);
  primed_ = false;
}

PoseSample PoseFilter::apply(const PoseSample& input) {
  PoseSample out = input;
  const double dtd = primed_ ? input.time - lastTime_ : 0.0;
  if (primed_ && (dtd > maxGapSeconds || dtd < 0.0)) reset();
  const float dt = primed_ ? static_cast<float>(dtd) : 0.0f;
  for (auto id : kAllTrackers) {
    const auto i = static_cast<size_t>(index(id));
    TrackerPose& p = out[id];
    if (!p.valid || !isUsable(p)) {
      position_[i].reset();
      orientation_[i].reset();
      haveRaw_[i] = false;
      continue;
    }
    if (haveRaw_[i] && glm::length(p.position - lastRaw_[i]) > jumpSpeed * dt + 0.02f) {
      position_[i].reset();
      orientation_[i].reset();
    }
    lastRaw_[i] = p.position;
    haveRaw_[i] = true;
    p.position = position_[i].filter(p.position, dt);
    p.orientation = orientation_[i].filter(glm::normalize(p.orientation), dt);
  }
  lastTime_ = input.time;
  primed_ = true;
  return out;
}

}  // namespace embody::tracking
