#include "runtime/skeleton_pose_job.h"

namespace embody::runtime {

bool SkeletonPoseJob::Validate() const {
  if (!body || !avatar || !data || !pose) return false;
  const size_t joints = avatar->skeleton.joints.size();
  return data->q().size() == body->model.dofs && pose->local.size() == joints && body->ikJointOfAvatar.size() == joints;
}

bool SkeletonPoseJob::Run() const {
  if (!Validate()) return false;
  avatar::retarget(*body, *avatar, *data, *pose);
  return true;
}

}  // namespace embody::runtime
