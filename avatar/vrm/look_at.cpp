// VRM look-at: parsing (1.0 lookAt, 0.x firstPerson) and applying a gaze to eye bones or expressions.
#include "avatar/vrm/vrm_parsers.h"

#include <algorithm>
#include <cmath>

#include "avatar/avatar_asset.h"
#include "avatar/vrm/expressions.h"

namespace embody::avatar {

namespace {

using vrm::Json;
using vrm::member;

glm::quat rotationOf(const glm::mat4& m) {
  return glm::normalize(glm::quat_cast(
      glm::mat3(glm::normalize(glm::vec3(m[0])), glm::normalize(glm::vec3(m[1])), glm::normalize(glm::vec3(m[2])))));
}

LookAtRangeMap readRange(const Json& r, const char* inName, const char* outName, float outputDefault,
                         const std::string& what, std::vector<std::string>& w) {
  LookAtRangeMap m;
  m.outputScale = outputDefault;
  if (r.is_null()) return m;
  m.inputMaxValue = vrm::numberIn(member(r, inName), 90.0f, 1e-3f, 180.0f, what + " " + inName, w);
  m.outputScale = vrm::numberIn(member(r, outName), outputDefault, 0.0f, 180.0f, what + " " + outName, w);
  return m;
}

// A VRM 0.x curve ([time, value, inTangent, outTangent] x n): a positive multiple of four finite
// numbers with strictly increasing times, else empty (linear) with a warning.
std::vector<float> readCurve0(const Json& c, const std::string& what, std::vector<std::string>& w) {
  if (c.is_null()) return {};
  std::vector<float> keys;
  bool ok = c.is_array() && !c.empty() && c.size() % 4 == 0 && c.size() <= 4096;
  for (size_t i = 0; ok && i < c.size(); ++i) {
    ok = c[i].is_number() && std::isfinite(c[i].get<double>()) && std::abs(c[i].get<double>()) < 1e6;
    if (ok) keys.push_back(c[i].get<float>());
    if (ok && i % 4 == 0 && i >= 4) ok = keys[i] > keys[i - 4];
  }
  if (ok) return keys;
  w.push_back(what + " curve: " + c.dump().substr(0, 60) +
              " is not [time, value, inTangent, outTangent] x n with finite numbers and increasing times; read as linear");
  return {};
}

LookAtRangeMap readRange0(const Json& r, float outputDefault, const std::string& what, std::vector<std::string>& w) {
  LookAtRangeMap m = readRange(r, "xRange", "yRange", outputDefault, what, w);
  m.curve = readCurve0(member(r, "curve"), what, w);
  return m;
}

// Model-space axes of the face: forward, up, left (= up x forward).
struct FaceAxes {
  glm::vec3 f, u, l;
};
FaceAxes faceAxes(const LookAtSetup& s) {
  const glm::vec3 f = glm::normalize(s.forward), u(0.0f, 1.0f, 0.0f);
  return {f, u, glm::normalize(glm::cross(u, f))};
}

}  // namespace

float evaluateUnityCurve(std::span<const float> keys, float x) {
  const size_t n = keys.size() / 4;
  if (n == 0) return x;
  if (x <= keys[0]) return keys[1];
  if (x >= keys[4 * (n - 1)]) return keys[4 * (n - 1) + 1];
  size_t k = 0;
  while (x > keys[4 * (k + 1)]) ++k;  // keys[4k] < x <= keys[4(k+1)]
  const float* a = &keys[4 * k];
  const float* b = a + 4;
  const float dt = b[0] - a[0], t = (x - a[0]) / dt, t2 = t * t, t3 = t2 * t;
  return (2 * t3 - 3 * t2 + 1) * a[1] + (t3 - 2 * t2 + t) * dt * a[3] + (t3 - t2) * dt * b[2] + (-2 * t3 + 3 * t2) * b[1];
}

float LookAtRangeMap::map(float degrees) const {
  const float x = std::clamp(degrees, 0.0f, inputMaxValue) / inputMaxValue;
  return outputScale * (curve.empty() ? x : evaluateUnityCurve(curve, x));
}

LookAtSetup parseLookAt(const Json& doc, const AvatarAsset& asset, std::vector<std::string>& w) {
  LookAtSetup s;
  s.head = asset.humanoid.joint(HumanBone::head);
  s.leftEye = asset.humanoid.joint(HumanBone::leftEye);
  s.rightEye = asset.humanoid.joint(HumanBone::rightEye);
  if (glm::length(asset.humanoid.forward) > 0.5f) s.forward = glm::normalize(asset.humanoid.forward);
  const Json& ext = member(doc, "extensions");
  const Json& la1 = member(member(ext, "VRMC_vrm"), "lookAt");
  const Json& fp0 = member(member(ext, "VRM"), "firstPerson");
  std::string type;
  if (la1.is_object()) {
    type = vrm::stringOr(member(la1, "type"), "bone");
    const float out = type == "expression" ? 1.0f : 10.0f;
    s.offsetFromHead = vrm::vec3Of(member(la1, "offsetFromHeadBone"), glm::vec3(0.0f), "lookAt offsetFromHeadBone", w);
    s.horizontalInner = readRange(member(la1, "rangeMapHorizontalInner"), "inputMaxValue", "outputScale", out, "lookAt rangeMapHorizontalInner", w);
    s.horizontalOuter = readRange(member(la1, "rangeMapHorizontalOuter"), "inputMaxValue", "outputScale", out, "lookAt rangeMapHorizontalOuter", w);
    s.verticalDown = readRange(member(la1, "rangeMapVerticalDown"), "inputMaxValue", "outputScale", out, "lookAt rangeMapVerticalDown", w);
    s.verticalUp = readRange(member(la1, "rangeMapVerticalUp"), "inputMaxValue", "outputScale", out, "lookAt rangeMapVerticalUp", w);
  } else if (fp0.is_object()) {
    const std::string t = vrm::stringOr(member(fp0, "lookAtTypeName"), "Bone");
    type = t == "BlendShape" ? "expression" : "bone";
    const float out = type == "expression" ? 1.0f : 10.0f;
    s.offsetFromHead = vrm::vec3Of(member(fp0, "firstPersonBoneOffset"), glm::vec3(0.0f), "firstPersonBoneOffset", w);
    s.offsetFromHead.z = -s.offsetFromHead.z;  // Unity's left-handed z
    s.horizontalInner = readRange0(member(fp0, "lookAtHorizontalInner"), out, "lookAtHorizontalInner", w);
    s.horizontalOuter = readRange0(member(fp0, "lookAtHorizontalOuter"), out, "lookAtHorizontalOuter", w);
    s.verticalDown = readRange0(member(fp0, "lookAtVerticalDown"), out, "lookAtVerticalDown", w);
    s.verticalUp = readRange0(member(fp0, "lookAtVerticalUp"), out, "lookAtVerticalUp", w);
  } else {
    return s;
  }
  if (type != "bone" && type != "expression") {
    w.push_back("lookAt type '" + type.substr(0, 20) + "' is neither bone nor expression; look-at off");
    return s;
  }
  if (s.head < 0) {
    w.push_back("lookAt: no head bone; look-at off");
    return s;
  }
  if (type == "bone" && (s.leftEye < 0 || s.rightEye < 0)) {
    w.push_back("lookAt type bone without leftEye and rightEye bones; look-at off");
    return s;
  }
  s.type = type == "bone" ? LookAtSetup::Type::Bone : LookAtSetup::Type::Expression;
  std::vector<glm::mat4> rest;
  computeGlobals(asset.skeleton, SkeletonPose::rest(asset.skeleton), rest);
  s.headRest = rotationOf(rest[static_cast<size_t>(s.head)]);
  if (s.leftEye >= 0) s.leftEyeRest = rotationOf(rest[static_cast<size_t>(s.leftEye)]);
  if (s.rightEye >= 0) s.rightEyeRest = rotationOf(rest[static_cast<size_t>(s.rightEye)]);
  return s;
}

Gaze gazeTowards(const LookAtSetup& s, const Skeleton& skeleton, std::span<const glm::mat4> globals, glm::vec3 target) {
  Gaze g;
  if (s.type == LookAtSetup::Type::None || s.head < 0 || static_cast<size_t>(s.head) >= globals.size() ||
      globals.size() != skeleton.joints.size())
    return g;
  const glm::mat4& h = globals[static_cast<size_t>(s.head)];
  const glm::vec3 origin(h * glm::vec4(s.offsetFromHead, 1.0f));
  // The direction in the head's rest-aligned frame: undo the head's turn since rest.
  const glm::vec3 d = s.headRest * (glm::inverse(rotationOf(h)) * (target - origin));
  const FaceAxes a = faceAxes(s);
  const float x = glm::dot(d, a.l), y = glm::dot(d, a.u), z = glm::dot(d, a.f);
  if (!std::isfinite(x + y + z) || x * x + y * y + z * z < 1e-12f) return g;
  g.yawDegrees = glm::degrees(std::atan2(x, z));
  g.pitchDegrees = glm::degrees(std::atan2(y, std::sqrt(x * x + z * z)));
  return g;
}

void applyGaze(const LookAtSetup& s, const Skeleton& skeleton, std::span<const glm::mat4> globals, Gaze gaze,
               SkeletonPose& pose, const ExpressionSet& expressions, std::span<float> weights) {
  if (!std::isfinite(gaze.yawDegrees + gaze.pitchDegrees)) return;
  const float yaw = gaze.yawDegrees, pitch = gaze.pitchDegrees;
  if (s.type == LookAtSetup::Type::Expression) {
    auto set = [&](ExpressionPreset p, float v) {
      const int i = expressions.find(p);
      if (i >= 0 && static_cast<size_t>(i) < weights.size()) weights[static_cast<size_t>(i)] = std::clamp(v, 0.0f, 1.0f);
    };
    set(ExpressionPreset::LookLeft, yaw > 0 ? s.horizontalOuter.map(yaw) : 0.0f);
    set(ExpressionPreset::LookRight, yaw < 0 ? s.horizontalOuter.map(-yaw) : 0.0f);
    set(ExpressionPreset::LookUp, pitch > 0 ? s.verticalUp.map(pitch) : 0.0f);
    set(ExpressionPreset::LookDown, pitch < 0 ? s.verticalDown.map(-pitch) : 0.0f);
    return;
  }
  if (s.type != LookAtSetup::Type::Bone || globals.size() != skeleton.joints.size() ||
      pose.local.size() != skeleton.joints.size())
    return;
  const FaceAxes a = faceAxes(s);
  const float eyePitch = pitch > 0 ? s.verticalUp.map(pitch) : -s.verticalDown.map(-pitch);
  // Looking left turns the left eye outwards (away from the nose) and the right eye inwards.
  const float leftYaw = yaw > 0 ? s.horizontalOuter.map(yaw) : -s.horizontalInner.map(-yaw);
  const float rightYaw = yaw > 0 ? s.horizontalInner.map(yaw) : -s.horizontalOuter.map(-yaw);
  const glm::quat headNow = rotationOf(globals[static_cast<size_t>(s.head)]);
  const int eyes[2] = {s.leftEye, s.rightEye};
  const glm::quat rests[2] = {s.leftEyeRest, s.rightEyeRest};
  const float yaws[2] = {leftYaw, rightYaw};
  for (int e = 0; e < 2; ++e) {
    const size_t j = static_cast<size_t>(eyes[e]);
    const glm::quat look = glm::angleAxis(glm::radians(yaws[e]), a.u) * glm::angleAxis(glm::radians(eyePitch), -a.l);
    const glm::quat global = headNow * glm::inverse(s.headRest) * look * rests[e];
    const int parent = skeleton.joints[j].parent;
    const glm::quat parentNow = parent < 0 ? glm::quat(1, 0, 0, 0) : rotationOf(globals[static_cast<size_t>(parent)]);
    pose.local[j].rotation = glm::normalize(glm::inverse(parentNow) * global);
  }
}

}  // namespace embody::avatar
