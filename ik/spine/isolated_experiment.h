#pragma once
// The isolated-spine experiment (Raunhardt & Boulic 2008, §5.1): the spine alone on a fixed
// pelvis, the head's orientation kept (priority 0) while the top of the neck is pulled sideways
// (priority 1), solved with the coupled model and with the uncoupled ball-joint spine. The
// results feed `embody experiment isolated-spine` (CSV, summary.json, plots) and the tests.
#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include <string>
#include <vector>

#include "ik/spine/spine_analysis.h"
#include "ik/spine/spine_description.h"
#include "core/result.h"

namespace embody::ik::spine {

struct ExperimentOptions {
  int iterations = 100;      // fixed count, so both runs are plotted over the same axis
  double pull = 0.12;        // metres the neck target is moved towards the character's left (+x)
  double height = 1.75;      // body height the spine is scaled to (m)
  bool axis_coupling = false;
  // > 0: the solver's damping_max and damping_eps both set to this; 0: the solver's defaults.
  // (The spine's lever arms are short: singular values of the neck position task are ~0.05-0.3
  // m/rad, so a damping threshold well below that lets a near-singular direction take steps of
  // tenths of a radian.)
  double damping = 0.0;
};

struct IterationSample {
  int iteration = 0;                 // 1-based: the state after this many iterations
  double time_us = 0.0;              // cumulative solver time
  double position_error = 0.0;       // metres, neck position task
  double orientation_error = 0.0;    // radians, head orientation task
  double step_norm = 0.0;            // |Δq| of this iteration (radians)
};

struct ExperimentRun {
  std::string variant;  // "coupled" / "uncoupled"
  SpineDescription description;
  SpineJoints joints;
  std::vector<IterationSample> samples;
  std::vector<SiteMotion> motion;  // per site, final
  // World joint centres of the sites, then the skullbase: at rest and after solving.
  std::vector<Eigen::Vector3d> rest_centres, final_centres;
  double final_position_error = 0.0;     // metres
  double final_orientation_error = 0.0;  // radians
  double mean_iteration_us = 0.0;
  double swing_spread = 0.0;
  int torsion_sign_changes = 0;
  bool equalities_hold = true;  // every equality row within 1e-9 at the end
};

struct ExperimentResult {
  Eigen::Vector3d neck_start = Eigen::Vector3d::Zero();
  Eigen::Vector3d neck_target = Eigen::Vector3d::Zero();
  ExperimentRun coupled, uncoupled;
};

Result<ExperimentResult> runIsolatedSpineExperiment(const SpineDescription& description,
                                                    const ExperimentOptions& options = {});

// The §5.1 result hinges on the inter-region band slack s (|q_j - r q_i| <= s between regions), a
// value the paper does not give: the coupled run repeated for each slack (degrees) in `slacks_deg`.
struct SlackSweepPoint {
  double slack_deg = 0.0;
  double position_error = 0.0;     // metres, neck, after options.iterations
  double orientation_error = 0.0;  // radians, head
  double swing_spread = 0.0;
  int torsion_sign_changes = 0;
  bool equalities_hold = true;
};
Result<std::vector<SlackSweepPoint>> sweepBandSlack(const SpineDescription& description, const ExperimentOptions& options,
                                                   const std::vector<double>& slacks_deg);
nlohmann::json sweepSummary(const std::vector<SlackSweepPoint>& sweep);

// summary.json: {"coupled": {...}, "uncoupled": {...}, "setup": {...}} with, per run,
// final_position_error_m, final_orientation_error_deg, mean_iteration_us, swing_spread,
// torsion_sign_changes_within_regions.
nlohmann::json experimentSummary(const ExperimentResult& result, const ExperimentOptions& options);

}  // namespace embody::ik::spine
