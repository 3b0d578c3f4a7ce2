// P0 (the null-space projector of the equality rows) and the corrected Algorithm 1.
#include <catch2/catch.hpp>

#include <Eigen/QR>
#include <random>

#include "ik/projector.h"
#include "tests/support/sample_models.h"

using namespace embody;
using namespace embody::ik;

TEST_CASE("P0 from the incremental build is symmetric, idempotent, annihilates A and equals I - A+A") {
  std::mt19937 rng(1);
  std::normal_distribution<double> g;
  for (int trial = 0; trial < 50; ++trial) {
    const int n = 5 + trial % 20, rows = 1 + trial % (n - 1);
    Eigen::MatrixXd a(rows, n);
    for (int i = 0; i < rows; ++i)
      for (int j = 0; j < n; ++j) a(i, j) = g(rng);
    std::vector<int> dependent;
    const Eigen::MatrixXd p = incrementalNullspaceProjector(a, 1e-9, &dependent);
    CHECK(dependent.empty());
    CHECK((p - p.transpose()).cwiseAbs().maxCoeff() < 1e-12);
    CHECK((p * p - p).cwiseAbs().maxCoeff() < 1e-12);
    CHECK((a * p).cwiseAbs().maxCoeff() < 1e-12);
    const Eigen::MatrixXd pinv = a.completeOrthogonalDecomposition().pseudoInverse();
    const Eigen::MatrixXd reference = Eigen::MatrixXd::Identity(n, n) - pinv * a;
    CHECK((p - reference).cwiseAbs().maxCoeff() < 1e-10);
  }
}

TEST_CASE("a row dependent on earlier rows is skipped and reported, first added wins") {
  Eigen::MatrixXd a(4, 5);
  a << 1, 2, 0, 0, 0,   //
      0, 1, 1, 0, 0,    //
      2, 5, 1, 0, 0,    // = 2 row0 + row1: dependent
      0, 0, 0, 1, -1;
  std::vector<int> dependent;
  const Eigen::MatrixXd p = incrementalNullspaceProjector(a, 1e-9, &dependent);
  REQUIRE(dependent == std::vector<int>{2});
  CHECK((a * p).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(std::abs(p.trace() - 2.0) < 1e-12);  // rank 3 removed from 5 dofs
  // The same rows in another order: now the last added of the dependent triple is reported.
  Eigen::MatrixXd b(3, 5);
  b << a.row(2), a.row(0), a.row(1);
  dependent.clear();
  (void)incrementalNullspaceProjector(b, 1e-9, &dependent);
  CHECK(dependent == std::vector<int>{2});
}

TEST_CASE("the model lists dependent equality rows, and the coupled spine keeps 9 free dofs") {
  const Model spine = test::sampleSpine(true).value();
  CHECK(spine.equalities.size() == 33);
  CHECK(spine.dependent_equalities.empty());
  CHECK(spine.dofs - (static_cast<int>(spine.equalities.size()) - static_cast<int>(spine.dependent_equalities.size())) == 9);

  ModelBuilder b;
  const JointId r = b.addJoint("r", kNoParent, JointType::Ball);
  b.addEquality("a", {r, 0}, 1.0, {r, 1}, -1.0);
  b.addEquality("b", {r, 1}, 1.0, {r, 2}, -1.0);
  b.addEquality("c", {r, 0}, 1.0, {r, 2}, -1.0);  // a + b
  TaskDesc t;
  t.name = "t";
  t.type = TaskType::Orientation;
  t.joint = r;
  b.addTask(t);
  const Model m = b.build().value();
  CHECK(m.dependent_equalities == std::vector<int>{2});
}
