#include "tracking/synthetic_source.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <glm/gtc/constants.hpp>

#include "avatar/body/calibration.h"
#include "core/smoothstep.h"

namespace embody::tracking {

namespace {

constexpr float kTau = 6.28318530717958647692f;

enum Kind { kIdle, kReach, kLook, kBow, kFigure8, kSquat, kSeated };

constexpr std::array<SyntheticMotionInfo, 7> kMotions = {{
    {"idle", "weight-shifting sway, breathing, small head turns", 8.0},
    {"reach", "the hands reach forward, sideways, overhead, low and across the body in turn", 14.0},
    {"look", "the head looks around (yaw +-60 deg, pitch +-25 deg), the trunk turning a little", 10.0},
    {"bow", "bending forward at the hips to 50 deg and back, arms hanging", 6.0},
    {"figure8", "both hands trace a figure eight in front of the chest (Raunhardt & Boulic 2008, 5.2.2)", 6.0},
    {"squat", "squatting 0.35 m (for 1.75 m) with the arms rising forward for balance", 5.0},
    {"seated", "sitting on a chair: leaning forward to reach a table and back, swaying sideways, looking around "
               "(for embody render --seated)", 8.0},
}};

glm::quat yawPitch(float yaw, float pitch) {
  return glm::angleAxis(yaw, glm::vec3(0, 1, 0)) * glm::angleAxis(pitch, glm::vec3(1, 0, 0));
}

// Spherical interpolation of two unit directions (they are never antipodal in the scripts).
glm::vec3 slerpDir(const glm::vec3& a, const glm::vec3& b, float u) {
  const float c = std::clamp(glm::dot(a, b), -1.0f, 1.0f);
  const float ang = std::acos(c);
  if (ang < 1e-4f) return glm::normalize(glm::mix(a, b, u));
  const float s = std::sin(ang);
  return glm::normalize(a * (std::sin((1.0f - u) * ang) / s) + b * (std::sin(u * ang) / s));
}

// A small generator skeleton: pelvis, a rigid trunk pivoting at the pelvis, a head pivoting at
// the neck. Every motion sets these few parameters; the trackers follow from the dimensions.
struct Figure {
  glm::vec3 pelvis{0.0f};
  glm::quat pelvisRot{1, 0, 0, 0};
  glm::quat trunkRot{1, 0, 0, 0};
  glm::quat headRot{1, 0, 0, 0};
  bool seated = false;  // the feet trackers in front of a seat instead of under the pelvis
};

struct Posed {
  Figure f;
  TrackerPose left, right;
};

struct Generator {
  const BodyDimensions& d;

  glm::vec3 neck(const Figure& f) const {
    return f.pelvis + f.trunkRot * glm::vec3(0, d.shoulderHeight + d.neckAboveShoulders - d.hipHeight, 0);
  }
  glm::vec3 shoulder(const Figure& f, Side side) const {
    const float x = side == Side::Left ? -d.shoulderHalfWidth : d.shoulderHalfWidth;
    return neck(f) + f.trunkRot * glm::vec3(x, -d.neckAboveShoulders, 0);
  }
  // Hand along a world direction from the shoulder, `frac` of the arm's reach.
  TrackerPose hand(const Figure& f, Side side, const glm::vec3& worldDir, float frac,
                   const glm::vec3& palm) const {
    TrackerPose p;
    const glm::vec3 dir = glm::normalize(worldDir);
    p.position = shoulder(f, side) + dir * (frac * d.armReach);
    p.orientation = gripOrientation(side, dir, palm);
    p.valid = true;
    return p;
  }
  // A hanging arm, in the trunk's frame unless `world` (then straight down under gravity).
  TrackerPose hanging(const Figure& f, Side side, float swing = 0.0f, bool world = false) const {
    const float out = side == Side::Left ? -1.0f : 1.0f;
    const glm::vec3 local = glm::normalize(glm::vec3(out * 0.08f, -1.0f, -0.05f + swing));
    const glm::quat frame = world ? headingOf(f.trunkRot) : f.trunkRot;
    return hand(f, side, frame * local, 0.96f, frame * glm::vec3(-out, 0, 0));
  }

  PoseSample compose(const Figure& f, const TrackerPose& left, const TrackerPose& right) const {
    PoseSample s;
    auto& head = s[TrackerId::Head];
    head.orientation = glm::normalize(f.headRot);
    head.position = neck(f) + head.orientation * glm::vec3(0, d.eyeAboveNeck, -d.eyeForward);
    head.valid = true;
    s[TrackerId::LeftHand] = left;
    s[TrackerId::RightHand] = right;
    s[TrackerId::Hips] = {f.pelvis, glm::normalize(f.pelvisRot), true};
    const float footX = d.hipHalfWidth + 0.01f * d.height;
    const float footZ = f.seated ? f.pelvis.z - d.thigh : 0.01f * d.height;
    s[TrackerId::LeftFoot] = {glm::vec3(-footX, d.ankleHeight, footZ), glm::quat(1, 0, 0, 0), true};
    s[TrackerId::RightFoot] = {glm::vec3(footX, d.ankleHeight, footZ), glm::quat(1, 0, 0, 0), true};
    return s;
  }

  Figure standing() const {
    Figure f;
    f.pelvis = glm::vec3(0, d.hipHeight, 0);
    return f;
  }

  // Head turned towards a point, by `gain` of the full angle.
  glm::quat lookAt(const Figure& f, const glm::vec3& target, float gain) const {
    const glm::vec3 eye = neck(f) + glm::vec3(0, d.eyeAboveNeck, -d.eyeForward);
    glm::vec3 v = target - eye;
    v.z = std::min(v.z, -0.3f * d.height / 1.75f);  // never look behind: atan2 would flip
    const float yaw = std::atan2(-v.x, -v.z);
    const float pitch = std::atan2(v.y, std::sqrt(v.x * v.x + v.z * v.z));
    return yawPitch(gain * yaw, std::clamp(gain * pitch, -0.6f, 0.5f));
  }

  Posed idle(float t) const {
    Figure f = standing();
    const float w = kTau / 8.0f;
    const float sway = std::sin(w * t);
    f.pelvis.x += 0.025f * d.height / 1.75f * sway;
    f.pelvis.y += 0.004f * std::sin(2.0f * w * t);
    f.pelvisRot = glm::angleAxis(0.02f * sway, glm::vec3(0, 0, 1));
    f.trunkRot = glm::angleAxis(-0.015f * sway, glm::vec3(0, 0, 1)) *
                 glm::angleAxis(0.01f * std::sin(2.0f * w * t), glm::vec3(1, 0, 0));
    f.headRot = yawPitch(0.1f * std::sin(2.0f * w * t + 1.0f), 0.05f * std::sin(w * t + 0.5f));
    const float swing = 0.05f * std::sin(2.0f * w * t);
    return {f, hanging(f, Side::Left, swing), hanging(f, Side::Right, -swing)};
  }

  Posed reach(float t) const {
    struct Key {
      glm::vec3 left;
      float leftFrac;
      glm::vec3 right;
      float rightFrac;
    };
    const glm::vec3 hangL(-0.08f, -1.0f, -0.05f), hangR(0.08f, -1.0f, -0.05f);
    const std::array<Key, 7> keys = {{
        {hangL, 0.96f, hangR, 0.96f},
        {hangL, 0.96f, {0.1f, 0.0f, -1.0f}, 0.9f},
        {{-0.1f, -0.5f, -1.0f}, 0.85f, {1.0f, 0.1f, -0.25f}, 0.9f},
        {{-0.25f, 1.0f, -0.35f}, 0.9f, {0.25f, 1.0f, -0.35f}, 0.9f},
        {{0.65f, -0.15f, -1.0f}, 0.8f, {0.2f, -0.8f, -0.6f}, 0.9f},
        {{-1.0f, 0.1f, -0.25f}, 0.9f, {-0.65f, 0.1f, -1.0f}, 0.8f},
        {{-0.15f, 0.5f, -1.0f}, 0.9f, hangR, 0.96f},
    }};
    const float keyTime = 2.0f;
    const int k = static_cast<int>(t / keyTime) % static_cast<int>(keys.size());
    const Key& a = keys[static_cast<size_t>(k)];
    const Key& b = keys[static_cast<size_t>((k + 1) % static_cast<int>(keys.size()))];
    // Move during the first 1.2 s of each key, hold for the rest.
    const float u = smoothstep((t - static_cast<float>(k) * keyTime) / 1.2f);
    Figure f = standing();
    const glm::vec3 dl = slerpDir(glm::normalize(a.left), glm::normalize(b.left), u);
    const glm::vec3 dr = slerpDir(glm::normalize(a.right), glm::normalize(b.right), u);
    const float fl = glm::mix(a.leftFrac, b.leftFrac, u), fr = glm::mix(a.rightFrac, b.rightFrac, u);
    // Lean the trunk slightly towards where the hands go, then look at the more active hand.
    const glm::vec3 lean = (dl + dr) * 0.5f;
    f.trunkRot = glm::angleAxis(0.08f * std::clamp(-lean.z, 0.0f, 1.0f), glm::vec3(-1, 0, 0)) *
                 glm::angleAxis(-0.06f * lean.x, glm::vec3(0, 1, 0));
    const float palmDown = 0.6f;
    TrackerPose left = hand(f, Side::Left, f.trunkRot * dl, fl, f.trunkRot * glm::vec3(1, -palmDown, 0));
    TrackerPose right = hand(f, Side::Right, f.trunkRot * dr, fr, f.trunkRot * glm::vec3(-1, -palmDown, 0));
    const float wl = 1.05f - glm::dot(dl, glm::normalize(hangL)), wr = 1.05f - glm::dot(dr, glm::normalize(hangR));
    const glm::vec3 ahead(0.0f, d.eyeHeight * 0.8f, -1.0f * d.height);
    const glm::vec3 gaze = (left.position * wl + right.position * wr + ahead * 0.2f) / (wl + wr + 0.2f);
    f.headRot = lookAt(f, gaze, 0.6f);
    return {f, left, right};
  }

  Posed look(float t) const {
    Figure f = standing();
    const float w = kTau / 10.0f;
    const float yaw = 1.05f * std::sin(w * t), pitch = 0.44f * std::sin(2.0f * w * t);
    f.trunkRot = glm::angleAxis(0.2f * yaw, glm::vec3(0, 1, 0));
    f.pelvisRot = glm::angleAxis(0.05f * yaw, glm::vec3(0, 1, 0));
    f.headRot = yawPitch(yaw, pitch);
    return {f, hanging(f, Side::Left), hanging(f, Side::Right)};
  }

  Posed bow(float t) const {
    Figure f = standing();
    const float u = 0.5f - 0.5f * std::cos(kTau * t / 6.0f);
    const float theta = 0.87f * u;
    // Hinge at the hips: the pelvis goes back to keep the centre of mass over the feet.
    f.pelvis.z += 0.12f * d.height / 1.75f * std::sin(theta);
    f.pelvis.y -= 0.03f * d.height / 1.75f * (1.0f - std::cos(theta));
    f.pelvisRot = glm::angleAxis(-0.55f * theta, glm::vec3(1, 0, 0));
    f.trunkRot = glm::angleAxis(-theta, glm::vec3(1, 0, 0));
    f.headRot = f.trunkRot * glm::angleAxis(0.25f * theta, glm::vec3(1, 0, 0));
    return {f, hanging(f, Side::Left, 0.0f, true), hanging(f, Side::Right, 0.0f, true)};
  }

  // Sitting on a chair (hip joints a thigh's thickness above a seat at 0.25 of stature): the trunk
  // leans forward 14 degrees as the hands reach for a table and comes back, sways sideways at half
  // the rate, the head looks at the hands and around.
  Posed seated(float t) const {
    Figure f;
    f.seated = true;
    f.pelvis = glm::vec3(0.0f, 0.30f * d.height, 0.0f);
    const float w = kTau / 8.0f;
    const float lean = 0.5f - 0.5f * std::cos(w * t), side = std::sin(0.5f * w * t);
    f.trunkRot = glm::angleAxis(-0.1f * side, glm::vec3(0, 0, 1)) * glm::angleAxis(-0.25f * lean, glm::vec3(1, 0, 0));
    f.headRot = yawPitch(0.3f * side, -0.3f + 0.1f * lean);
    const glm::quat heading = headingOf(f.trunkRot);
    const glm::vec3 dir = heading * glm::vec3(0.0f, -0.6f + 0.45f * lean, -1.0f);
    const float frac = 0.5f + 0.1f * lean;
    return {f, hand(f, Side::Left, dir, frac, heading * glm::vec3(1, -0.6f, 0)),
            hand(f, Side::Right, dir, frac, heading * glm::vec3(-1, -0.6f, 0))};
  }

  Posed figure8(float t) const {
    Figure f = standing();
    const float s = d.height / 1.75f;
    const float phi = kTau * t / 6.0f;
    // Lemniscate of Gerono in the frontal plane: x = A sin(phi), y = B sin(2 phi).
    const glm::vec3 c(0.0f, 1.18f * s, -0.32f * s);
    const glm::vec3 p = c + glm::vec3(0.2f * s * std::sin(phi), 0.15f * s * std::sin(2.0f * phi),
                                      0.03f * s * std::cos(2.0f * phi));
    f.trunkRot = glm::angleAxis(-0.3f * std::atan2(p.x, 0.4f * s), glm::vec3(0, 1, 0)) *
                 glm::angleAxis(-0.15f * (p.x / (0.2f * s)), glm::vec3(0, 0, 1));
    f.pelvisRot = glm::angleAxis(-0.08f * std::atan2(p.x, 0.4f * s), glm::vec3(0, 1, 0));
    const glm::vec3 apart(0.08f * s, 0.0f, 0.0f);
    auto place = [&](Side side, const glm::vec3& pos) {
      TrackerPose h;
      h.position = pos;
      const glm::vec3 fingers = glm::normalize(pos - shoulder(f, side)) + glm::vec3(0, 0, -0.5f);
      h.orientation = gripOrientation(side, fingers, glm::vec3(side == Side::Left ? 1.0f : -1.0f, 0, 0));
      h.valid = true;
      return h;
    };
    const TrackerPose left = place(Side::Left, p - apart), right = place(Side::Right, p + apart);
    f.headRot = lookAt(f, p, 0.7f);
    return {f, left, right};
  }

  Posed squat(float t) const {
    Figure f = standing();
    const float s = d.height / 1.75f;
    const float u = 0.5f - 0.5f * std::cos(kTau * t / 5.0f);
    f.pelvis.y -= 0.35f * s * u;
    f.pelvis.z += 0.12f * s * u;
    f.pelvisRot = glm::angleAxis(-0.35f * u, glm::vec3(1, 0, 0));
    f.trunkRot = glm::angleAxis(-0.45f * u, glm::vec3(1, 0, 0));
    f.headRot = f.trunkRot * glm::angleAxis(0.35f * u, glm::vec3(1, 0, 0));
    auto arm = [&](Side side) {
      const float out = side == Side::Left ? -1.0f : 1.0f;
      const glm::vec3 down = glm::normalize(glm::vec3(out * 0.08f, -1.0f, -0.05f));
      const glm::vec3 fwd = glm::normalize(glm::vec3(out * 0.1f, 0.0f, -1.0f));
      return hand(f, side, slerpDir(down, fwd, u), 0.93f, glm::vec3(-out, 0, 0));
    };
    return {f, arm(Side::Left), arm(Side::Right)};
  }
};

}  // namespace

std::span<const SyntheticMotionInfo> syntheticMotions() { return kMotions; }

SyntheticSource::SyntheticSource(const SyntheticMotionInfo* info, int kind, float userHeight)
    : info_(info), kind_(kind), body_(BodyDimensions::fromHeight(userHeight)) {}

Result<std::unique_ptr<SyntheticSource>> SyntheticSource::create(std::string_view motion, float userHeight) {
  if (!avatar::plausibleBodyHeight(userHeight))
    return Error{"user height " + std::to_string(userHeight) + " m is outside " + avatar::bodyHeightRange()};
  for (size_t i = 0; i < kMotions.size(); ++i)
    if (kMotions[i].name == motion)
      return std::unique_ptr<SyntheticSource>(new SyntheticSource(&kMotions[i], static_cast<int>(i), userHeight));
  std::string known;
  for (const auto& m : kMotions) known += (known.empty() ? "" : ", ") + std::string("synthetic:") + std::string(m.name);
  return Error{"unknown synthetic motion 'synthetic:" + std::string(motion) + "' (known: " + known + ")"};
}

std::string SyntheticSource::name() const { return "synthetic:" + std::string(info_->name); }

namespace {
Posed evaluate(const Generator& g, int kind, double time, double period) {
  // Periodic: evaluate at the phase, so long runs keep full float precision.
  double phase = std::fmod(time, period);
  if (!std::isfinite(phase)) phase = 0.0;
  if (phase < 0.0) phase += period;
  const float t = static_cast<float>(phase);
  switch (kind) {
    case kIdle: return g.idle(t);
    case kReach: return g.reach(t);
    case kLook: return g.look(t);
    case kBow: return g.bow(t);
    case kFigure8: return g.figure8(t);
    case kSeated: return g.seated(t);
    default: return g.squat(t);
  }
}
}  // namespace

glm::vec3 SyntheticSource::shoulder(double time, Side side) const {
  const Generator g{body_};
  return g.shoulder(evaluate(g, kind_, time, info_->period).f, side);
}

PoseSample SyntheticSource::sample(double time) {
  const Generator g{body_};
  const Posed p = evaluate(g, kind_, time, info_->period);
  PoseSample s = g.compose(p.f, p.left, p.right);
  s.time = time;
  sanitize(s);
  return s;
}

}  // namespace embody::tracking
