// The isolated-spine experiment (§5.1) reproduces the paper's qualitative findings. Timings are
// the benchmarks' business (bench/spine_bench.cpp), not asserted here.
#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include "ik/spine/isolated_experiment.h"

using namespace embody::ik::spine;

TEST_CASE("isolated spine: uncoupled reaches closer, coupled is smoother and never twists back") {
  ExperimentOptions o;
  auto r = runIsolatedSpineExperiment(defaultFullSpine(), o);
  REQUIRE(r.ok());
  const nlohmann::json s = experimentSummary(*r, o);
  const auto& c = s["coupled"];
  const auto& u = s["uncoupled"];
  INFO(s.dump(2));
  // The head orientation has the higher priority: both keep it to round-off (measured ~1e-13°;
  // json::get throws on a missing key, which fails the test too).
  CHECK(c["final_orientation_error_deg"].get<double>() < 1e-6);
  CHECK(u["final_orientation_error_deg"].get<double>() < 1e-6);
  // The uncoupled spine (72 dofs) reaches the sideways neck target more closely.
  CHECK(u["final_position_error_m"].get<double>() < 0.5 * c["final_position_error_m"].get<double>());
  // The coupled spine bends every level in proportion to its mobility (its spread and torsion
  // sign follow from the equality rows, so only those are checked); the uncoupled one does not.
  CHECK(r->coupled.equalities_hold);
  CHECK(u["swing_spread"].get<double>() > 10 * c["swing_spread"].get<double>() + 1e-3);
  // Both runs moved the neck toward the target.
  const double start = (r->neck_target - r->neck_start).norm();
  CHECK(c["final_position_error_m"].get<double>() < 0.8 * start);
  CHECK(r->coupled.samples.size() == static_cast<size_t>(o.iterations));
}

TEST_CASE("isolated spine: invalid options are refused") {
  ExperimentOptions o;
  o.iterations = 0;
  CHECK_FALSE(runIsolatedSpineExperiment(defaultFullSpine(), o).ok());
  o.iterations = 10;
  o.pull = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(runIsolatedSpineExperiment(defaultFullSpine(), o).ok());
}

TEST_CASE("isolated spine: the band-slack sweep shows how much of the reach the bands take") {
  ExperimentOptions o;
  auto sweep = sweepBandSlack(defaultFullSpine(), o, {0.0, 2.0, 5.0});
  REQUIRE(sweep.ok());
  REQUIRE(sweep->size() == 3);
  const auto& p = *sweep;
  for (const SlackSweepPoint& point : p) {
    INFO("slack " << point.slack_deg << " deg: neck error " << point.position_error << " m");
    CHECK(point.equalities_hold);
    CHECK(point.orientation_error < 1e-8);  // radians: the head keeps its orientation at any slack
  }
  // Rigid bands (0°) leave the three regions one chain: the neck cannot get far; every degree of
  // slack lets the regions bend more independently (measured 0.120, 0.049, 0.008 m).
  CHECK(p[0].position_error > 2 * p[1].position_error);
  CHECK(p[1].position_error > 2 * p[2].position_error);
  CHECK_FALSE(sweepBandSlack(defaultFullSpine(), o, {-1.0}).ok());
}
