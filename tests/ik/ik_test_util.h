#pragma once
// Shared fixtures for the IK tests: random models with every joint type, FD helpers.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <catch2/catch.hpp>
#include <random>
#include <stdexcept>
#include <vector>

#include "ik/expmap.h"
#include "ik/model.h"
#include "ik/solver.h"

namespace embody::test {
using namespace embody::ik;  // fixtures for the IK tests: the IK vocabulary throughout

inline Eigen::Isometry3d randomRest(std::mt19937& rng, double reach = 0.3) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = expMapRotation(Eigen::Vector3d(u(rng), u(rng), u(rng)) * 0.8);
  t.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng)) * reach;
  return t;
}

// A chain with every joint type (free root, ball, swing, revolute, fixed, ball) and a branch,
// random rest transforms and masses, and one task of each type. `coupled` adds two equality rows.
inline Model randomAllTypesModel(std::mt19937& rng, bool coupled = false) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ModelBuilder b;
  const JointId root = b.addJoint("root", kNoParent, JointType::Free, randomRest(rng));
  const JointId ball = b.addJoint("ball", root, JointType::Ball, randomRest(rng));
  const JointId swing = b.addJoint("swing", ball, JointType::Swing, randomRest(rng),
                                   Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized());
  const JointId rev = b.addJoint("revolute", swing, JointType::Revolute, randomRest(rng),
                                 Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized());
  const JointId fixed = b.addJoint("fixed", rev, JointType::Fixed, randomRest(rng));
  const JointId ball2 = b.addJoint("ball2", fixed, JointType::Ball, randomRest(rng));
  const JointId tip = b.addJoint("tip", ball2, JointType::Fixed, randomRest(rng));
  const JointId branch = b.addJoint("branch", ball, JointType::Revolute, randomRest(rng),
                                    Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized());
  int k = 0;
  for (JointId j : {root, ball, swing, rev, fixed, ball2, tip, branch})
    b.setSegment(j, 1.0 + 0.5 * (k++ % 3), Eigen::Vector3d(u(rng), u(rng), u(rng)) * 0.1);
  if (coupled) {
    b.addEquality("couple swing-ball2", {swing, 0}, 1.0, {ball2, 1}, -0.7);
    b.addEquality("couple rev-branch", {rev, 0}, 1.0, {branch, 0}, 0.4);
  }
  TaskDesc t;
  t.name = "pos_xz";
  t.type = TaskType::Position;
  t.joint = tip;
  t.axes = kAxisX | kAxisZ;
  t.offset = Eigen::Vector3d(0.05, 0.02, -0.03);
  t.level = 0;
  b.addTask(t);
  t.name = "orient";
  t.type = TaskType::Orientation;
  t.joint = ball2;
  t.level = 1;
  b.addTask(t);
  t.name = "pose";
  t.type = TaskType::Pose;
  t.joint = branch;
  t.level = 1;
  b.addTask(t);
  t.name = "com";
  t.type = TaskType::CenterOfMass;
  t.level = 2;
  b.addTask(t);
  Result<Model> m = b.build();
  if (!m) throw std::runtime_error(m.error());
  return std::move(m).value();
}

inline Eigen::VectorXd randomConfiguration(const Model& model, std::mt19937& rng, double scale = 1.0) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd q(model.dofs);
  for (int i = 0; i < model.dofs; ++i) q(i) = u(rng) * scale;
  return q;
}

// A configuration inside the joint limits (uniform between them, or ±range when unbounded).
inline Eigen::VectorXd randomInsideLimits(const Model& model, std::mt19937& rng, double unbounded_range,
                                          double shrink = 1.0) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::VectorXd q(model.dofs);
  for (const Model::Joint& j : model.joints) {
    for (int k = 0; k < j.dof_count; ++k) {
      double lo = j.desc.lower[k], hi = j.desc.upper[k];
      if (!std::isfinite(lo)) lo = -unbounded_range;
      if (!std::isfinite(hi)) hi = unbounded_range;
      const double mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo) * shrink;
      q(j.first_dof + k) = mid - half + 2 * half * u(rng);
    }
  }
  return q;
}

// Every task's target := its current value in `source` (after kinematics), translated by
// `shift()` (one draw per task).
template <class Shift>
inline void setTargetsToTaskValues(const Model& model, const Data& source, Data& data, Shift shift) {
  for (size_t t = 0; t < model.tasks.size(); ++t) {
    const TaskId id = static_cast<TaskId>(t);
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = source.taskOrientation(id).toRotationMatrix();
    pose.translation() = source.taskPosition(id) + shift();
    if (!data.setTarget(id, pose)) throw std::runtime_error("target");
  }
}

// Targets = the task values of a random configuration inside the limits, optionally pushed by
// `push` metres (normal per axis).
inline void randomTargets(const Model& model, Data& data, std::mt19937& rng, double spread, double push = 0.0,
                          double shrink = 1.0) {
  Data probe(model);
  if (!probe.setConfiguration(randomInsideLimits(model, rng, spread, shrink))) throw std::runtime_error("configuration");
  kinematics(model, probe, false);
  std::normal_distribution<double> g;
  setTargetsToTaskValues(model, probe, data, [&] { return Eigen::Vector3d(push * Eigen::Vector3d(g(rng), g(rng), g(rng))); });
}

// The strict-priority scenario (sample humanoid): from a random configuration inside the limits,
// every task keeps its current value except the left hand, which wants to be 0.5 m further out
// than the arm reaches without moving the feet, CoM and head.
inline void setConflictingReach(const Model& model, Data& data, std::mt19937& rng) {
  if (!data.setConfiguration(randomInsideLimits(model, rng, 0.3, 0.5))) throw std::runtime_error("configuration");
  kinematics(model, data, false);
  setTargetsToTaskValues(model, data, data, [] { return Eigen::Vector3d::Zero(); });
  const TaskId lh = model.findTask("left_hand");
  if (!data.setTarget(lh, data.taskPosition(lh) + Eigen::Vector3d(0.5, 0.3, 0.3))) throw std::runtime_error("target");
}

// What setConflictingReach's solve must show: the feet exact and the head close (second-order drift
// from the lower task's steps is corrected every iteration: what is left is orders of magnitude
// below the lower task's own error), and the conflict real: the hand stays off.
inline void checkConflictingReach(const Model& model, const SolveReport& r) {
  const TaskId lf = model.findTask("left_foot"), rf = model.findTask("right_foot");
  const TaskId lh = model.findTask("left_hand"), head = model.findTask("head");
  CHECK(r.tasks[lf].position < 2e-5);
  CHECK(r.tasks[rf].position < 2e-5);
  CHECK(r.tasks[lf].rotation < 2e-5);
  CHECK(r.tasks[rf].rotation < 2e-5);
  CHECK(r.tasks[head].position < 2e-3);
  CHECK(r.tasks[lh].position > 0.02);
}

inline double equalityViolation(const Model& model, const Eigen::VectorXd& q) {
  if (model.equality_matrix.rows() == 0) return 0.0;
  return (model.equality_matrix * q - model.equality_rhs).cwiseAbs().maxCoeff();
}

// max (c q - rhs) over the inequality rows not listed in `excused`.
inline double worstInequality(const Model& model, const Eigen::VectorXd& q, const std::vector<int>& excused) {
  double worst = -1e300;
  for (size_t i = 0; i < model.inequalities.size(); ++i) {
    if (std::find(excused.begin(), excused.end(), static_cast<int>(i)) != excused.end()) continue;
    double v = -model.inequalities[i].rhs;
    for (const LinearTerm& t : model.inequalities[i].terms) v += t.coefficient * q(model.dofIndex(t.dof));
    worst = std::max(worst, v);
  }
  return worst;
}

// Two revolute joints about z on a short chain (links 0.5 m) and a fixed tip; returns the tip.
inline JointId addTwoJointChain(ModelBuilder& b) {
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  step.translation() = Eigen::Vector3d(0.5, 0, 0);
  const JointId a = b.addJoint("a", kNoParent, JointType::Revolute);
  const JointId c = b.addJoint("b", a, JointType::Revolute, step);
  return b.addJoint("tip", c, JointType::Fixed, step);
}

// The two-joint chain with a point task (x, y) at the tip (position tolerance `tolerance`, the
// TaskDesc default when negative).
inline Model twoJointModel(const std::vector<InequalityRow>& inequalities, const std::vector<EqualityRow>& equalities = {},
                           double tolerance = -1.0) {
  ModelBuilder b;
  const JointId tip = addTwoJointChain(b);
  for (InequalityRow row : inequalities) b.addInequality(row);
  for (EqualityRow row : equalities) b.addEquality(row);
  TaskDesc t;
  t.name = "tip";
  t.joint = tip;
  t.axes = kAxisX | kAxisY;
  if (tolerance >= 0) t.position_tolerance = tolerance;
  b.addTask(t);
  return b.build().value();
}

}  // namespace embody::test
