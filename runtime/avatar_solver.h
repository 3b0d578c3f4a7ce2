#pragma once
// The avatar's body model (avatar/body) as the runtime's solver: its tasks bound to trackers,
// calibrated on the avatar's rest pose, and the solved configuration retargeted onto the avatar.
//
// Calibration: for each task the tracker pose the body part has when the avatar stands in its
// rest pose is computed in tracking space (OpenXR axes, from the avatar's humanoid forward/up):
// head = the eyes (kEyeHeightRatio of the height, ahead of the head joint), looking forward;
// hands = the wrists, restGripOrientation along the forearm (as BVH sources do); feet = the
// ankles, flat. `trackerToTask` is the task frame in that tracker frame, so rest trackers give
// the rest pose and every tracker motion is applied to its body part relative to rest.
#include <memory>

#include "avatar/body/body_model.h"
#include "runtime/pik_body_solver.h"

namespace embody::runtime {

struct AvatarBinding {
  PikBinding binding;
  tracking::PoseSample rest;  // the calibration tracker poses (tracking space), valid where bound
  double height = 0.0;        // the body's standing height in metres (avatar height x scale)
};

Result<AvatarBinding> bindBodyModel(const avatar::BodyModel& body, const avatar::AvatarAsset& avatar);

// A PikBodySolver on the body model whose PoseWriter retargets onto `avatar`'s skeleton.
Result<std::unique_ptr<PikBodySolver>> makeAvatarSolver(std::shared_ptr<const avatar::BodyModel> body,
                                                        std::shared_ptr<const avatar::AvatarAsset> avatar,
                                                        const ik::SolveOptions& options = {});

}  // namespace embody::runtime
