// Pose math, the JSON Lines trace reader, the synthetic motion and the derived hand skeleton.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <istream>
#include <nlohmann/json.hpp>

#include "tools/xr_runtime/runtime.h"

namespace embody::xr_runtime {

Pose compose(const Pose& a, const Pose& b) {
  return {a.p + a.q * b.p, glm::normalize(a.q * b.q)};
}

Pose inverse(const Pose& a) {
  const glm::quat qi = glm::conjugate(a.q);
  return {qi * -a.p, qi};
}

Pose fromXr(const XrPosef& p) {
  Pose r{{p.position.x, p.position.y, p.position.z},
         glm::quat(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z)};
  const float n = glm::length(r.q);
  r.q = n > 1e-6f && std::isfinite(n) ? r.q / n : glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  return r;
}

XrPosef toXr(const Pose& p) {
  XrPosef r;
  r.position = {p.p.x, p.p.y, p.p.z};
  r.orientation = {p.q.x, p.q.y, p.q.z, p.q.w};
  return r;
}

namespace {

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// {"p": [x,y,z], "q": [x,y,z,w], "valid": bool}; anything malformed or non-finite is invalid.
TrackedPose readTracked(const nlohmann::json& j) {
  TrackedPose t;
  if (!j.is_object()) return t;
  const auto p = j.find("p"), q = j.find("q");
  if (p == j.end() || q == j.end() || !p->is_array() || !q->is_array() || p->size() != 3 || q->size() != 4)
    return t;
  for (const auto& v : *p)
    if (!v.is_number()) return t;
  for (const auto& v : *q)
    if (!v.is_number()) return t;
  t.pose.p = {(*p)[0].get<float>(), (*p)[1].get<float>(), (*p)[2].get<float>()};
  glm::quat quat((*q)[3].get<float>(), (*q)[0].get<float>(), (*q)[1].get<float>(), (*q)[2].get<float>());
  const float n = glm::length(quat);
  if (!finite(t.pose.p) || !std::isfinite(n) || n < 1e-6f) return t;
  t.pose.q = quat / n;
  const auto valid = j.find("valid");
  t.valid = valid == j.end() || (valid->is_boolean() && valid->get<bool>());
  return t;
}

// The hand's "trigger" (0..1); anything else (missing, not a number, out of range) clamps.
float readTrigger(const nlohmann::json& sample, const char* hand) {
  const auto h = sample.find(hand);
  if (h == sample.end() || !h->is_object()) return 0.0f;
  const auto t = h->find("trigger");
  if (t == h->end() || !t->is_number()) return 0.0f;
  const double v = t->get<double>();
  return std::isfinite(v) ? static_cast<float>(std::clamp(v, 0.0, 1.0)) : 0.0f;
}

TrackedPose interpolate(const TrackedPose& a, const TrackedPose& b, float u) {
  if (!a.valid || !b.valid) return u < 0.5f ? a : b;
  return {{glm::mix(a.pose.p, b.pose.p, u), glm::slerp(a.pose.q, b.pose.q, u)}, true};
}

glm::quat yawPitch(float yaw, float pitch) {
  return glm::angleAxis(yaw, glm::vec3(0, 1, 0)) * glm::angleAxis(pitch, glm::vec3(1, 0, 0));
}

}  // namespace

std::string parseTraceSamples(std::istream& in, const std::string& name, std::vector<BodySample>& out) {
  out.clear();
  std::string line;
  int lineNo = 0;
  while (std::getline(in, line)) {
    ++lineNo;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto where = name + ":" + std::to_string(lineNo) + ": ";
    const auto j = nlohmann::json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("t") || !j["t"].is_number())
      return where + "not a trace sample ({\"t\": seconds, ...})";
    BodySample s;
    s.t = j["t"].get<double>();
    // Times stay within a day of each other, so sample() can subtract and divide them.
    if (!std::isfinite(s.t) || (!out.empty() && (s.t < out.back().t || s.t - out.front().t > 86400.0)))
      return where + "time goes backwards, jumps past a day or is not finite";
    if (j.contains("head")) s.head = readTracked(j["head"]);
    if (j.contains("left")) s.left = readTracked(j["left"]);
    if (j.contains("right")) s.right = readTracked(j["right"]);
    s.leftTrigger = readTrigger(j, "left");
    s.rightTrigger = readTrigger(j, "right");
    out.push_back(s);
  }
  if (out.empty()) return name + ": no samples";
  return "";
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
  s.head = interpolate(lo->head, hi->head, u);
  s.left = interpolate(lo->left, hi->left, u);
  s.right = interpolate(lo->right, hi->right, u);
  s.leftTrigger = glm::mix(lo->leftTrigger, hi->leftTrigger, u);
  s.rightTrigger = glm::mix(lo->rightTrigger, hi->rightTrigger, u);
  return s;
}

Pose aimFromGrip(const Pose& grip) {
  // The aim ray starts a little ahead of the grip and points 30 degrees further down than the
  // handle's forward axis, like most tracked controllers.
  const Pose local{{0.0f, 0.0f, -0.05f}, glm::angleAxis(glm::radians(-30.0f), glm::vec3(1, 0, 0))};
  return compose(grip, local);
}

void handJointsFromGrip(const Pose& grip, bool leftHand, float curl, std::array<HandJoint, 26>& out) {
  // Palm frame per XR_EXT_hand_tracking: +Y out of the back of the hand, +Z towards the wrist.
  // Grip frame: -Z along the straightened index finger, +X normal to the palm (into the palm for
  // the right hand, away from it for the left). So palm = grip * Rz(-90 deg) (right), Rz(+90)
  // (left); with this the right thumb lies at palm -X.
  const Pose palm = compose(
      grip,
      {{0.0f, 0.0f, 0.0f}, glm::angleAxis(glm::radians(leftHand ? 90.0f : -90.0f), glm::vec3(0, 0, 1))});
  auto local = [&](int index, const glm::vec3& p, float radius) {
    out[index].pose.p = p;
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
    for (auto& j : out) j.pose.p.x = -j.pose.p.x;
  // Orientation: -Z along the bone towards the next joint (tips copy their parent), +Y the back of
  // the finger. The back is carried down each finger from the previous joint's +Y (starting at the
  // back of the hand), so it stays on the nail side when a curled phalanx points back up.
  auto orient = [&](int joint, int next, const glm::vec3& back) {
    const glm::vec3 forward = out[next].pose.p - out[joint].pose.p;
    const glm::vec3 z = -glm::normalize(forward);
    glm::vec3 x = glm::cross(back, z);
    x = glm::length(x) < 1e-4f ? glm::vec3(1, 0, 0) : glm::normalize(x);
    const glm::vec3 y = glm::cross(z, x);
    out[joint].pose.q = glm::quat_cast(glm::mat3(x, y, z));
    return y;
  };
  out[XR_HAND_JOINT_PALM_EXT].pose.q = glm::quat(1, 0, 0, 0);
  out[XR_HAND_JOINT_WRIST_EXT].pose.q = glm::quat(1, 0, 0, 0);
  for (int chainStart : {2, 6, 11, 16, 21}) {
    const int last = chainStart == 2 ? 5 : chainStart + 4;
    glm::vec3 back(0, 1, 0);
    for (int j = chainStart; j < last; ++j) back = orient(j, j + 1, back);
    out[last].pose.q = out[last - 1].pose.q;
  }
  for (auto& j : out) j.pose = compose(palm, j.pose);
}

}  // namespace embody::xr_runtime
