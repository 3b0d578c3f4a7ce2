// An independent oracle for the damped priority loop: the textbook recursion with a full SVD per
// level (P0 = I - A⁺A, Δq0 = A⁺(b - Aq), Ĵ_k = J_k P_{k-1}, Δq += Ĵ_k^{+λ}(e_k - J_k Δq),
// P_k = P_{k-1} - V_r V_rᵀ), written here from pik.md without any of the solver's code: its
// damping comes from Ĵ's exact smallest singular value (the solver estimates it by inverse
// iteration on ĴĴᵀ), no step caps, no null-space basis, no Cholesky.
#include <catch2/catch.hpp>

#include <Eigen/SVD>

#include "ik_test_util.h"
#include "tests/support/sample_models.h"

using namespace embody;
using namespace embody::ik;

namespace {

Eigen::MatrixXd pseudoInverse(const Eigen::MatrixXd& a, double tol) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(a.cols(), a.rows());
  for (Eigen::Index i = 0; i < svd.singularValues().size(); ++i)
    if (svd.singularValues()(i) > tol)
      out += svd.matrixV().col(i) * svd.matrixU().col(i).transpose() / svd.singularValues()(i);
  return out;
}

// `second`: damp each level from its second-smallest singular value instead (the solver's σ_min
// estimate lies between the two when they are close).
Eigen::VectorXd oracleStep(const Model& model, const Data& data, const SolveOptions& o, bool* damped = nullptr,
                           bool second = false) {
  const Eigen::MatrixXd& j = taskJacobian(data);
  const Eigen::VectorXd& e = taskError(data);
  const Eigen::Index n = model.dofs;
  Eigen::MatrixXd p = Eigen::MatrixXd::Identity(n, n);
  Eigen::VectorXd dq = Eigen::VectorXd::Zero(n);
  if (model.equality_matrix.rows() > 0) {
    const Eigen::MatrixXd& a = model.equality_matrix;
    const Eigen::MatrixXd ap = pseudoInverse(a, 1e-9);
    p -= ap * a;
    dq = ap * (model.equality_rhs - a * data.q());
  }
  for (const Model::Level& level : model.levels) {
    const Eigen::MatrixXd jk = j.middleRows(level.first_row, level.rows);
    const Eigen::MatrixXd jh = jk * p;
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(jh, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::VectorXd& sv = svd.singularValues();
    // σ_min of the m x n matrix: zero when it has more rows than columns.
    double sigmaMin = level.rows > n ? 0.0 : sv(sv.size() - 1);
    if (second && sv.size() > 1) sigmaMin = level.rows > n ? sv(sv.size() - 1) : sv(sv.size() - 2);
    double lambda2 = 0.0;
    if (sigmaMin < o.damping_eps) {
      const double x = sigmaMin / o.damping_eps;
      lambda2 = (1.0 - x * x) * o.damping_max * o.damping_max;
    }
    if (damped && lambda2 > 0) *damped = true;
    const Eigen::VectorXd r = e.segment(level.first_row, level.rows) - jk * dq;
    for (Eigen::Index i = 0; i < sv.size(); ++i) {
      const double s = sv(i);
      if (lambda2 == 0.0 && !(s > o.rank_tolerance)) continue;  // undamped: truncated pseudo-inverse
      dq += svd.matrixV().col(i) * (s / (s * s + lambda2)) * svd.matrixU().col(i).dot(r);
    }
    for (Eigen::Index i = 0; i < sv.size(); ++i)
      if (sv(i) > o.rank_tolerance) p -= svd.matrixV().col(i) * svd.matrixV().col(i).transpose();
  }
  return dq;
}

// The two-joint chain (test::addTwoJointChain); `copies` identical position tasks on level 0 (a
// rank-deficient level when copies > 1).
Model duplicatedTaskModel(int copies) {
  ModelBuilder b;
  const JointId tip = test::addTwoJointChain(b);
  for (int i = 0; i < copies; ++i) {
    TaskDesc t;
    t.name = "tip" + std::to_string(i);
    t.joint = tip;
    t.axes = kAxisX | kAxisY;
    b.addTask(t);
  }
  return b.build().value();
}

}  // namespace

TEST_CASE("both paths match an independent SVD oracle of the damped priority loop on random problems") {
  std::mt19937 rng(1605);
  std::vector<Model> models;
  models.push_back(test::sampleHumanoid().value());
  models.push_back(test::sampleSpine(true).value());
  for (int i = 0; i < 8; ++i) models.push_back(test::randomAllTypesModel(rng, i % 2 == 0));
  int damped = 0, compared = 0;
  double worstDamped = 0.0;
  for (const Model& model : models) {
    for (int trial = 0; trial < 12; ++trial) {
      Data data(model);
      REQUIRE(data.setConfiguration(test::randomInsideLimits(model, rng, 1.0)));
      test::randomTargets(model, data, rng, 1.0, trial % 3 == 0 ? 0.5 : 0.05);  // some far: damping active
      kinematics(model, data);
      SolveOptions o;
      o.max_level_step = 0.0;  // the oracle has no trust region
      bool levelDamped = false;
      const Eigen::VectorXd expected = oracleStep(model, data, o, &levelDamped);
      for (Path path : {Path::Fast, Path::Reference}) {
        o.path = path;
        const Eigen::VectorXd got = priorityPass(model, data, o);
        INFO(model.dofs << " dofs, trial " << trial << (path == Path::Fast ? " fast" : " reference")
                        << (levelDamped ? " (damped)" : " (undamped)"));
        const double error = (got - expected).norm() / std::max(1.0, expected.norm());
        // Undamped steps agree to round-off. Damped ones inherit the solver's σ_min estimate
        // (three inverse-iteration steps on ĴĴᵀ), which lies between σ1 and σ2 when they are
        // close: the step must then be within the spread between damping from σ1 and from σ2.
        const double spread = (oracleStep(model, data, o, nullptr, true) - expected).norm() / std::max(1.0, expected.norm());
        CHECK(error <= (levelDamped ? 1e-6 + spread : 1e-9));
        worstDamped = std::max(worstDamped, levelDamped ? error : 0.0);
        ++compared;
      }
      damped += levelDamped ? 1 : 0;
    }
  }
  WARN("worst damped relative difference from the oracle: " << worstDamped);
  CHECK(compared == static_cast<int>(models.size()) * 24);
  CHECK(damped > 0);  // the comparison covers damped levels, not only the undamped solve
}

TEST_CASE("damping_max = 0 on a rank-deficient level: the truncated pseudo-inverse, both paths") {
  SolveOptions o;
  o.damping_max = 0.0;
  o.max_level_step = 0.0;
  const Model single = duplicatedTaskModel(1), doubled = duplicatedTaskModel(2);
  Data one(single), two(doubled);
  REQUIRE(one.setConfiguration(Eigen::Vector2d(0.3, 0.4)));
  REQUIRE(two.setConfiguration(Eigen::Vector2d(0.3, 0.4)));
  SECTION("two copies of one target: the step of the single task") {
    REQUIRE(one.setTarget(0, Eigen::Vector3d(0.6, 0.5, 0.0)));
    REQUIRE(two.setTarget(0, Eigen::Vector3d(0.6, 0.5, 0.0)));
    REQUIRE(two.setTarget(1, Eigen::Vector3d(0.6, 0.5, 0.0)));
    kinematics(single, one);
    kinematics(doubled, two);
    const Eigen::VectorXd expected = priorityPass(single, one, o);
    for (Path path : {Path::Fast, Path::Reference}) {
      o.path = path;
      const Eigen::VectorXd got = priorityPass(doubled, two, o);
      CHECK((got - expected).norm() < 1e-9);
      CHECK((got - oracleStep(doubled, two, o)).norm() < 1e-9);
    }
  }
  SECTION("two copies with different targets: the least-squares compromise, both paths equal") {
    REQUIRE(two.setTarget(0, Eigen::Vector3d(0.6, 0.5, 0.0)));
    REQUIRE(two.setTarget(1, Eigen::Vector3d(0.5, 0.6, 0.0)));
    kinematics(doubled, two);
    o.path = Path::Fast;
    const Eigen::VectorXd fast = priorityPass(doubled, two, o);
    o.path = Path::Reference;
    const Eigen::VectorXd reference = priorityPass(doubled, two, o);
    CHECK((fast - reference).norm() < 1e-9);
    CHECK((fast - oracleStep(doubled, two, o)).norm() < 1e-9);
    CHECK(fast.norm() < 1.0);  // not the 1e7 of a division by a round-off pivot
  }
  SECTION("a full solve converges to the shared target") {
    REQUIRE(two.setTarget(0, Eigen::Vector3d(0.6, 0.5, 0.0)));
    REQUIRE(two.setTarget(1, Eigen::Vector3d(0.6, 0.5, 0.0)));
    o.max_iterations = 50;
    const SolveReport& r = solve(doubled, two, o);
    CHECK(r.converged());
    CHECK(two.q().allFinite());
    CHECK(r.tasks[0].position < 1e-4);
  }
}
