#include "runtime/avatar_solver.h"

#include "avatar/body/calibration.h"
#include "xr/tracking/body_dimensions.h"

namespace embody::runtime {

namespace {

Eigen::Vector3d toEigen(const glm::vec3& v) { return {v.x, v.y, v.z}; }
glm::vec3 toGlm(const Eigen::Vector3d& v) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}
Eigen::Isometry3d isometry(const tracking::TrackerPose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = toEigen(p.position);
  t.linear() = Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z)
                   .normalized()
                   .toRotationMatrix();
  return t;
}

}  // namespace

Result<AvatarBinding> bindBodyModel(const avatar::BodyModel& body, const avatar::AvatarAsset& avatar) {
  const ik::Model& model = body.model;
  if (body.headTask < 0 || body.leftHandTask < 0 || body.rightHandTask < 0)
    return Error{"the body model has no head and hand tasks (built with addTasks = false?)"};
  // OpenXR axes in the model: +X right = forward x up, +Y up, +Z back.
  const Eigen::Vector3d up = toEigen(avatar.humanoid.up).normalized();
  Eigen::Vector3d forward = toEigen(avatar.humanoid.forward);
  forward = (forward - up * forward.dot(up)).normalized();
  if (!forward.allFinite()) return Error{"the avatar's forward direction is parallel to its up direction"};
  AvatarBinding out;
  PikBinding& b = out.binding;
  b.modelFromTracking = Eigen::Isometry3d::Identity();
  b.modelFromTracking.linear().col(0) = forward.cross(up);
  b.modelFromTracking.linear().col(1) = up;
  b.modelFromTracking.linear().col(2) = -forward;
  const Eigen::Isometry3d trackingFromModel = b.modelFromTracking.inverse();

  ik::Data rest(model);
  ik::kinematics(model, rest, false);
  out.height = avatar::avatarHeight(avatar) * body.scale;
  if (!(out.height > 0.3 && out.height < 3.0)) return Error{"implausible body height " + std::to_string(out.height) + " m"};
  const tracking::BodyDimensions dims = tracking::BodyDimensions::fromHeight(static_cast<float>(out.height));

  auto taskFrame = [&](ik::TaskId t) {
    Eigen::Isometry3d f = Eigen::Isometry3d::Identity();
    f.translation() = rest.taskPosition(t);
    f.linear() = rest.taskOrientation(t).toRotationMatrix();
    return trackingFromModel * f;
  };
  auto bind = [&](tracking::TrackerId id, ik::TaskId task, const tracking::TrackerPose& trackerRest) {
    PikBinding::Target& t = b.targets[static_cast<size_t>(tracking::index(id))];
    t.task = task;
    t.trackerToTask = isometry(trackerRest).inverse() * taskFrame(task);
    out.rest[id] = trackerRest;
  };

  // Head: the eyes, level with the head joint sideways, ahead of it, at eye height.
  {
    const Eigen::Isometry3d head = taskFrame(body.headTask);
    const glm::vec3 eye(static_cast<float>(head.translation().x()), dims.eyeHeight,
                        static_cast<float>(head.translation().z()) - dims.eyeForward);
    bind(tracking::TrackerId::Head, body.headTask, {eye, glm::quat(1, 0, 0, 0), true});
  }
  // Hands: the wrists, grip axes along the forearm.
  for (auto [id, task, joint, side] : {std::tuple{tracking::TrackerId::LeftHand, body.leftHandTask, body.leftHand, tracking::Side::Left},
                                       std::tuple{tracking::TrackerId::RightHand, body.rightHandTask, body.rightHand, tracking::Side::Right}}) {
    const Eigen::Vector3d wrist = trackingFromModel * rest.jointFrame(joint).translation();
    ik::JointId a = model.joints[static_cast<size_t>(joint)].desc.parent;
    while (a >= 0 && (trackingFromModel * rest.jointFrame(a).translation() - wrist).norm() < 1e-4)
      a = model.joints[static_cast<size_t>(a)].desc.parent;
    const Eigen::Vector3d forearm =
        a >= 0 ? Eigen::Vector3d(wrist - trackingFromModel * rest.jointFrame(a).translation()) : Eigen::Vector3d::Zero();
    const Eigen::Vector3d p = taskFrame(task).translation();
    bind(id, task, {toGlm(p), tracking::restGripOrientation(side, toGlm(forearm)), true});
  }
  b.centerOfMass = body.comTask;
  // Feet: the ankles, flat.
  for (auto [id, task] : {std::pair{tracking::TrackerId::LeftFoot, body.leftFootTask},
                          std::pair{tracking::TrackerId::RightFoot, body.rightFootTask}}) {
    if (task < 0) continue;
    bind(id, task, {toGlm(taskFrame(task).translation()), glm::quat(1, 0, 0, 0), true});
  }
  return out;
}

Result<std::unique_ptr<PikBodySolver>> makeAvatarSolver(std::shared_ptr<const avatar::BodyModel> body,
                                                        std::shared_ptr<const avatar::AvatarAsset> avatar,
                                                        const ik::SolveOptions& options) {
  auto binding = bindBodyModel(*body, *avatar);
  if (!binding) return Error{binding.error()};
  std::shared_ptr<const ik::Model> model(body, &body->model);
  PoseWriter writer = [body, avatar](const ik::Model&, const ik::Data& data, avatar::SkeletonPose& pose) {
    avatar::retarget(*body, *avatar, data, pose);
  };
  return std::make_unique<PikBodySolver>(std::move(model), binding->binding, options, std::move(writer));
}

}  // namespace embody::runtime
