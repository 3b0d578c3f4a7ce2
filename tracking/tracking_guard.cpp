#include "tracking/tracking_guard.h"

#include <algorithm>
#include <cmath>

#include "avatar/body/calibration.h"

namespace embody::tracking {

namespace {

constexpr std::array<std::string_view, 6> kStatusNames = {"tracked", "recovering", "held", "easing", "neutral", "absent"};

bool isHand(TrackerId id) { return id == TrackerId::LeftHand || id == TrackerId::RightHand; }
bool isFoot(TrackerId id) { return id == TrackerId::LeftFoot || id == TrackerId::RightFoot; }
Side sideOf(TrackerId id) { return id == TrackerId::LeftHand ? Side::Left : Side::Right; }

// The frame lost trackers are held in: the head's position and heading.
struct Anchor {
  glm::vec3 origin;
  glm::quat heading;
  TrackerPose toLocal(const TrackerPose& p) const {
    const glm::quat inv = glm::inverse(heading);
    return {inv * (p.position - origin), glm::normalize(inv * p.orientation), true};
  }
  TrackerPose toWorld(const TrackerPose& p) const {
    return {origin + heading * p.position, glm::normalize(heading * p.orientation), true};
  }
};

// Moves `from` towards `to` by at most the given linear and angular steps.
TrackerPose approach(const TrackerPose& from, const TrackerPose& to, float maxStep, float maxAngle, bool& arrived) {
  TrackerPose r = to;
  const glm::vec3 d = to.position - from.position;
  const float dist = glm::length(d);
  if (dist > maxStep) r.position = from.position + d * (maxStep / dist);
  glm::quat qt = to.orientation;
  if (glm::dot(from.orientation, qt) < 0.0f) qt = -qt;
  const float angle = 2.0f * std::acos(std::clamp(glm::dot(from.orientation, qt), -1.0f, 1.0f));
  if (angle > maxAngle) r.orientation = glm::normalize(glm::slerp(from.orientation, qt, maxAngle / angle));
  arrived = dist <= std::max(maxStep, 1e-3f) && angle <= std::max(maxAngle, 1e-2f);
  r.valid = true;
  return r;
}

bool finitePose(const TrackerPose& p) { return isUsable(p); }

}  // namespace

std::string_view statusName(TrackerStatus s) { return kStatusNames[static_cast<size_t>(s)]; }

TrackingGuard::TrackingGuard(const TrackingGuardConfig& config)
    : config_(config), body_(BodyDimensions::fromHeight(float(std::clamp(double(config.userHeight), avatar::kMinBodyHeight, avatar::kMaxBodyHeight)))) {
  reset();
}

void TrackingGuard::reset() {
  state_ = {};
  primed_ = false;
  out_ = GuardedSample{};
  // Before any data: standing at the origin, looking along -Z, hands hanging.
  auto& head = out_.pose[TrackerId::Head];
  head = {glm::vec3(0.0f, body_.eyeHeight, 0.0f), glm::quat(1, 0, 0, 0), true};
  out_.status.fill(TrackerStatus::Absent);
  out_.status[static_cast<size_t>(index(TrackerId::Head))] = TrackerStatus::Neutral;
  for (auto id : {TrackerId::LeftHand, TrackerId::RightHand}) {
    out_.pose[id] = body_.neutralHand(head, sideOf(id));
    out_.status[static_cast<size_t>(index(id))] = TrackerStatus::Neutral;
  }
}

bool TrackingGuard::accept(State& st, const TrackerPose& in, double time) {
  if (!in.valid || !isUsable(in)) return false;
  if (st.acceptedTime >= 0.0) {
    const double dt = time - st.acceptedTime;
    const float dist = glm::length(in.position - st.accepted.position);
    // 2 cm of slack: a sample repeated at a tiny dt is not a jump.
    const bool jump = dt < 1.0 && dist > config_.jumpSpeed * static_cast<float>(std::max(dt, 0.0)) + 0.02f;
    if (jump) {
      if (st.jumpSince < 0.0) st.jumpSince = time;
      if (time - st.jumpSince < config_.maxJumpRejectSeconds) return false;
    }
  }
  st.jumpSince = -1.0;
  st.accepted = in;
  st.accepted.orientation = glm::normalize(in.orientation);
  st.acceptedTime = time;
  return true;
}

void TrackingGuard::updateHead(const TrackerPose& in, double time, float dt) {
  const auto i = static_cast<size_t>(index(TrackerId::Head));
  State& st = state_[i];
  TrackerPose& out = out_.pose.trackers[i];
  TrackerStatus& status = out_.status[i];
  if (accept(st, in, time)) {
    if (status == TrackerStatus::Tracked || !primed_) {
      out = st.accepted;  // still tracked, or the very first sample: nothing to blend from
      status = TrackerStatus::Tracked;
    } else {
      bool arrived = false;
      out = approach(out, st.accepted, config_.recoverySpeed * dt, config_.recoveryAngularSpeed * dt, arrived);
      status = arrived ? TrackerStatus::Tracked : TrackerStatus::Recovering;
    }
    st.lostSince = -1.0;
    return;
  }
  // Lost: hold the last head pose (there is nothing to hold it relative to).
  if (status == TrackerStatus::Tracked || status == TrackerStatus::Recovering) {
    st.lostSince = time;
    status = TrackerStatus::Held;
  }
}

void TrackingGuard::updateLimb(TrackerId id, const TrackerPose& in, double time, float dt) {
  const auto i = static_cast<size_t>(index(id));
  State& st = state_[i];
  TrackerPose& out = out_.pose.trackers[i];
  TrackerStatus& status = out_.status[i];
  const TrackerPose& head = out_.pose[TrackerId::Head];
  const Anchor anchor = isFoot(id) ? Anchor{glm::vec3(0.0f), glm::quat(1, 0, 0, 0)}
                                   : Anchor{head.position, headingOf(head.orientation)};
  // A target lost now is captured relative to the head it was solved with (the previous one).
  const Anchor lostAnchor = isFoot(id) ? anchor : Anchor{prevHead_.position, headingOf(prevHead_.orientation)};
  const bool neverSeen = st.acceptedTime < 0.0;
  if (accept(st, in, time)) {
    // Snap only when there is no earlier target to blend from.
    if (status == TrackerStatus::Tracked || (neverSeen && (!primed_ || status == TrackerStatus::Absent))) {
      out = st.accepted;
      status = TrackerStatus::Tracked;
    } else {
      // From wherever the target was (held, easing, neutral, or the held pose of a dropped
      // tracker) towards the live pose, speed-limited.
      if (status == TrackerStatus::Absent) out = anchor.toWorld(st.anchoredLocal);
      bool arrived = false;
      out = approach(out, st.accepted, config_.recoverySpeed * dt, config_.recoveryAngularSpeed * dt, arrived);
      status = arrived ? TrackerStatus::Tracked : TrackerStatus::Recovering;
    }
    st.lostSince = -1.0;
    return;
  }
  if (neverSeen) {
    if (isHand(id)) {
      out = body_.neutralHand(head, sideOf(id));
      status = TrackerStatus::Neutral;
    }
    return;  // hips and feet: Absent until first seen
  }
  if (status == TrackerStatus::Tracked || status == TrackerStatus::Recovering) {
    st.lostSince = time;
    st.anchoredLocal = lostAnchor.toLocal(out);
  }
  const float age = static_cast<float>(time - st.lostSince);
  const TrackerPose held = anchor.toWorld(st.anchoredLocal);
  if (age < config_.holdSeconds) {
    out = held;
    status = TrackerStatus::Held;
  } else if (isHand(id)) {
    const float u = config_.easeSeconds > 0.0f ? std::clamp((age - config_.holdSeconds) / config_.easeSeconds, 0.0f, 1.0f)
                                               : 1.0f;
    const float s = u * u * (3.0f - 2.0f * u);
    out = interpolate(held, body_.neutralHand(head, sideOf(id)), s);
    out.valid = true;
    status = u >= 1.0f ? TrackerStatus::Neutral : TrackerStatus::Easing;
  } else {
    out = held;  // kept for blending back in when the tracker returns
    status = TrackerStatus::Absent;
  }
}

const GuardedSample& TrackingGuard::update(const PoseSample& input) {
  const double time = input.time;
  float dt = primed_ ? static_cast<float>(std::clamp(time - lastTime_, 0.0, 0.1)) : 0.0f;
  if (!std::isfinite(time)) dt = 0.0f;
  prevHead_ = out_.pose[TrackerId::Head];
  updateHead(input[TrackerId::Head], time, dt);
  for (auto id : {TrackerId::Hips, TrackerId::LeftHand, TrackerId::RightHand, TrackerId::LeftFoot, TrackerId::RightFoot})
    updateLimb(id, input[id], time, dt);
  // Lost hands stay within reach of the estimated shoulder. (Not recovering ones: they head for
  // a live target, which the estimate must not hold back, from a point that was within reach.)
  const TrackerPose& head = out_.pose[TrackerId::Head];
  for (auto id : {TrackerId::LeftHand, TrackerId::RightHand}) {
    const auto s = out_.status[static_cast<size_t>(index(id))];
    if (s == TrackerStatus::Tracked || s == TrackerStatus::Recovering) continue;
    TrackerPose& h = out_.pose[id];
    const glm::vec3 shoulder = body_.shoulderFromHead(head, sideOf(id));
    const float maxReach = config_.reachMargin * body_.armReach;
    const glm::vec3 d = h.position - shoulder;
    const float len = glm::length(d);
    if (len > maxReach) h.position = shoulder + d * (maxReach / len);
  }
  // Belt and braces: whatever happened above, no NaN leaves this function.
  for (auto id : kAllTrackers) {
    TrackerPose& p = out_.pose[id];
    const auto i = static_cast<size_t>(index(id));
    if (out_.status[i] == TrackerStatus::Absent) {
      p.valid = false;
      if (!finitePose(p)) p = TrackerPose{head.position, glm::quat(1, 0, 0, 0), false};
      continue;
    }
    if (!finitePose(p)) p = isHand(id) ? body_.neutralHand(head, sideOf(id)) : TrackerPose{head.position, glm::quat(1, 0, 0, 0), true};
    p.valid = true;
  }
  out_.pose.time = time;
  lastTime_ = time;
  primed_ = true;
  return out_;
}

}  // namespace embody::tracking
