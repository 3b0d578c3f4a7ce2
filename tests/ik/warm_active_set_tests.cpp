// The warm active set (SolveOptions::warm_active_set, docs/ik.md): each iteration's clamping loop
// starts from the rows pinned in the iteration before and releases those the tasks now pull
// inside. Checked here: it keeps every invariant of the cold loop (strict priority, equality
// rows, inequalities), a carried row that has to go is released, warm and cold agree where the
// constrained problem has one solution, and both paths make the same decisions.
#include <catch2/catch.hpp>

#include <cmath>

#include <Eigen/QR>

#include "ik/solver_detail.h"
#include "ik/solver_internal.h"
#include "ik_test_util.h"
#include "tests/support/sample_models.h"

using namespace embody;
using namespace embody::ik;

namespace {

SolveOptions warm(bool on, int iterations = 100) {
  SolveOptions o;
  o.warm_active_set = on;
  o.max_iterations = iterations;
  return o;
}

Eigen::Vector3d tipAt(double a, double b) {
  return Eigen::Vector3d(0.5 * std::cos(a) + 0.5 * std::cos(a + b), 0.5 * std::sin(a) + 0.5 * std::sin(a + b), 0.0);
}

// a <= 0.3 and a + b <= 0.6 (they share dof a). tolerance 0: solves run until they stall.
Model limitAndSum(double tolerance = -1.0) {
  return test::twoJointModel({{"a <= 0.3", {{{0, 0}, 1.0}}, 0.3, InequalityKind::UserCoupling},
                              {"a+b <= 0.6", {{{0, 0}, 1.0}, {{1, 0}, 1.0}}, 0.6, InequalityKind::UserCoupling}},
                             {}, tolerance);
}

// The carried rows' multipliers for level k by a dense least-squares solve of
// [Aᵀ J_<kᵀ] (μ, λ) = J_kᵀ r_k (A: the independent equality rows and the carried rows as the model
// writes them; J_<k: the higher levels' non-zero task rows). Empty when that matrix is not of full
// column rank (the multipliers are not unique then).
Eigen::VectorXd denseMultipliers(const Model& model, const Data& data, size_t k) {
  const Workspace& w = data.workspace();
  const int eq = w.eq_rank, carried = w.carried_count;
  std::vector<Eigen::VectorXd> cols;
  for (int i = 0; i < eq; ++i) cols.push_back(model.equality_matrix.row(w.eq_rows[static_cast<size_t>(i)]).transpose());
  for (int p = 0; p < carried; ++p) {
    Eigen::VectorXd c = Eigen::VectorXd::Zero(w.n);
    for (const LinearTerm& t : model.inequalities[static_cast<size_t>(w.report.active_clamps[static_cast<size_t>(p)])].terms)
      c(model.dofIndex(t.dof)) += t.coefficient;
    cols.push_back(c);
  }
  for (size_t j = 0; j < k; ++j) {
    const Model::Level& level = model.levels[j];
    for (int i = level.first_row; i < level.first_row + level.rows; ++i)
      if (w.jacobian.row(i).norm() > 0) cols.push_back(w.jacobian.row(i).transpose());
  }
  Eigen::MatrixXd c(w.n, static_cast<Eigen::Index>(cols.size()));
  for (size_t i = 0; i < cols.size(); ++i) c.col(static_cast<Eigen::Index>(i)) = cols[i];
  const Model::Level& level = model.levels[k];
  const auto j = w.jacobian.middleRows(level.first_row, level.rows);
  const Eigen::VectorXd g = j.transpose() * (w.error.segment(level.first_row, level.rows) - j * w.dq);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(c, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  if (sv.size() < c.cols() || sv(sv.size() - 1) < 1e-4 * sv(0)) return {};
  return svd.solve(g).segment(eq, carried);
}

}  // namespace

TEST_CASE("warm active set: the carried rows' multipliers hold the levels above (dense KKT oracle)") {
  // The release test reads each level's multipliers of the carried rows with the active rows and
  // the higher levels held. Against a dense solve on the humanoid and the coupled spine, both
  // paths, after the first pass of warm iterations of random problems. A multiplier that keeps
  // only the active rows fixed (or solves with F where Fᵀ is due) misses this by O(1).
  const Model humanoid = test::sampleHumanoid().value();
  const Model spine = test::sampleSpine(true).value();
  for (const Model* model : {&humanoid, &spine}) {
    for (Path path : {Path::Fast, Path::Reference}) {
      std::mt19937 rng(23);
      Data data(*model);
      SolveOptions o = warm(true, 1);
      o.path = path;
      double worst = 0.0;
      int compared = 0;
      for (int it = 0; it < 400; ++it) {
        if (it % 20 == 0) test::randomTargets(*model, data, rng, 1.0, 0.05);
        kinematics(*model, data);
        Workspace& w = data.workspace();
        detail::startActiveSet(w, o);
        detail::computeDq0(w);
        detail::runPass(*model, w, o);
        for (size_t k = 0; k < model->levels.size() && w.carried_count > 0; ++k) {
          if (!detail::levelActive(model->levels[k], w)) continue;
          const Eigen::VectorXd expected = denseMultipliers(*model, data, k);
          if (expected.size() == 0) continue;
          detail::carriedMultipliers(*model, w, k, o);
          const double scale = std::max(1.0, expected.cwiseAbs().maxCoeff());
          worst = std::max(worst, (w.warm_multiplier.head(w.carried_count) - expected).cwiseAbs().maxCoeff() / scale);
          ++compared;
        }
        iterate(*model, data, o);
      }
      INFO((model == &spine ? "spine" : "humanoid") << (path == Path::Fast ? " fast" : " reference"));
      CHECK(worst < 1e-7);
      CHECK(compared > 50);
    }
  }
}

TEST_CASE("warm active set: a carried row the task now pulls inside is released (dropped row)") {
  const Model model = limitAndSum();
  for (Path path : {Path::Fast, Path::Reference}) {
    Data data(model);
    SolveOptions o = warm(true, 200);
    o.path = path;
    // Frame 1: the target wants a = 0.8, a + b = 1.4: both rows end pinned at their bounds.
    REQUIRE(data.setTarget(0, tipAt(0.8, 0.6)));
    const SolveReport& first = solve(model, data, o);
    REQUIRE(first.active_clamps.size() == 2);
    REQUIRE(std::abs(data.q()(0) - 0.3) < 1e-9);
    REQUIRE(std::abs(data.q()(0) + data.q()(1) - 0.6) < 1e-9);
    // Frame 2: a target inside both rows (a = 0.2, a + b = 0.3): the task now pulls both carried
    // rows inside, so both must go and the tip reaches the target. Kept, they would hold a at
    // 0.3 and a + b at 0.6 with the tip 0.16 m off.
    REQUIRE(data.setTarget(0, tipAt(0.2, 0.1)));
    const SolveReport& second = solve(model, data, o);
    CHECK(second.active_clamps.empty());
    CHECK(second.tasks[0].position < 1e-4);
    CHECK(std::abs(data.q()(0) - 0.2) < 1e-2);  // the solve stops at the task tolerance
    CHECK(std::abs(data.q()(1) - 0.1) < 1e-2);
  }
}

TEST_CASE("warm active set: warm and cold agree on converged solutions of a problem with one solution") {
  // Two dofs, two task rows, two rows pinned or not: from the same start, both loops settle on
  // the same constrained optimum (tolerance 0: they run until the step stalls), whichever rows
  // each pins on its way. Each problem starts from the previous warm solution (the warm solve
  // carries its active set into it).
  const Model model = limitAndSum(0.0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.15, 0.15);
  Data warmData(model), coldData(model);
  int pinnedAtEnd = 0;
  Eigen::Vector2d wanted(0.2, 0.2);
  for (int problem = 0; problem < 60; ++problem) {
    // A walk of the wanted configuration (small steps: the arm's nonlinearity cannot send the
    // two solves to different local optima), often past the rows.
    wanted += Eigen::Vector2d(u(rng), u(rng));
    wanted = wanted.cwiseMax(-0.6).cwiseMin(1.0);
    const Eigen::Vector3d target = tipAt(wanted(0), wanted(1));
    REQUIRE(coldData.setConfiguration(warmData.q()));
    REQUIRE(warmData.setTarget(0, target));
    REQUIRE(coldData.setTarget(0, target));
    const SolveReport& w = solve(model, warmData, warm(true, 300));
    (void)solve(model, coldData, warm(false, 300));
    pinnedAtEnd += w.active_clamps.empty() ? 0 : 1;
    INFO("problem " << problem);
    CHECK((warmData.q() - coldData.q()).cwiseAbs().maxCoeff() < 1e-6);
  }
  CHECK(pinnedAtEnd > 10);  // the rows do take part
}

TEST_CASE("warm active set: strict priority, equality rows and inequalities hold over random problems") {
  const Model humanoid = test::sampleHumanoid().value();
  const Model spine = test::sampleSpine(true).value();
  std::mt19937 rng(17);
  for (const Model* model : {&humanoid, &spine}) {
    Data data(model == &spine ? spine : humanoid);
    const SolveOptions o = warm(true, 1);
    double worstEq = 0.0, worstIneq = -1.0;
    int carriedIterations = 0;
    for (int it = 0; it < 3000; ++it) {
      if (it % 20 == 0) test::randomTargets(*model, data, rng, 1.0, 0.05);
      iterate(*model, data, o);
      worstEq = std::max(worstEq, test::equalityViolation(*model, data.q()));
      worstIneq = std::max(worstIneq, test::worstInequality(*model, data.q(), data.report().unsatisfiable));
      carriedIterations += data.workspace().carried_count > 0 ? 1 : 0;
    }
    CHECK(worstEq < 1e-9);
    CHECK(worstIneq < 1e-8);
    CHECK(carriedIterations > 100);  // the warm start is exercised
  }
}

TEST_CASE("warm active set: strict priority over a full solve, a conflicting lower task cannot pull the feet off") {
  const Model model = test::sampleHumanoid().value();
  std::mt19937 rng(8);
  for (int trial = 0; trial < 10; ++trial) {
    Data data(model);
    test::setConflictingReach(model, data, rng);
    test::checkConflictingReach(model, solve(model, data, warm(true, 200)));
  }
}

TEST_CASE("warm active set: the fast and reference paths make the same decisions") {
  const Model model = test::sampleSpine(true).value();
  std::mt19937 rng(41);
  Data fast(model), reference(model);
  SolveOptions of = warm(true, 1), orf = warm(true, 1);
  orf.path = Path::Reference;
  double worst = 0.0;
  int carried = 0;
  for (int it = 0; it < 200; ++it) {
    if (it % 20 == 0) {
      std::mt19937 copy = rng;
      test::randomTargets(model, fast, rng, 1.0, 0.05);
      test::randomTargets(model, reference, copy, 1.0, 0.05);
    }
    iterate(model, fast, of);
    iterate(model, reference, orf);
    REQUIRE(fast.report().active_clamps == reference.report().active_clamps);
    worst = std::max(worst, (fast.q() - reference.q()).cwiseAbs().maxCoeff());
    carried += fast.workspace().carried_count > 0 ? 1 : 0;
  }
  CHECK(worst < 1e-8);
  CHECK(carried > 20);
}
