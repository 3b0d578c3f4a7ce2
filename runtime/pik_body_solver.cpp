#include "runtime/pik_body_solver.h"

#include <algorithm>

#include "runtime/task_layout.h"

namespace embody::runtime {

PikBinding PikBinding::byTaskNames(const ik::Model& model, const std::array<std::string, tracking::kTrackerCount>& names) {
  PikBinding b;
  for (size_t i = 0; i < names.size(); ++i)
    if (!names[i].empty()) b.targets[i].task = model.findTask(names[i]);
  b.centerOfMass = model.findTask("com");
  return b;
}

void PikBodySolver::runSolve(const SolveRequest& request) {
  ik::SolveOptions options = options_;
  options.clock = request.clock;
  options.deadline = cost_.safeDeadline(request.deadline);
  if (*options.deadline <= request.clock->now()) {
    // Not even one iteration is predicted to fit: run exactly one (progress every frame, an
    // overshoot of at most one iteration), which also refreshes the cost estimate.
    options.deadline.reset();
    options.max_iterations = std::min(options.max_iterations, 1);
  }
  const ik::SolveReport& report = ik::solve(*model_, data_, options);
  cost_.observe(report.elapsed, report.iterations);
}

std::array<float, tracking::kTrackerCount> PikBodySolver::residuals() const {
  const ik::SolveReport& report = data_.report();
  std::array<float, tracking::kTrackerCount> r{-1, -1, -1, -1, -1, -1};
  for (size_t i = 0; i < binding_.targets.size(); ++i) {
    const ik::TaskId t = binding_.targets[i].task;
    if (t >= 0 && static_cast<size_t>(t) < report.tasks.size() && report.tasks[static_cast<size_t>(t)].enabled)
      r[i] = static_cast<float>(report.tasks[static_cast<size_t>(t)].position);
  }
  return r;
}

double PikBodySolver::worstResidual() const {
  const ik::SolveReport& report = data_.report();
  double worst = 0.0;
  for (const auto& t : binding_.targets)
    if (t.task >= 0 && static_cast<size_t>(t.task) < report.tasks.size() && report.tasks[static_cast<size_t>(t.task)].enabled)
      worst = std::max(worst, report.tasks[static_cast<size_t>(t.task)].position);
  return worst;
}

PikBodySolver::PikBodySolver(std::shared_ptr<const ik::Model> model, PikBinding binding, ik::SolveOptions options,
                             PoseWriter writer)
    : model_(std::move(model)),
      binding_(binding),
      options_(options),
      writer_(std::move(writer)),
      data_(*model_),
      initialQ_(data_.q()) {}

void PikBodySolver::resetWarmStart() { (void)data_.setConfiguration(initialQ_); }

SolveResult PikBodySolver::solve(const SolveRequest& request, avatar::SkeletonPose& pose) {
  const tracking::GuardedSample& g = *request.targets;
  for (auto id : tracking::kAllTrackers) {
    const auto i = static_cast<size_t>(tracking::index(id));
    const PikBinding::Target& b = binding_.targets[i];
    if (b.task < 0) continue;
    const float w = statusWeight(g.status[i]);
    const bool on = w > 0.0f && g.pose.trackers[i].valid;
    (void)data_.setEnabled(b.task, on);
    if (b.orientationTask >= 0) (void)data_.setEnabled(b.orientationTask, on);
    if (!on) continue;
    const tracking::TrackerPose& p = g.pose.trackers[i];
    Eigen::Isometry3d tracker = Eigen::Isometry3d::Identity();
    tracker.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
    tracker.linear() = Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z)
                           .normalized()
                           .toRotationMatrix();
    const Eigen::Isometry3d target = binding_.modelFromTracking * tracker * b.trackerToTask;
    const ik::TaskDesc& desc = model_->tasks[static_cast<size_t>(b.task)].desc;
    (void)data_.setWeight(b.task, desc.weight * w);
    switch (desc.type) {
      case ik::TaskType::Pose: (void)data_.setTarget(b.task, target); break;
      case ik::TaskType::Orientation: (void)data_.setTarget(b.task, Eigen::Quaterniond(target.linear())); break;
      default: (void)data_.setTarget(b.task, Eigen::Vector3d(target.translation())); break;
    }
    if (b.orientationTask >= 0) (void)data_.setTarget(b.orientationTask, Eigen::Quaterniond(target.linear()));
  }

  if (binding_.centerOfMass >= 0) {
    // Balance. With tracked feet the performer's own balance is in the targets and a point
    // target for the centre of mass would only fight them: off. Without (head and hands only)
    // the centre of mass goes under the head, where a standing user's is.
    bool feet = false;
    for (auto foot : {tracking::TrackerId::LeftFoot, tracking::TrackerId::RightFoot})
      feet = feet || (g.pose[foot].valid && g[foot] != tracking::TrackerStatus::Absent);
    (void)data_.setEnabled(binding_.centerOfMass, !feet);
    if (!feet) {
      const glm::vec3 head = g.pose[tracking::TrackerId::Head].position;
      (void)data_.setTarget(binding_.centerOfMass, binding_.modelFromTracking * Eigen::Vector3d(head.x, 0.0, head.z));
    }
  }
  runSolve(request);
  SolveResult r;
  r.iterations = data_.report().iterations;
  r.converged = data_.report().converged();
  r.residual = residuals();
  if (restartAboveResidual > 0.0 && worstResidual() > restartAboveResidual && request.clock->now() < request.deadline) {
    const Eigen::VectorXd warm = data_.q();
    const double warmResidual = worstResidual();
    resetWarmStart();
    // Move the free root (if any) by the head target's offset from the rest head.
    const ik::TaskId head = binding_.targets[static_cast<size_t>(tracking::index(tracking::TrackerId::Head))].task;
    const ik::Model::Joint& root = model_->joints.front();
    if (head >= 0 && root.desc.type == ik::JointType::Free && data_.enabled(head)) {
      ik::kinematics(*model_, data_, false);
      Eigen::VectorXd q = data_.q();
      const Eigen::Vector3d shift = data_.targetPosition(head) - data_.taskPosition(head);
      q.segment<3>(root.first_dof) += root.desc.rest.linear().transpose() * shift;
      (void)data_.setConfiguration(q);
    }
    runSolve(request);
    ++restarts_;
    r.iterations += data_.report().iterations;
    if (worstResidual() > warmResidual) {
      (void)data_.setConfiguration(warm);  // the warm start was better after all
      ik::kinematics(*model_, data_, false);  // joint frames for the pose writer
    } else {
      r.converged = data_.report().converged();
      r.residual = residuals();
    }
  }
  if (data_.report().stop == ik::StopReason::InvalidState || !data_.q().allFinite()) {
    resetWarmStart();
    ik::kinematics(*model_, data_, false);
  }
  if (writer_) writer_(*model_, data_, pose);
  return r;
}

}  // namespace embody::runtime
