#include "app/job_inputs.h"

#include <filesystem>

#include "app/avatar_arg.h"
#include "avatar/body/calibration.h"

namespace embody::app {

Result<double> profileArmScale(const avatar::BodyProfile& profile, const std::string& path, const avatar::AvatarAsset& asset,
                               float userHeight) {
  if (!(profile.armSpan > 0.0)) return 1.0;
  // The profile's arm span against this avatar (it may have been calibrated on another one).
  avatar::CalibrationInput ci;
  ci.userHeight = userHeight > 0.0f ? double(userHeight) : profile.userHeight;
  ci.armSpan = profile.armSpan;
  auto onThis = avatar::calibrate(asset, ci);
  if (!onThis) return Error{"profile " + path + ": " + onThis.error()};
  if (!avatar::plausibleArmScale(onThis->armLengthScale))
    return Error{"profile " + path + ": an arm span of " + std::to_string(profile.armSpan) +
                 " m gives arms outside half to twice this avatar's at the user's height"};
  return onThis->armLengthScale;
}

Result<JobInputs> openJobInputs(const RenderJob& job) {
  JobInputs in;
  in.userHeight = job.userHeight;
  std::optional<avatar::BodyProfile> profile;
  if (!job.profile.empty()) {
    auto loaded = avatar::loadProfile(job.profile);  // avatar/body/calibration.h, `embody avatar calibrate`
    if (!loaded) return Error{"profile " + job.profile + ": " + loaded.error()};
    profile = std::move(loaded).value();
    if (in.userHeight == 0.0f) in.userHeight = float(profile->userHeight);
  }
  auto bvhBody = bvhBodyOptions(job.bvh);
  if (!bvhBody) return Error{bvhBody.error()};
  if (isBvhPath(job.avatar) && job.boneMap.empty()) {  // keep the clip: --export writes its hierarchy
    // The --bvh-* overrides describe the --motion file; an --avatar that is that file takes them
    // too (a clip whose axes need them failed as the avatar with a message asking for them).
    tracking::BvhTrackerOptions avatarImport;
    std::error_code ec;
    if (!job.motion.empty() && std::filesystem::equivalent(job.avatar, job.motion, ec)) avatarImport.body = *bvhBody;
    auto bvh = tracking::loadBvhAvatar(job.avatar, avatarImport);
    if (!bvh) return Error{bvh.error()};
    in.asset = bvh->asset;
    in.bvhAvatar = std::move(bvh).value();
  } else {
    auto loaded = loadAvatarArg(job.avatar, job.boneMap);
    if (!loaded) return Error{loaded.error()};
    in.asset = std::move(loaded).value();
  }
  if (profile) {
    auto arms = profileArmScale(*profile, job.profile, in.asset, in.userHeight);
    if (!arms) return Error{arms.error()};
    in.armScale = *arms;
  }
  in.sourceOptions.userHeight = in.userHeight > 0.0f ? in.userHeight : 1.75f;
  in.sourceOptions.bvhScale = job.bvhScale;
  in.sourceOptions.bvh = std::move(*bvhBody);
  if (job.threePoint) in.sourceOptions.trackers = tracking::TrackerMask::threePoint();
  auto opened = tracking::openPoseSource(job.motion, in.sourceOptions);
  if (!opened) return Error{opened.error()};
  in.source = std::move(opened).value();
  return in;
}

runtime::AvatarBodyOptions bodyOptionsFor(const RenderJob& job, const JobInputs& in) {
  runtime::AvatarBodyOptions bo;
  bo.spine = job.spine;
  bo.coupledSpine = job.coupledSpine;
  bo.trackers = in.source->trackers();
  const bool trace = job.motion.size() > 6 && job.motion.substr(job.motion.size() - 6) == ".jsonl";
  bo.userHeight = in.userHeight > 0.0f ? in.userHeight : (trace ? 0.0f : in.sourceOptions.userHeight);
  bo.seat.enabled = job.seated;
  bo.armScale = in.armScale;
  return bo;
}

}  // namespace embody::app
