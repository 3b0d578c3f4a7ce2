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
  for (const char* key : {"final_position_error_m", "final_orientation_error_deg", "mean_iteration_us", "swing_spread",
                          "torsion_sign_changes_within_regions"}) {
    CHECK(c.contains(key));
    CHECK(u.contains(key));
  }
  // The head orientation has the higher priority: both keep it.
  CHECK(c["final_orientation_error_deg"].get<double>() < 0.5);
  CHECK(u["final_orientation_error_deg"].get<double>() < 0.5);
  // The uncoupled spine (72 dofs) reaches the sideways neck target more closely.
  CHECK(u["final_position_error_m"].get<double>() < 0.5 * c["final_position_error_m"].get<double>());
  // The coupled spine bends every level in proportion to its mobility and keeps torsion one way.
  CHECK(c["swing_spread"].get<double>() < 0.1 * u["swing_spread"].get<double>());
  CHECK(c["torsion_sign_changes_within_regions"].get<int>() == 0);
  CHECK(r->coupled.equalities_hold);
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
