// Analytic Jacobians (position, orientation, pose, CoM) against central finite differences for
// every joint type, including exponential-map rotations near |v| = π.
#include <catch2/catch.hpp>

#include <numbers>

#include "ik/expmap.h"
#include "tests/support/sample_models.h"
#include "ik_test_util.h"

using namespace embody;
using namespace embody::ik;

namespace {

// The stacked task values the Jacobian differentiates: selected position axes, CoM on the ground;
// rotations are compared through finite-difference angular velocities.
Eigen::MatrixXd numericJacobian(const Model& model, Data& data, const Eigen::VectorXd& q, double h) {
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(model.task_rows, model.dofs);
  for (int d = 0; d < model.dofs; ++d) {
    Eigen::VectorXd qp = q, qm = q;
    qp(d) += h;
    qm(d) -= h;
    REQUIRE(data.setConfiguration(qp));
    kinematics(model, data, false);
    std::vector<Eigen::Vector3d> pp;
    std::vector<Eigen::Quaterniond> rp;
    for (size_t t = 0; t < model.tasks.size(); ++t) {
      pp.push_back(data.taskPosition(static_cast<TaskId>(t)));
      rp.push_back(data.taskOrientation(static_cast<TaskId>(t)));
    }
    REQUIRE(data.setConfiguration(qm));
    kinematics(model, data, false);
    for (size_t t = 0; t < model.tasks.size(); ++t) {
      const Model::Task& task = model.tasks[t];
      const Eigen::Vector3d dp = (pp[t] - data.taskPosition(static_cast<TaskId>(t))) / (2 * h);
      const Eigen::Matrix3d rm = data.taskOrientation(static_cast<TaskId>(t)).toRotationMatrix();
      const Eigen::Vector3d w = rotationLog(rp[t].toRotationMatrix() * rm.transpose()) / (2 * h);
      int r = task.first_row;
      switch (task.desc.type) {
        case TaskType::Position:
          for (int k = 0; k < 3; ++k)
            if (task.desc.axes & (1 << k)) j(r++, d) = dp(k);
          break;
        case TaskType::Orientation: j.block<3, 1>(r, d) = w; break;
        case TaskType::Pose:
          j.block<3, 1>(r, d) = dp;
          j.block<3, 1>(r + 3, d) = w;
          break;
        case TaskType::CenterOfMass: j.block<2, 1>(r, d) = model.ground_axes.transpose() * dp; break;
      }
      // Non-recruited columns are zero in the analytic Jacobian by design.
      const int joint = [&] {
        for (size_t i = 0; i < model.joints.size(); ++i)
          if (d >= model.joints[i].first_dof && d < model.joints[i].first_dof + model.joints[i].dof_count)
            return static_cast<int>(i);
        return 0;
      }();
      if (!task.recruited[joint]) j.block(task.first_row, d, task.rows, 1).setZero();
    }
  }
  REQUIRE(data.setConfiguration(q));
  return j;
}

void checkJacobian(const Model& model, const Eigen::VectorXd& q, double tol) {
  Data data(model);
  REQUIRE(data.setConfiguration(q));
  kinematics(model, data, true);
  const Eigen::MatrixXd analytic = taskJacobian(data);
  const Eigen::MatrixXd numeric = numericJacobian(model, data, q, 1e-6);
  INFO("analytic\n" << analytic << "\nnumeric\n" << numeric);
  CHECK((analytic - numeric).cwiseAbs().maxCoeff() < tol);
}

}  // namespace

TEST_CASE("exponential map: left Jacobian matches finite differences of exp, including near pi") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (double radius : {0.0, 1e-5, 0.3, 1.5, std::numbers::pi - 1e-3, std::numbers::pi, std::numbers::pi + 1e-3, 4.0}) {
    for (int trial = 0; trial < 5; ++trial) {
      Eigen::Vector3d v = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized() * radius;
      const Eigen::Matrix3d jl = leftJacobian(v);
      for (int k = 0; k < 3; ++k) {
        const double h = 1e-6;
        Eigen::Vector3d vp = v, vm = v;
        vp(k) += h;
        vm(k) -= h;
        const Eigen::Vector3d w = rotationLog(expMapRotation(vp) * expMapRotation(vm).transpose()) / (2 * h);
        INFO("radius " << radius << " component " << k);
        CHECK((w - jl.col(k)).norm() < 1e-7);
      }
    }
  }
}

TEST_CASE("exponential map: re-parameterisation keeps the rotation and brings |v| below pi") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (double radius : {std::numbers::pi + 1e-6, 3.5, 5.0, 6.0}) {
    Eigen::Vector3d v = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized() * radius;
    const Eigen::Matrix3d r = expMapRotation(v);
    REQUIRE(reparameterizeExpMap(v));
    CHECK(v.norm() < std::numbers::pi);
    CHECK((expMapRotation(v) - r).norm() < 1e-12);
  }
  Eigen::Vector3d small(0.1, 0.2, 0.3);
  CHECK_FALSE(reparameterizeExpMap(small));
}

TEST_CASE("Jacobians of every task type match central differences for every joint type") {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const Model model = test::randomAllTypesModel(rng, trial % 2 == 1);
    checkJacobian(model, test::randomConfiguration(model, rng, 1.2), 1e-6);
  }
}

TEST_CASE("Jacobians stay exact with exp-map joints near |v| = pi") {
  std::mt19937 rng(5);
  for (double radius : {std::numbers::pi - 1e-3, std::numbers::pi, std::numbers::pi + 1e-3}) {
    const Model model = test::randomAllTypesModel(rng);
    Eigen::VectorXd q = test::randomConfiguration(model, rng, 0.5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (const char* name : {"root", "ball", "swing", "ball2"}) {
      const Model::Joint& j = model.joints[model.findJoint(name)];
      const int first = j.first_dof + (j.desc.type == JointType::Free ? 3 : 0);
      const int count = j.desc.type == JointType::Swing ? 2 : 3;
      Eigen::VectorXd v(count);
      for (int k = 0; k < count; ++k) v(k) = u(rng);
      q.segment(first, count) = v.normalized() * radius;
    }
    INFO("radius " << radius);
    checkJacobian(model, q, 2e-6);
  }
}

TEST_CASE("Jacobians of the sample humanoid and coupled spine match central differences") {
  std::mt19937 rng(2);
  const Model humanoid = test::sampleHumanoid().value();
  CHECK(humanoid.dofs == 61);
  CHECK(humanoid.task_rows == 32);
  CHECK(humanoid.levels.size() == 4);
  checkJacobian(humanoid, test::randomInsideLimits(humanoid, rng, 1.0), 1e-6);
  const Model spine = test::sampleSpine(true).value();
  CHECK(spine.dofs == 42);
  checkJacobian(spine, test::randomInsideLimits(spine, rng, 1.0), 1e-6);
}

TEST_CASE("weights scale task rows by sqrt(weight) and disabled tasks contribute zero rows") {
  std::mt19937 rng(4);
  const Model model = test::randomAllTypesModel(rng);
  Data data(model);
  REQUIRE(data.setConfiguration(test::randomConfiguration(model, rng)));
  kinematics(model, data);
  const Eigen::MatrixXd j1 = taskJacobian(data);
  const TaskId pose = model.findTask("pose");
  REQUIRE(data.setWeight(pose, 4.0));
  kinematics(model, data);
  const auto& task = model.tasks[pose];
  CHECK((taskJacobian(data).middleRows(task.first_row, 6) - 2.0 * j1.middleRows(task.first_row, 6)).norm() < 1e-12);
  REQUIRE(data.setEnabled(pose, false));
  kinematics(model, data);
  CHECK(taskJacobian(data).middleRows(task.first_row, 6).norm() == 0.0);
  CHECK(taskError(data).segment(task.first_row, 6).norm() == 0.0);
}
