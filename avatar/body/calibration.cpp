#include "avatar/body/calibration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <span>
#include <sstream>
#include <tuple>

namespace embody::avatar {
bool plausibleArmScale(double ratio) { return std::isfinite(ratio) && ratio >= kMinArmScale && ratio <= kMaxArmScale; }

bool plausibleBodyHeight(double metres) {
  return std::isfinite(metres) && metres >= kMinBodyHeight && metres <= kMaxBodyHeight;
}

std::string bodyHeightRange() {
  char text[48];
  std::snprintf(text, sizeof text, "%.1f .. %.1f m", kMinBodyHeight, kMaxBodyHeight);
  return text;
}

namespace {

bool plausible(double metres) { return plausibleBodyHeight(metres); }

}  // namespace

namespace {

// The head rule: the head joint's height above the lowest joint over 0.91.
double skeletonHeight(const AvatarAsset& avatar, const std::vector<glm::mat4>& globals) {
  const glm::vec3 up = avatar.humanoid.up;
  const int head = avatar.humanoid.joint(HumanBone::head);
  if (head < 0 || static_cast<size_t>(head) >= globals.size()) return 0.0;
  float lo = INFINITY;
  for (const auto& g : globals) lo = std::min(lo, glm::dot(glm::vec3(g[3]), up));
  return static_cast<double>(glm::dot(glm::vec3(globals[static_cast<size_t>(head)][3]), up) - lo) / 0.91;
}

std::vector<glm::mat4> restGlobalsOf(const AvatarAsset& avatar) {
  std::vector<glm::mat4> globals;
  computeGlobals(avatar.skeleton, SkeletonPose::rest(avatar.skeleton), globals);
  return globals;
}

}  // namespace

double avatarHeight(const AvatarAsset& avatar) {
  const glm::vec3 up = avatar.humanoid.up;
  const std::vector<glm::mat4> globals = restGlobalsOf(avatar);
  if (!avatar.mesh.vertices.empty()) {
    std::vector<glm::mat4> palette;
    computeSkinningPalette(avatar, globals, palette);
    std::vector<glm::vec3> pos, nrm;
    skinOnCpu(avatar.mesh, palette, pos, nrm);
    float lo = INFINITY, hi = -INFINITY;
    for (const auto& p : pos) {
      lo = std::min(lo, glm::dot(p, up));
      hi = std::max(hi, glm::dot(p, up));
    }
    return static_cast<double>(hi - lo);
  }
  return skeletonHeight(avatar, globals);
}

Result<double> measureAvatarHeight(const AvatarAsset& avatar) {
  auto plausibleAvatar = [](double metres) {
    return std::isfinite(metres) && metres >= kMinAvatarHeight && metres <= kMaxAvatarHeight;
  };
  const double h = avatarHeight(avatar);
  if (plausibleAvatar(h)) return h;
  // A mesh on part of the body only (a floating head, a bust) with a skeleton of human size:
  // the skeleton's height. A mesh of no size (under 5 cm) is not such a part.
  if (!avatar.mesh.vertices.empty() && h >= 0.05 && h < kMinAvatarHeight)
    if (const double s = skeletonHeight(avatar, restGlobalsOf(avatar)); plausibleAvatar(s)) return s;
  char text[320];
  if (!std::isfinite(h) || h < 0.001) {
    std::snprintf(text, sizeof text,
                  "cannot measure the avatar's height: it stands %.3g m tall at rest (an avatar is taken to be %g "
                  "to %g m tall); its mesh has no size, or without a mesh its skeleton has none",
                  std::isfinite(h) && h >= 1e-6 ? h : 0.0, kMinAvatarHeight, kMaxAvatarHeight);
    return Error{text};
  }
  // The likely mistake: the power of ten (or inch) that brings the avatar nearest 1.7 m.
  struct Unit {
    double scale;  // the root node scale that would fix it
    const char* what;
  };
  static constexpr Unit kTooTall[] = {
      {0.01, "are its units centimetres"}, {0.001, "are its units millimetres"},
      {0.1, "are its units decimetres"},   {0.0254, "are its units inches"}};
  static constexpr Unit kTooSmall[] = {{10.0, "is it 10 times too small"},
                                       {100.0, "is it 100 times too small (scaled to metres twice)"},
                                       {1000.0, "is it 1000 times too small"}};
  const auto units = h > kMaxAvatarHeight ? std::span<const Unit>(kTooTall) : std::span<const Unit>(kTooSmall);
  const Unit* best = &units[0];
  for (const Unit& u : units)
    if (std::abs(std::log(h * u.scale / 1.7)) < std::abs(std::log(h * best->scale / 1.7))) best = &u;
  std::snprintf(text, sizeof text,
                "the avatar is %.4g m tall (an avatar is taken to be %g to %g m tall): %s? Fix the file (a root "
                "node scale of %g makes it %.2f m tall) or export it in metres",
                h, kMinAvatarHeight, kMaxAvatarHeight, best->what, best->scale, h * best->scale);
  return Error{text};
}

Result<BodyProfile> calibrate(const AvatarAsset& avatar, const CalibrationInput& in) {
  BodyProfile p;
  p.avatar = avatar.sourcePath.empty() ? "default" : avatar.sourcePath;
  auto height = measureAvatarHeight(avatar);
  if (!height) return Error{height.error()};
  p.avatarHeight = *height;
  if (in.userHeight) {
    if (!plausible(*in.userHeight)) return Error{"user height must be between 0.5 and 2.6 m"};
    p.userHeight = *in.userHeight;
    p.eyeHeight = kEyeHeightRatio * p.userHeight;
  } else if (in.eyeHeight) {
    if (!plausible(*in.eyeHeight / kEyeHeightRatio))
      return Error{"eye height must be between 0.47 and 2.4 m"};
    p.eyeHeight = *in.eyeHeight;
    p.userHeight = p.eyeHeight / kEyeHeightRatio;
  } else {
    return Error{"calibration needs the user's height or eye height"};
  }
  p.scale = p.userHeight / p.avatarHeight;
  // Arm span of the avatar: both arm chains (shoulder -> hand) plus the hands and the shoulder width.
  const HumanoidMap& h = avatar.humanoid;
  double avatarArms = 0.0;  // both arms, shoulder to wrist, at rest
  if (h.usable()) {
    std::vector<glm::mat4> g;
    computeGlobals(avatar.skeleton, SkeletonPose::rest(avatar.skeleton), g);
    auto at = [&](HumanBone b) { return glm::vec3(g[static_cast<size_t>(h.joint(b))][3]); };
    const double left = glm::length(at(HumanBone::leftLowerArm) - at(HumanBone::leftUpperArm)) +
                        glm::length(at(HumanBone::leftHand) - at(HumanBone::leftLowerArm));
    const double right = glm::length(at(HumanBone::rightLowerArm) - at(HumanBone::rightUpperArm)) +
                         glm::length(at(HumanBone::rightHand) - at(HumanBone::rightLowerArm));
    const double shoulders = glm::length(at(HumanBone::leftUpperArm) - at(HumanBone::rightUpperArm));
    p.avatarArmSpan =
        left + right + shoulders + 2.0 * 0.108 * p.avatarHeight;  // hand length ~10.8 % of height
    avatarArms = left + right;
  }
  if (in.armSpan) {
    if (!plausible(*in.armSpan)) return Error{"arm span must be between 0.5 and 2.6 m"};
    p.armSpan = *in.armSpan;
    if (p.avatarArmSpan > 0.0) p.armScale = p.armSpan / (p.avatarArmSpan * p.scale);
    if (avatarArms > 0.0) p.armLengthScale = std::max(0.0, 1.0 + (p.armSpan - p.avatarArmSpan * p.scale) / (avatarArms * p.scale));
  }
  return p;
}

Status saveProfile(const BodyProfile& p, const std::string& path) {
  nlohmann::json j = {{"version", 1},
                      {"avatar", p.avatar},
                      {"user_height_m", p.userHeight},
                      {"eye_height_m", p.eyeHeight},
                      {"arm_span_m", p.armSpan > 0.0 ? nlohmann::json(p.armSpan) : nlohmann::json(nullptr)},
                      {"avatar_height_m", p.avatarHeight},
                      {"avatar_arm_span_m", p.avatarArmSpan},
                      {"scale", p.scale},
                      {"arm_scale", p.armScale}};
  std::ofstream f(path);
  if (!f) return Error{"cannot write profile '" + path + "'"};
  f << j.dump(2) << "\n";
  if (!f) return Error{"cannot write profile '" + path + "'"};
  return {};
}

Result<BodyProfile> loadProfile(const std::string& path) {
  std::ifstream f(path);
  if (!f) return Error{"cannot open profile '" + path + "'"};
  std::stringstream ss;
  ss << f.rdbuf();
  return parseProfile(ss.str(), path);
}

Result<BodyProfile> parseProfile(std::string_view text, const std::string& path) {
  const auto j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return Error{"profile '" + path + "' is not a JSON object"};
  auto number = [&](const char* key, double& out, bool required) -> Status {
    if (!j.contains(key) || j[key].is_null()) {
      if (required) return Error{"profile '" + path + "': missing " + key};
      return {};
    }
    if (!j[key].is_number() || !std::isfinite(j[key].get<double>()))
      return Error{"profile '" + path + "': " + key + " must be a number"};
    out = j[key].get<double>();
    return {};
  };
  BodyProfile p;
  if (j.contains("avatar") && j["avatar"].is_string()) p.avatar = j["avatar"].get<std::string>();
  for (auto [key, out, required] :
       {std::tuple{"user_height_m", &p.userHeight, true}, std::tuple{"eye_height_m", &p.eyeHeight, false},
        std::tuple{"arm_span_m", &p.armSpan, false}, std::tuple{"avatar_height_m", &p.avatarHeight, false},
        std::tuple{"avatar_arm_span_m", &p.avatarArmSpan, false}, std::tuple{"scale", &p.scale, true},
        std::tuple{"arm_scale", &p.armScale, false}})
    if (auto s = number(key, *out, required); !s.ok()) return Error{s.error()};
  if (!plausible(p.userHeight))
    return Error{"profile '" + path + "': user_height_m must be between 0.5 and 2.6"};
  if (!(p.scale > 0.05 && p.scale < 20.0))
    return Error{"profile '" + path + "': scale must be between 0.05 and 20"};
  return p;
}

}  // namespace embody::avatar
