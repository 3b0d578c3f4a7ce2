#include "avatar/bvh/bvh_writer.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <glm/gtc/constants.hpp>

namespace embody::avatar {

namespace {

template <typename T>
void appendNumber(std::string& out, T v) {
  char buf[40];
  if (v == T(0)) v = T(0);  // no "-0"
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

const char* channelName(BvhChannel c) {
  static const char* kNames[] = {"Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation"};
  return kNames[int(c)];
}

void writeJoint(const BvhClip& clip, size_t j, int depth, std::string& out) {
  const BvhJoint& joint = clip.joints[j];
  const std::string indent(size_t(depth) * 2, ' ');
  if (joint.endSite) {
    out += indent + "End Site\n";
  } else {
    out += indent + (joint.parent < 0 ? "ROOT " : "JOINT ") + joint.name + "\n";
  }
  out += indent + "{\n" + indent + "  OFFSET ";
  for (int k = 0; k < 3; ++k) {
    appendNumber(out, joint.offset[k]);
    out += k < 2 ? " " : "\n";
  }
  if (!joint.endSite) {
    out += indent + "  CHANNELS " + std::to_string(joint.channels.size());
    for (BvhChannel c : joint.channels) out += std::string(" ") + channelName(c);
    out += "\n";
  }
  for (size_t c = j + 1; c < clip.joints.size(); ++c)
    if (clip.joints[c].parent == int(j)) writeJoint(clip, c, depth + 1, out);
  out += indent + "}\n";
}

// The joints in the order the HIERARCHY lists them (depth first from each root), which is the
// order a reader assigns the MOTION columns in. A clip built from a skeleton (an avatar's export)
// may keep its joints in another order, with firstChannel counting in that order.
void hierarchyOrder(const BvhClip& clip, size_t j, std::vector<size_t>& out) {
  out.push_back(j);
  for (size_t c = j + 1; c < clip.joints.size(); ++c)
    if (clip.joints[c].parent == int(j)) hierarchyOrder(clip, c, out);
}

glm::dmat3 axisRotation(int axis, double radians) {
  const double c = std::cos(radians), s = std::sin(radians);
  glm::dmat3 m(1.0);  // column-major: m[col][row]
  const int a = (axis + 1) % 3, b = (axis + 2) % 3;
  m[a][a] = c, m[b][a] = -s, m[a][b] = s, m[b][b] = c;
  return m;
}

}  // namespace

std::string formatBvh(const BvhClip& clip) {
  std::string out = "HIERARCHY\n";
  for (size_t j = 0; j < clip.joints.size(); ++j)
    if (clip.joints[j].parent < 0) writeJoint(clip, j, 0, out);
  out += "MOTION\nFrames: " + std::to_string(clip.frameCount) + "\nFrame Time: ";
  appendNumber(out, clip.frameTime);
  out += "\n";
  std::vector<size_t> order;
  for (size_t j = 0; j < clip.joints.size(); ++j)
    if (clip.joints[j].parent < 0) hierarchyOrder(clip, j, order);
  for (size_t f = 0; f < clip.frameCount; ++f) {
    const auto values = clip.frame(f);
    bool first = true;
    for (size_t j : order) {
      const BvhJoint& joint = clip.joints[j];
      if (joint.endSite) continue;
      for (size_t k = 0; k < joint.channels.size(); ++k) {
        if (!first) out += ' ';
        first = false;
        appendNumber(out, values[size_t(joint.firstChannel) + k]);
      }
    }
    out += "\n";
  }
  return out;
}

Status writeBvh(const BvhClip& clip, const std::string& path) {
  std::ofstream f(path, std::ios::binary);
  if (!f) return Error{"cannot write " + path};
  f << formatBvh(clip);
  f.close();
  if (!f) return Error{"cannot write " + path};
  return Status::success();
}

void eulerForChannels(const glm::dquat& rotation, const BvhChannel channels[3], double degrees[3]) {
  int axis[3];
  for (int k = 0; k < 3; ++k) axis[k] = int(channels[k]) - int(BvhChannel::Xrotation);
  const glm::dmat3 m = glm::mat3_cast(glm::normalize(rotation));
  auto el = [&](int r, int c) { return m[c][r]; };
  const int i = axis[0], j = axis[1], k = axis[2];
  if (i == j || j == k || i == k) {  // fewer than three distinct axes: not a Tait-Bryan order
    degrees[0] = degrees[1] = degrees[2] = 0.0;
    return;
  }
  // R = Ri(a) Rj(b) Rk(c); e = +1 for cyclic (even) orders, -1 otherwise.
  const double e = (j == (i + 1) % 3) ? 1.0 : -1.0;
  const double b = std::asin(std::clamp(e * el(i, k), -1.0, 1.0));
  double a, c;
  if (std::abs(el(i, k)) < 1.0 - 1e-12) {
    a = std::atan2(-e * el(j, k), el(k, k));
    c = std::atan2(-e * el(i, j), el(i, i));
  } else {  // gimbal lock: the whole turn about the first axis, Ri(a) = R Rj(b)^-1
    c = 0.0;
    const glm::dmat3 first = m * glm::transpose(axisRotation(j, b));
    const int p = (i + 1) % 3, q = (i + 2) % 3;
    a = std::atan2(first[p][q], first[p][p]);
  }
  degrees[0] = glm::degrees(a), degrees[1] = glm::degrees(b), degrees[2] = glm::degrees(c);
}

}  // namespace embody::avatar
