// EMBODY_XR_POSES through the project's own readers, the looped replay, the synthetic motion and
// the derived hand skeleton.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <istream>
#include <iterator>

#include "avatar/bvh/bvh.h"
#include "tools/xr_runtime/runtime.h"
#include "tracking/bvh_source.h"
#include "tracking/trace.h"

namespace embody::xr_runtime {

namespace {

// The head and hands of a trace, as the runtime replays them; "" or why not. Times stay within a
// day of the first, so sample() can subtract and divide them.
std::string toBodySamples(const tracking::Trace& trace, const std::string& name, std::vector<BodySample>& out) {
  out.clear();
  if (trace.samples.empty()) return name + ": no samples";
  if (!(trace.samples.back().time - trace.samples.front().time <= 86400.0))
    return name + ": the samples' times span more than a day";
  out.reserve(trace.samples.size());
  for (const tracking::PoseSample& p : trace.samples) {
    // Lost tracking is an identity pose marked invalid, never NaN (a BVH chain that overflows).
    auto clean = [&](tracking::TrackerId id) {
      const TrackerPose& t = p[id];
      return t.valid && tracking::isUsable(t) ? t : TrackerPose{};
    };
    BodySample s;
    s.t = p.time;
    s.head = clean(tracking::TrackerId::Head);
    s.left = clean(tracking::TrackerId::LeftHand);
    s.right = clean(tracking::TrackerId::RightHand);
    s.leftTrigger = p.triggers[0];
    s.rightTrigger = p.triggers[1];
    out.push_back(s);
  }
  return "";
}

// Between two samples: interpolated while both are valid, else the nearer one.
TrackerPose between(const TrackerPose& a, const TrackerPose& b, float u) {
  if (!a.valid || !b.valid) return u < 0.5f ? a : b;
  return tracking::interpolate(a, b, u);
}

glm::quat yawPitch(float yaw, float pitch) {
  return glm::angleAxis(yaw, glm::vec3(0, 1, 0)) * glm::angleAxis(pitch, glm::vec3(1, 0, 0));
}

}  // namespace

std::string parseTraceSamples(std::istream& in, const std::string& name, std::vector<BodySample>& out) {
  out.clear();
  auto trace = tracking::parseTrace(in, name);
  if (!trace) return trace.error();
  return toBodySamples(*trace, name, out);
}

std::string parseBvhSamples(std::istream& in, const std::string& name, std::vector<BodySample>& out) {
  out.clear();
  // Read at most what the BVH reader would accept from a file (avatar::loadBvh's bound).
  const size_t maxBytes = avatar::BvhLimits{}.maxValues * 16;
  std::string text;
  for (std::istreambuf_iterator<char> it(in), end; it != end; ++it) {
    if (text.size() >= maxBytes) return name + ": file too large for a BVH clip";
    text += *it;
  }
  auto clip = avatar::parseBvh(text, name);
  if (!clip) return clip.error();
  auto trace = tracking::bvhToTrace(*clip, tracking::BvhTrackerOptions{});
  if (!trace) return name + ": " + trace.error();
  return toBodySamples(*trace, name, out);
}

void PoseProvider::use(std::vector<BodySample> samples, std::string source) {
  samples_ = std::move(samples);
  source_ = std::move(source);
}

void PoseProvider::loadFromEnvironment() {
  const char* path = std::getenv("EMBODY_XR_POSES");
  if (!path || !*path) return;
  const std::string p = path;
  std::ifstream in(p, std::ios::binary);
  if (!in) {
    error_ = "cannot open EMBODY_XR_POSES file " + p;
    return;
  }
  const bool bvh = p.size() > 4 && (p.substr(p.size() - 4) == ".bvh" || p.substr(p.size() - 4) == ".BVH");
  std::vector<BodySample> samples;
  error_ = bvh ? parseBvhSamples(in, p, samples) : parseTraceSamples(in, p, samples);
  if (error_.empty()) use(std::move(samples), p);
}

BodySample PoseProvider::sample(double seconds) const {
  if (samples_.empty()) {
    // A person standing at the stage origin, looking around gently, hands in front of the body
    // drawing slow circles: every pose stays valid and smooth.
    const float t = static_cast<float>(seconds);
    BodySample s;
    s.t = seconds;
    s.head = {{{0.02f * std::sin(0.7f * t), 1.62f + 0.01f * std::sin(1.1f * t), 0.0f},
               yawPitch(0.25f * std::sin(0.5f * t), -0.1f + 0.05f * std::sin(0.8f * t))},
              true};
    const float a = 1.3f * t;
    s.left = {{{-0.22f + 0.05f * std::cos(a), 1.25f + 0.05f * std::sin(a), -0.35f}, yawPitch(0.2f, 0.3f)},
              true};
    s.right = {{{0.22f + 0.05f * std::cos(-a), 1.25f + 0.05f * std::sin(-a), -0.35f}, yawPitch(-0.2f, 0.3f)},
               true};
    return s;
  }
  // Looped trace, linear/spherical interpolation between neighbouring samples.
  const double duration = samples_.back().t - samples_.front().t;
  double t = samples_.front().t + (duration > 0.0 ? std::fmod(std::max(seconds, 0.0), duration + 1e-9) : 0.0);
  auto hi = std::lower_bound(samples_.begin(), samples_.end(), t,
                             [](const BodySample& s, double v) { return s.t < v; });
  if (hi == samples_.begin()) return *hi;
  if (hi == samples_.end()) return samples_.back();
  const auto lo = hi - 1;
  const float u = hi->t > lo->t ? static_cast<float>((t - lo->t) / (hi->t - lo->t)) : 1.0f;
  BodySample s;
  s.t = seconds;
  s.head = between(lo->head, hi->head, u);
  s.left = between(lo->left, hi->left, u);
  s.right = between(lo->right, hi->right, u);
  s.leftTrigger = glm::mix(lo->leftTrigger, hi->leftTrigger, u);
  s.rightTrigger = glm::mix(lo->rightTrigger, hi->rightTrigger, u);
  return s;
}

Pose aimFromGrip(const Pose& grip) {
  // The aim ray starts a little ahead of the grip and points 30 degrees further down than the
  // handle's forward axis, like most tracked controllers.
  const Pose local{{0.0f, 0.0f, -0.05f}, glm::angleAxis(glm::radians(-30.0f), glm::vec3(1, 0, 0))};
  return grip * local;
}

void handJointsFromGrip(const Pose& grip, bool leftHand, float curl, std::array<HandJoint, 26>& out) {
  // Palm frame per XR_EXT_hand_tracking: +Y out of the back of the hand, +Z towards the wrist.
  // Grip frame: -Z along the straightened index finger, +X normal to the palm (into the palm for
  // the right hand, away from it for the left). So palm = grip * Rz(-90 deg) (right), Rz(+90)
  // (left); with this the right thumb lies at palm -X.
  const Pose palm =
      grip * Pose{{0.0f, 0.0f, 0.0f}, glm::angleAxis(glm::radians(leftHand ? 90.0f : -90.0f), glm::vec3(0, 0, 1))};
  auto local = [&](int index, const glm::vec3& p, float radius) {
    out[index].pose.position = p;
    out[index].radius = radius;
  };
  // Positions in palm frame for a right hand (thumb side is -X), then mirrored.
  local(XR_HAND_JOINT_PALM_EXT, {0.0f, 0.0f, 0.0f}, 0.025f);
  local(XR_HAND_JOINT_WRIST_EXT, {0.0f, 0.0f, 0.055f}, 0.022f);
  struct Finger {
    int first;
    float x, baseZ, knuckleZ;
    float lengths[3];
    float radius;
  };
  const Finger fingers[4] = {
      {XR_HAND_JOINT_INDEX_METACARPAL_EXT, -0.022f, 0.04f, -0.035f, {0.040f, 0.025f, 0.022f}, 0.0095f},
      {XR_HAND_JOINT_MIDDLE_METACARPAL_EXT, 0.0f, 0.04f, -0.038f, {0.045f, 0.028f, 0.024f}, 0.0095f},
      {XR_HAND_JOINT_RING_METACARPAL_EXT, 0.019f, 0.038f, -0.034f, {0.042f, 0.026f, 0.023f}, 0.009f},
      {XR_HAND_JOINT_LITTLE_METACARPAL_EXT, 0.036f, 0.035f, -0.027f, {0.032f, 0.018f, 0.020f}, 0.008f}};
  const float bend = glm::radians(12.0f + 60.0f * std::clamp(curl, 0.0f, 1.0f));
  for (const auto& f : fingers) {
    local(f.first, {f.x * 0.6f, 0.0f, f.baseZ}, f.radius * 1.1f);
    glm::vec3 p{f.x, 0.0f, f.knuckleZ};
    local(f.first + 1, p, f.radius);
    float angle = 0.0f;
    for (int k = 0; k < 3; ++k) {
      angle += bend;  // each phalanx bends further towards the palm (-Y)
      p += f.lengths[k] * glm::vec3(0.0f, -std::sin(angle), -std::cos(angle));
      local(f.first + 2 + k, p, f.radius * (k == 2 ? 0.8f : 0.9f));
    }
  }
  local(XR_HAND_JOINT_THUMB_METACARPAL_EXT, {-0.02f, -0.012f, 0.032f}, 0.012f);
  local(XR_HAND_JOINT_THUMB_PROXIMAL_EXT, {-0.042f, -0.018f, 0.0f}, 0.01f);
  local(XR_HAND_JOINT_THUMB_DISTAL_EXT, {-0.056f, -0.022f, -0.028f}, 0.009f);
  local(XR_HAND_JOINT_THUMB_TIP_EXT, {-0.064f, -0.024f, -0.05f}, 0.008f);
  if (leftHand)  // the left hand is the mirror image: thumb at palm +X
    for (auto& j : out) j.pose.position.x = -j.pose.position.x;
  // Orientation: -Z along the bone towards the next joint (tips copy their parent), +Y the back of
  // the finger. The back is carried down each finger from the previous joint's +Y (starting at the
  // back of the hand), so it stays on the nail side when a curled phalanx points back up.
  auto orient = [&](int joint, int next, const glm::vec3& back) {
    const glm::vec3 forward = out[next].pose.position - out[joint].pose.position;
    const glm::vec3 z = -glm::normalize(forward);
    glm::vec3 x = glm::cross(back, z);
    x = glm::length(x) < 1e-4f ? glm::vec3(1, 0, 0) : glm::normalize(x);
    const glm::vec3 y = glm::cross(z, x);
    out[joint].pose.orientation = glm::quat_cast(glm::mat3(x, y, z));
    return y;
  };
  out[XR_HAND_JOINT_PALM_EXT].pose.orientation = glm::quat(1, 0, 0, 0);
  out[XR_HAND_JOINT_WRIST_EXT].pose.orientation = glm::quat(1, 0, 0, 0);
  for (int chainStart : {2, 6, 11, 16, 21}) {
    const int last = chainStart == 2 ? 5 : chainStart + 4;
    glm::vec3 back(0, 1, 0);
    for (int j = chainStart; j < last; ++j) back = orient(j, j + 1, back);
    out[last].pose.orientation = out[last - 1].pose.orientation;
  }
  for (auto& j : out) j.pose = palm * j.pose;
}

}  // namespace embody::xr_runtime
