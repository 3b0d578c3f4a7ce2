#pragma once
// The runtime's BodySolver on top of the prioritized IK solver (ik): guarded tracker
// targets become task targets, the solve runs warm-started against the frame's deadline, and an
// optional writer turns the solved configuration into the avatar's SkeletonPose (retargeting,
// owned by the body model).
//
// Deadline: ik::solve checks "now >= deadline" before each iteration, which alone would end up
// to one iteration late. This adapter hands it the frame deadline minus the predicted cost of
// one iteration (IterationCostModel, learnt from earlier solves), so the solve ends before the
// deadline while iteration costs stay as measured.
#include <Eigen/Geometry>
#include <functional>
#include <memory>

#include "ik/model.h"
#include "ik/solver.h"
#include "runtime/body_solver.h"

namespace embody::runtime {

struct PikBinding {
  struct Target {
    ik::TaskId task = -1;             // Pose, Position or Orientation task driven by the tracker
    ik::TaskId orientationTask = -1;  // a separate Orientation task when `task` is a Position one
    // The task frame expressed in the tracker frame (e.g. the head joint relative to the eyes).
    Eigen::Isometry3d trackerToTask = Eigen::Isometry3d::Identity();
  };
  std::array<Target, tracking::kTrackerCount> targets{};
  // The centre-of-mass task (balance), -1 for none. Off while feet are tracked (the performer's
  // balance is in their targets); otherwise its target is the point under the head target.
  ik::TaskId centerOfMass = -1;
  // Tracking space (OpenXR: +Y up, -Z forward, +X right) to the model's world frame; e.g. a
  // rotation of 180 degrees about Y for a model facing +Z with +X to its left.
  Eigen::Isometry3d modelFromTracking = Eigen::Isometry3d::Identity();

  // Binds each tracker to the task of the given name ("" or a missing name: not driven).
  static PikBinding byTaskNames(const ik::Model& model,
                                const std::array<std::string, tracking::kTrackerCount>& names = {
                                    "head", "left_hand", "right_hand", "hips", "left_foot", "right_foot"});
};

// Writes the solved configuration into the avatar's pose (joint count already right).
using PoseWriter = std::function<void(const ik::Model&, const ik::Data&, avatar::SkeletonPose&)>;

class PikBodySolver final : public BodySolver {
 public:
  PikBodySolver(std::shared_ptr<const ik::Model> model, PikBinding binding, ik::SolveOptions options = {},
                PoseWriter writer = {});

  // A warm start can lead the solver into a configuration it does not leave (a folded spine, a
  // limb caught at its limits) while the targets stay reachable. When a bound task ends farther
  // than this from its target, the solver restarts from the initial configuration (its root moved
  // under the head target) within the same deadline, and keeps the better of the two.
  double restartAboveResidual = 0.1;  // metres; <= 0 disables
  int restarts() const { return restarts_; }

  SolveResult solve(const SolveRequest& request, avatar::SkeletonPose& pose) override;
  void resetWarmStart() override;

  const ik::Model& model() const { return *model_; }
  const ik::Data& data() const { return data_; }
  const ik::SolveReport& lastReport() const { return data_.report(); }
  const IterationCostModel& costModel() const { return cost_; }

 private:
  std::shared_ptr<const ik::Model> model_;
  PikBinding binding_;
  ik::SolveOptions options_;
  PoseWriter writer_;
  ik::Data data_;
  Eigen::VectorXd initialQ_;
  IterationCostModel cost_;
  int restarts_ = 0;

  double worstResidual() const;
  std::array<float, tracking::kTrackerCount> residuals() const;
  void runSolve(const SolveRequest& request);
};

}  // namespace embody::runtime
