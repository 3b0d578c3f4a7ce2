#include "app/job_inputs.h"

#include "app/avatar_arg.h"
#include "avatar/body/calibration.h"

namespace embody::app {

Result<JobInputs> openJobInputs(const RenderJob& job) {
  JobInputs in;
  in.userHeight = job.userHeight;
  if (in.userHeight == 0.0f && !job.profile.empty()) {
    auto profile = avatar::loadProfile(job.profile);  // avatar/body/calibration.h, `embody avatar calibrate`
    if (!profile) return Error{"profile " + job.profile + ": " + profile.error()};
    in.userHeight = float(profile->userHeight);
  }
  if (isBvhPath(job.avatar) && job.boneMap.empty()) {  // keep the clip: --export writes its hierarchy
    auto bvh = tracking::loadBvhAvatar(job.avatar, {});
    if (!bvh) return Error{bvh.error()};
    in.asset = bvh->asset;
    in.bvhAvatar = std::move(bvh).value();
  } else {
    auto loaded = loadAvatarArg(job.avatar, job.boneMap);
    if (!loaded) return Error{loaded.error()};
    in.asset = std::move(loaded).value();
  }
  in.sourceOptions.userHeight = in.userHeight > 0.0f ? in.userHeight : 1.75f;
  in.sourceOptions.bvhScale = job.bvhScale;
  auto bvh = bvhBodyOptions(job.bvh);
  if (!bvh) return Error{bvh.error()};
  in.sourceOptions.bvh = std::move(*bvh);
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
  return bo;
}

}  // namespace embody::app
