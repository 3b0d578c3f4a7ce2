// Conflicting lower levels (regression for the runtime's "the solver diverges when low-priority
// rows conflict with higher ones"): on many random problems, feasible higher levels are met and
// stay met while a lower level pulls against them, and nothing diverges.
#include <catch2/catch.hpp>

#include <algorithm>
#include <random>
#include <sstream>

#include "tests/support/sample_models.h"
#include "ik_test_util.h"

using namespace embody;
using namespace embody::ik;

namespace {

// Worst position / rotation residual over the tasks of levels [0, lastLevel].
double worstUpTo(const Model& model, const SolveReport& r, int lastLevel) {
  double worst = 0.0;
  for (size_t t = 0; t < model.tasks.size(); ++t)
    if (model.tasks[t].desc.level <= lastLevel && r.tasks[t].enabled)
      worst = std::max({worst, r.tasks[t].position, r.tasks[t].rotation});
  return worst;
}

struct ConflictStats {
  int problems = 0, regrown = 0, unmet = 0, nonFinite = 0;
  double worstFinal = 0.0, worstRegrowth = 0.0, maxDq = 0.0;
};

ConflictStats runConflicts(const SolveOptions& options) {
  // Feet (0), centre of mass (1) and head (2) get the task values of one random configuration
  // (feasible together); the hands (3) get targets 0.4-1.5 m away from theirs, in random
  // directions: far out of reach with the feet, CoM and head held. Solved one iteration at a
  // time from the neutral pose, warm-started over 3 successive target sets, 150 iterations each.
  const Model& model = test::sharedSampleHumanoid();
  const TaskId lh = model.findTask("left_hand"), rh = model.findTask("right_hand");
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> dist(0.4, 1.5);
  std::normal_distribution<double> g;
  SolveOptions o = options;
  o.max_iterations = 1;
  ConflictStats s;
  int& problems = s.problems;
  int& regrown = s.regrown;
  int& unmet = s.unmet;
  int& nonFinite = s.nonFinite;
  double& worstFinal = s.worstFinal;
  double& worstRegrowth = s.worstRegrowth;
  double& maxDq = s.maxDq;
  for (int trial = 0; trial < 60; ++trial) {
    Data data(model);
    for (int set = 0; set < 3; ++set, ++problems) {
      Data probe(model);
      REQUIRE(probe.setConfiguration(test::randomInsideLimits(model, rng, 0.5, 0.5)));
      kinematics(model, probe, false);
      for (TaskId t = 0; t < static_cast<TaskId>(model.tasks.size()); ++t) {
        Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
        pose.linear() = probe.taskOrientation(t).toRotationMatrix();
        pose.translation() = probe.taskPosition(t);
        if (t == lh || t == rh) {
          const Eigen::Vector3d dir = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
          pose.translation() += dist(rng) * dir;
        }
        REQUIRE(data.setTarget(t, pose));
      }
      bool met = false;
      double final = 0.0;
      for (int it = 0; it < 150; ++it) {
        const Eigen::VectorXd before = data.q();
        const SolveReport& r = solve(model, data, o);
        if (!data.q().allFinite()) {
          ++nonFinite;
          break;
        }
        maxDq = std::max(maxDq, (data.q() - before).cwiseAbs().maxCoeff());
        final = worstUpTo(model, r, 2);
        if (met && final > 2e-3) {  // met once, then pulled off by the lower level
          ++regrown;
          worstRegrowth = std::max(worstRegrowth, final);
        }
        met = met || final < 1e-4;
      }
      if (final > 1e-3) ++unmet;
      worstFinal = std::max(worstFinal, final);
    }
  }
  return s;
}

}  // namespace

TEST_CASE("a conflicting lower level keeps feasible higher levels met (second-order drift < 1 cm), never diverges") {
  const auto report = [](const ConflictStats& s) {
    std::ostringstream o;
    o << "problems " << s.problems << ", unmet " << s.unmet << ", worst final " << s.worstFinal << ", regrown "
      << s.regrown << " (worst " << s.worstRegrowth << "), non-finite " << s.nonFinite << ", largest |dq_i| " << s.maxDq;
    return o.str();
  };
  // Without the per-level trust region (max_level_step = 0) the same problems gave: higher
  // levels pulled back off by up to 2.4 cm after being met (59 iterations), 2 problems left
  // unmet (worst 5 cm), single-dof steps up to 2.6 rad. See the "[.figures]" case below.
  const ConflictStats s = runConflicts(SolveOptions{});
  const int problems = s.problems;
  INFO(report(s));
  CHECK(s.nonFinite == 0);
  CHECK(s.unmet <= problems / 100);  // a random configuration can sit at a limit: allow 1 %
  CHECK(s.worstFinal < 2e-3);
  // Strict priority holds to first order; the lower level's steps disturb the met levels only to
  // second order, and the next iteration takes that back. Bounded well below the 2.4 cm measured
  // without the trust region (measured with it: 5.7 mm at worst, 40 iterations of 27,000).
  CHECK(s.worstRegrowth < 0.01);
  CHECK(s.regrown < problems);
  CHECK(s.maxDq < 0.2);  // no wild steps (the cap is on a level's norm: 0.1 each, 4 levels)
}

// Figures for docs/ik.md (hidden: `embody_tests_ik "[.figures]" -s`).
TEST_CASE("figures: conflicting lower level against the per-level trust region", "[.figures]") {
  for (double cap : {0.0, 0.5, 0.25, 0.1, 0.05}) {
    SolveOptions o;
    o.max_level_step = cap;
    const ConflictStats s = runConflicts(o);
    WARN("max_level_step " << cap << ": problems " << s.problems << ", unmet " << s.unmet << ", worst final "
                           << s.worstFinal << ", regrown " << s.regrown << " (worst " << s.worstRegrowth
                           << "), largest |dq_i| " << s.maxDq);
  }
}
