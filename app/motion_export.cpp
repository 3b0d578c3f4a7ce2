#include "app/motion_export.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <system_error>

#include "app/avatar_arg.h"

namespace embody::app {

bool isGlbPath(const std::string& path) { return path.size() > 4 && path.substr(path.size() - 4) == ".glb"; }

std::string checkExportPath(const std::string& path) {
  if (path.empty()) return "";
  if (!isBvhPath(path) && !isGlbPath(path)) return "--export writes FILE.bvh or FILE.glb: " + path;
  // The file is written when the run ends: a folder that is missing or read-only is reported now,
  // not after a whole session (an `embody xr` session's motion was lost that way).
  const std::filesystem::path folder = std::filesystem::absolute(path).parent_path();
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec)) return "--export " + path + ": the folder " + folder.string() + " does not exist";
  if (::access(folder.c_str(), W_OK) != 0) return "--export " + path + ": the folder " + folder.string() + " is not writable";
  return "";
}

namespace {
// Frames reserved up front (a minute at 90 Hz is 5400): a longer run grows the buffer as it
// goes; reserving what --frames asked (10^8) failed with std::bad_alloc before the session began.
constexpr size_t kReservedExportFrames = 100000;
}  // namespace

void MotionExport::open(const std::string& path, const avatar::AvatarAsset& asset, const tracking::BvhAvatar* clip,
                        double frameTime, size_t frames) {
  path_ = path;
  if (isGlbPath(path)) {
    glb_.emplace();
    glb_->frameTime = frameTime;
    glb_->frames.reserve(std::min(frames, kReservedExportFrames));
  } else if (isBvhPath(path)) {
    bvh_ = clip ? tracking::SolvedMotionBvh::forBvhAvatar(*clip) : tracking::SolvedMotionBvh::forAvatar(asset, frameTime);
    clipFrameTime_ = clip ? bvh_->clip().frameTime : 0.0;
    // The clip's own frame time, to the digit, when the run keeps its rate.
    if (!clip || std::abs(clipFrameTime_ / frameTime - 1.0) > 1e-6) bvh_->setFrameTime(frameTime);
    bvh_->reserve(std::min(frames, kReservedExportFrames));
  }
}

void MotionExport::add(const avatar::SkeletonPose& pose) {
  if (bvh_) bvh_->add(pose);
  if (glb_) glb_->frames.push_back(pose);
  frames_ += active() ? 1 : 0;
}

void MotionExport::setFrameTime(double seconds) {
  if (bvh_) bvh_->setFrameTime(seconds);
  if (glb_) glb_->frameTime = seconds;
}

Status MotionExport::write(const avatar::AvatarAsset& asset) const {
  if (bvh_)
    if (auto s = bvh_->write(path_); !s) return s;
  if (glb_)
    if (auto s = avatar::writeGlbFile(asset, path_, &*glb_); !s) return Error{"--export " + path_ + ": " + s.error()};
  return {};
}

}  // namespace embody::app
