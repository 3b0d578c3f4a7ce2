#pragma once
// Shared fixtures for the IK tests: random models with every joint type, FD helpers.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <random>

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

}  // namespace embody::test
