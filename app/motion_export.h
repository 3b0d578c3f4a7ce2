#pragma once
// --export FILE.bvh|FILE.glb (`embody render`, `embody xr`): the body actually shown, every frame.
// BVH on the avatar's hierarchy (for a BVH avatar the clip's own hierarchy, names, offsets and
// channel order), glTF binary as the avatar with the motion as an animation.
#include <optional>
#include <string>

#include "avatar/avatar_asset.h"
#include "avatar/gltf/glb_writer.h"
#include "core/result.h"
#include "tracking/bvh_avatar.h"
#include "tracking/bvh_export.h"

namespace embody::app {

bool isGlbPath(const std::string& path);  // ends in .glb
// "" when --export's path names a format it writes, else the usage error.
std::string checkExportPath(const std::string& path);

class MotionExport {
 public:
  // Nothing is recorded for an empty path. `clip`: the BVH the avatar was built from, when it was
  // one (its hierarchy and channels are kept). `frameTime`: seconds per frame (setFrameTime() may
  // change it before write(), e.g. to the headset's measured display period); `frames`: how many
  // to reserve room for (0: unknown, the recording grows).
  void open(const std::string& path, const avatar::AvatarAsset& asset, const tracking::BvhAvatar* clip,
            double frameTime, size_t frames);
  bool active() const { return bvh_.has_value() || glb_.has_value(); }
  void add(const avatar::SkeletonPose& pose);
  size_t frames() const { return frames_; }
  // The clip's own frame time for a BVH avatar (0 otherwise): render warns when --fps differs.
  double clipFrameTime() const { return clipFrameTime_; }
  void setFrameTime(double seconds);
  Status write(const avatar::AvatarAsset& asset) const;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::optional<tracking::SolvedMotionBvh> bvh_;
  std::optional<avatar::GlbAnimation> glb_;
  size_t frames_ = 0;
  double clipFrameTime_ = 0.0;
};

}  // namespace embody::app
