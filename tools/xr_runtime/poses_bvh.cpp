// BVH motion capture as a pose source: the head and hands of the captured person, converted to
// OpenXR conventions (metres, +Y up, the performer's rest pose facing -Z).
#include <cmath>
#include <istream>
#include <glm/gtc/constants.hpp>

#include "tools/xr_runtime/runtime.h"

namespace embody::xr_runtime {

namespace {

struct BvhJoint {
  std::string name;
  int parent = -1;
  glm::vec3 offset{0.0f};
  std::vector<int> channels;  // 0..2 position X/Y/Z, 3..5 rotation X/Y/Z, in file order
  int firstChannel = 0;
};

int channelCode(const std::string& c) {
  static const char* names[] = {"Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation"};
  for (int i = 0; i < 6; ++i)
    if (c == names[i]) return i;
  return -1;
}

int findJoint(const std::vector<BvhJoint>& joints, std::initializer_list<const char*> names) {
  for (const char* n : names)
    for (size_t i = 0; i < joints.size(); ++i)
      if (joints[i].name == n) return static_cast<int>(i);
  return -1;
}

// Limits as in the project's BVH loader (avatar/bvh/bvh.h): a hostile file is an error, never
// an allocation its header claims.
constexpr size_t kMaxJoints = 4096;
constexpr size_t kMaxDepth = 256;
constexpr size_t kMaxValues = size_t{64} << 20;  // frames x channels

// HIERARCHY up to and including the MOTION keyword; "" or why it failed.
std::string readHierarchy(std::istream& in, const std::string& name, std::vector<BvhJoint>& joints,
                          int& channelCount) {
  std::vector<int> stack;
  std::string tok;
  bool endSite = false;
  int depthInEndSite = 0;
  in >> tok;
  if (tok != "HIERARCHY") return name + ": not a BVH file (no HIERARCHY)";
  while (in >> tok && tok != "MOTION") {
    if (tok == "ROOT" || tok == "JOINT") {
      if (joints.size() >= kMaxJoints) return name + ": more than " + std::to_string(kMaxJoints) + " joints";
      BvhJoint j;
      in >> j.name;
      j.parent = stack.empty() ? -1 : stack.back();
      joints.push_back(j);
    } else if (tok == "End") {
      in >> tok;  // "Site"
      endSite = true;
    } else if (tok == "{") {
      if (endSite)
        ++depthInEndSite;
      else if (stack.size() >= kMaxDepth)
        return name + ": hierarchy deeper than " + std::to_string(kMaxDepth);
      else
        stack.push_back(static_cast<int>(joints.size()) - 1);
    } else if (tok == "}") {
      if (endSite) {
        endSite = --depthInEndSite > 0;
      } else if (!stack.empty()) {
        stack.pop_back();
      }
    } else if (tok == "OFFSET") {
      glm::vec3 o;
      if (!(in >> o.x >> o.y >> o.z) || !std::isfinite(o.x + o.y + o.z)) return name + ": broken OFFSET";
      if (!endSite && !joints.empty()) joints.back().offset = o;
    } else if (tok == "CHANNELS") {
      int n = 0;
      if (!(in >> n) || n < 0 || n > 6 || joints.empty() || !joints.back().channels.empty())
        return name + ": broken CHANNELS";
      joints.back().firstChannel = channelCount;
      for (int i = 0; i < n; ++i) {
        in >> tok;
        const int c = channelCode(tok);
        if (c < 0) return name + ": unknown channel " + tok;
        joints.back().channels.push_back(c);
      }
      channelCount += n;
    }
  }
  if (tok != "MOTION" || joints.empty()) return name + ": no MOTION section";
  return "";
}

}  // namespace

std::string parseBvhSamples(std::istream& in, const std::string& name, std::vector<BodySample>& out) {
  out.clear();
  std::vector<BvhJoint> joints;
  int channelCount = 0;
  if (std::string e = readHierarchy(in, name, joints, channelCount); !e.empty()) return e;
  int frames = 0;
  double frameTime = 0.0;
  std::string tok;
  in >> tok >> frames >> tok >> tok >> frameTime;  // "Frames:" N "Frame" "Time:" dt
  if (!in || frames <= 0 || !(frameTime > 0.0) || frameTime > 1.0)
    return name + ": broken frame count or frame time";
  if (channelCount == 0) return name + ": no channels";
  if (static_cast<size_t>(frames) > kMaxValues / static_cast<size_t>(channelCount))
    return name + ": " + std::to_string(frames) + " frames of " + std::to_string(channelCount) +
           " channels is more than this reader accepts";
  const int head = findJoint(joints, {"Head", "head", "Neck1", "Neck"});
  const int left = findJoint(joints, {"LeftHand", "LeftWrist", "lhand", "l_hand"});
  const int right = findJoint(joints, {"RightHand", "RightWrist", "rhand", "r_hand"});
  if (head < 0 || left < 0 || right < 0) return name + ": no Head/LeftHand/RightHand joints";

  // Metres: scale so the rest pose's head stands 1.6 m above the root's first-frame height minus
  // the root offset (BVH files come in centimetres, inches or CMU units).
  float restHeadY = 0.0f;
  for (int j = head; j >= 0; j = joints[j].parent) restHeadY += joints[j].offset.y;
  // Values are read as they come (the claim only bounds them), so a short file fails early.
  std::vector<float> values;
  for (size_t i = 0, n = static_cast<size_t>(channelCount) * static_cast<size_t>(frames); i < n; ++i) {
    float v = 0.0f;
    if (!(in >> v) || !std::isfinite(v)) return name + ": broken or short MOTION data";
    values.push_back(v);
  }
  float rootY = 0.0f;
  for (size_t c = 0; c < joints[0].channels.size(); ++c)
    if (joints[0].channels[c] == 1) rootY = values[joints[0].firstChannel + c];
  const float height = restHeadY + rootY;
  if (!(height > 1e-3f) || !std::isfinite(height)) return name + ": the head is not above the root; cannot scale";
  const float scale = 1.6f / height;
  // The performer's rest pose faces +Z (the BVH convention); OpenXR users face -Z.
  const glm::quat turn = glm::angleAxis(glm::pi<float>(), glm::vec3(0, 1, 0));

  // Only the head's and hands' chains are posed (a file may hold thousands of other joints).
  std::vector<char> needed(joints.size(), 0);
  for (int end : {head, left, right})
    for (int j = end; j >= 0 && !needed[j]; j = joints[j].parent) needed[j] = 1;
  std::vector<glm::mat4> global(joints.size());
  out.reserve(static_cast<size_t>(frames));
  for (int f = 0; f < frames; ++f) {
    const float* v = &values[static_cast<size_t>(f) * channelCount];
    for (size_t j = 0; j < joints.size(); ++j) {
      if (!needed[j]) continue;
      glm::vec3 t = joints[j].offset;
      glm::mat4 r(1.0f);
      for (size_t c = 0; c < joints[j].channels.size(); ++c) {
        const float x = v[joints[j].firstChannel + c];
        const int code = joints[j].channels[c];
        if (code < 3)
          t[code] = x + (joints[j].parent < 0 ? 0.0f : joints[j].offset[code]);
        else
          r = r * glm::mat4_cast(glm::angleAxis(glm::radians(x), glm::vec3(code == 3, code == 4, code == 5)));
      }
      glm::mat4 local = r;
      local[3] = glm::vec4(t, 1.0f);
      global[j] = joints[j].parent < 0 ? local : global[joints[j].parent] * local;
    }
    auto tracked = [&](int j) {
      TrackedPose p;
      p.pose.p = turn * (glm::vec3(global[j][3]) * scale);
      const glm::quat q = glm::normalize(glm::quat_cast(glm::mat3(global[j])));
      p.pose.q = glm::normalize(turn * q * glm::conjugate(turn));
      p.valid = std::isfinite(p.pose.p.x + p.pose.p.y + p.pose.p.z) &&
                std::isfinite(p.pose.q.x + p.pose.q.y + p.pose.q.z + p.pose.q.w);
      if (!p.valid) p.pose = Pose{};  // an overflowing chain is lost tracking, never a NaN pose
      return p;
    };
    BodySample s;
    s.t = f * frameTime;
    s.head = tracked(head);
    s.left = tracked(left);
    s.right = tracked(right);
    out.push_back(s);
  }
  return "";
}

}  // namespace embody::xr_runtime
