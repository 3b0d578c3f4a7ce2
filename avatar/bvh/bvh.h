#pragma once
// BVH motion capture (Biovision Hierarchy): the skeleton (HIERARCHY: joints, OFFSETs, CHANNELS
// in any order) and the MOTION frames, parsed into immutable data plus forward kinematics.
// Import code only: the tracking side (tracking/bvh_source.h) turns a clip into trackers.
//
// Robust against broken files: every error names the line; nothing is allocated beyond the
// limits below, whatever the file declares.
//
// Conventions kept from the file (no unit or axis conversion here): local transform of a joint
//   T(offset + [Xposition, Yposition, Zposition]) * R(c1) * R(c2) * R(c3)
// with the rotation channels multiplied in the order they are listed (ZYX -> Rz * Ry * Rx),
// angles in degrees.
#include <cstdint>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/result.h"

namespace embody::avatar {

enum class BvhChannel : uint8_t { Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation };

struct BvhJoint {
  std::string name;  // "End Site" children are named "<parent>_End"
  int parent = -1;   // index into BvhClip::joints, < this joint's index
  glm::dvec3 offset{0.0};
  std::vector<BvhChannel> channels;  // at most 6
  int firstChannel = 0;              // index of channels[0] in a frame's values
  bool endSite = false;
};

struct BvhLimits {
  size_t maxJoints = 4096;
  size_t maxDepth = 256;
  size_t maxValues = size_t{64} << 20;  // frames x channels (256 MiB of floats)
};

struct BvhClip {
  std::vector<BvhJoint> joints;  // parents before children
  int channelCount = 0;          // values per frame
  double frameTime = 0.0;        // seconds
  size_t frameCount = 0;
  std::vector<float> values;  // frameCount * channelCount
  std::vector<std::string> warnings;

  std::span<const float> frame(size_t i) const {
    return {values.data() + i * static_cast<size_t>(channelCount), static_cast<size_t>(channelCount)};
  }
  double duration() const { return frameCount > 1 ? static_cast<double>(frameCount - 1) * frameTime : 0.0; }
  int find(std::string_view name) const;  // -1 when absent
};

Result<BvhClip> parseBvh(std::string_view text, const std::string& name, const BvhLimits& limits = {});
Result<BvhClip> loadBvh(const std::string& path, const BvhLimits& limits = {});

struct BvhGlobal {
  glm::dvec3 position{0.0};
  glm::dquat rotation{1.0, 0.0, 0.0, 0.0};
};

// The clip mirrored across its X axis (x -> -x): a left-handed file read as the right-handed
// performance it records. Exact for any channel order: offsets and X positions change sign, and so
// do the Y and Z rotation angles (a mirror keeps the turn about X and reverses the others).
void mirrorBvhClip(BvhClip& clip);

// Global transforms of every joint for one frame's values; an empty span gives the rest pose
// (every channel zero). `out` is resized to the joint count.
void bvhGlobals(const BvhClip& clip, std::span<const float> frame, std::vector<BvhGlobal>& out);

}  // namespace embody::avatar
