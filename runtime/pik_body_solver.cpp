#include "runtime/pik_body_solver.h"

#include <algorithm>

#include "runtime/task_layout.h"

namespace embody::runtime {

PikBinding PikBinding::byTaskNames(const ik::Model& model, const std::array<std::string, tracking::kTrackerCount>& names) {
  PikBinding b;
  for (size_t i = 0; i < names.size(); ++i)
    if (!names[i].empty()) b.targets[i].task = model.findTask(names[i]);
  return b;
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
  if (report.stop == ik::StopReason::InvalidState || !data_.q().allFinite()) resetWarmStart();

  SolveResult r;
  r.iterations = report.iterations;
  r.converged = report.converged();
  for (size_t i = 0; i < binding_.targets.size(); ++i) {
    const ik::TaskId t = binding_.targets[i].task;
    if (t >= 0 && static_cast<size_t>(t) < report.tasks.size() && report.tasks[static_cast<size_t>(t)].enabled)
      r.residual[i] = static_cast<float>(report.tasks[static_cast<size_t>(t)].position);
  }
  if (writer_) writer_(*model_, data_, pose);
  return r;
}

}  // namespace embody::runtime
