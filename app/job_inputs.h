#pragma once
// What `embody render --motion` and `embody mirror` both open before any GPU or window work:
// the user's height (--user-height, else the --profile's), the avatar, the pose source, and the
// body solver's options. Files first: bad files are the likely errors and need no device.
#include <memory>
#include <optional>

#include "app/render_job.h"
#include "avatar/avatar_asset.h"
#include "avatar/body/calibration.h"
#include "core/result.h"
#include "runtime/avatar_body_solver.h"
#include "tracking/bvh_avatar.h"
#include "tracking/pose_source.h"

namespace embody::app {

struct JobInputs {
  float userHeight = 0.0f;  // 0: unknown (calibrate from the first head sample)
  double armScale = 1.0;    // the profile's arm span on this avatar (AvatarBodyOptions::armScale)
  avatar::AvatarAsset asset;
  tracking::SourceOptions sourceOptions;  // sourceOptions.userHeight: what the motion is fitted to
  std::unique_ptr<tracking::PoseSource> source;
  // --avatar CLIP.bvh: the clip behind the avatar (its hierarchy for --export), else empty.
  std::optional<tracking::BvhAvatar> bvhAvatar;
};

// Errors (exit code 1) name the file that failed.
Result<JobInputs> openJobInputs(const RenderJob& job);

// AvatarBodyOptions::armScale for a profile (`embody avatar calibrate --arm-span`) on `asset`:
// 1 without an arm span; an error naming `path` when the arms come out beyond half or twice the
// avatar's.
Result<double> profileArmScale(const avatar::BodyProfile& profile, const std::string& path, const avatar::AvatarAsset& asset,
                               float userHeight);

// The body solver's options for the job. Synthetic motions and BVH clips are built for (fitted
// to) sourceOptions.userHeight; a recorded trace's user is unknown unless given: the solver
// calibrates from its first head sample.
runtime::AvatarBodyOptions bodyOptionsFor(const RenderJob& job, const JobInputs& in);

}  // namespace embody::app
