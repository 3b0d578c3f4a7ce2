#include "ik/spine/isolated_experiment.h"

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/angles.h"
#include "ik/solver.h"
#include "ik/spine/spine_model.h"

namespace embody::ik::spine {
namespace {

Result<ExperimentRun> runOne(const SpineDescription& d, bool coupled, const ExperimentOptions& o,
                             ExperimentResult& result) {
  SpineOptions so;
  so.coupled = coupled;
  so.axis_coupling = o.axis_coupling;
  auto spine = buildIsolatedSpine(d, so, o.height);
  if (!spine) return Error{spine.error()};
  const ik::Model& model = spine->model;
  ik::Data data(model);
  ik::kinematics(model, data, false);

  ExperimentRun run;
  run.variant = coupled ? "coupled" : "uncoupled";
  run.description = d;
  run.joints = spine->joints;
  auto centres = [&] {
    std::vector<Eigen::Vector3d> c;
    for (const SpineJoints::SiteJoints& s : spine->joints.sites)
      c.push_back(data.jointFrame(s.swing >= 0 ? s.swing : s.last()).translation());
    c.push_back(data.jointFrame(spine->skullbase).translation());
    return c;
  };
  run.rest_centres = centres();

  const Eigen::Quaterniond headStart = data.taskOrientation(spine->head_orientation);
  result.neck_start = data.taskPosition(spine->neck_position);
  result.neck_target = result.neck_start + Eigen::Vector3d(o.pull, 0.0, 0.0);
  if (Status s = data.setTarget(spine->head_orientation, headStart); !s) return Error{s.error()};
  if (Status s = data.setTarget(spine->neck_position, result.neck_target); !s) return Error{s.error()};

  ik::SolveOptions solveOptions;
  if (o.damping > 0) solveOptions.damping_max = solveOptions.damping_eps = o.damping;
  {  // warm caches and code on a copy, so the first timed iterations are not cold-start outliers
    ik::Data warm = data;
    for (int i = 0; i < 3; ++i) ik::iterate(model, warm, solveOptions);
  }
  Eigen::VectorXd previous = data.q();
  double total = 0.0;
  run.samples.reserve(static_cast<size_t>(o.iterations));
  for (int i = 1; i <= o.iterations; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    ik::iterate(model, data, solveOptions);
    const auto t1 = std::chrono::steady_clock::now();
    total += std::chrono::duration<double, std::micro>(t1 - t0).count();
    ik::kinematics(model, data, false);  // errors of the new q (outside the timed part)
    IterationSample s;
    s.iteration = i;
    s.time_us = total;
    s.position_error = (data.taskPosition(spine->neck_position) - result.neck_target).norm();
    s.orientation_error = data.taskOrientation(spine->head_orientation).angularDistance(headStart);
    s.step_norm = (data.q() - previous).norm();
    previous = data.q();
    run.samples.push_back(s);
  }
  if (!data.q().allFinite()) return Error{"isolated-spine experiment: the " + run.variant + " solve produced NaN"};
  run.final_centres = centres();
  run.final_position_error = run.samples.empty() ? 0.0 : run.samples.back().position_error;
  run.final_orientation_error = run.samples.empty() ? 0.0 : run.samples.back().orientation_error;
  run.mean_iteration_us = o.iterations > 0 ? total / o.iterations : 0.0;
  run.motion = siteMotion(model, data.q(), run.joints);
  run.swing_spread = swingSpread(d, run.joints, run.motion);
  run.torsion_sign_changes = torsionSignChangesWithinRegions(d, run.joints, run.motion);
  if (model.equality_matrix.rows() > 0)
    run.equalities_hold = (model.equality_matrix * data.q() - model.equality_rhs).cwiseAbs().maxCoeff() <= 1e-9;
  return run;
}

nlohmann::json runJson(const ExperimentRun& r) {
  return {{"final_position_error_m", r.final_position_error},
          {"final_orientation_error_deg", r.final_orientation_error / kDeg},
          {"mean_iteration_us", r.mean_iteration_us},
          {"swing_spread", r.swing_spread},
          {"torsion_sign_changes_within_regions", r.torsion_sign_changes},
          {"iterations", r.samples.size()},
          {"dofs", r.joints.coupled ? r.description.swingCount() * 2 + r.description.revoluteCount()
                                    : static_cast<int>(r.description.sites.size()) * 3},
          {"equalities_hold", r.equalities_hold}};
}

}  // namespace

Result<ExperimentResult> runIsolatedSpineExperiment(const SpineDescription& d, const ExperimentOptions& o) {
  if (o.iterations < 1 || o.iterations > 100000) return Error{"isolated-spine experiment: iterations must be 1..100000"};
  if (!std::isfinite(o.pull) || std::abs(o.pull) > 1.0) return Error{"isolated-spine experiment: pull must be within ±1 m"};
  ExperimentResult result;
  auto coupled = runOne(d, true, o, result);
  if (!coupled) return Error{coupled.error()};
  auto uncoupled = runOne(d, false, o, result);
  if (!uncoupled) return Error{uncoupled.error()};
  result.coupled = std::move(*coupled);
  result.uncoupled = std::move(*uncoupled);
  return result;
}

Result<std::vector<SlackSweepPoint>> sweepBandSlack(const SpineDescription& d, const ExperimentOptions& o,
                                                   const std::vector<double>& slacks_deg) {
  if (o.iterations < 1 || o.iterations > 100000) return Error{"band-slack sweep: iterations must be 1..100000"};
  std::vector<SlackSweepPoint> out;
  for (double deg : slacks_deg) {
    if (!std::isfinite(deg) || deg < 0 || deg > 45) return Error{"band-slack sweep: slack must be 0..45 degrees"};
    SpineDescription copy = d;
    copy.band_slack = deg * kDeg;
    ExperimentResult scratch;
    auto run = runOne(copy, true, o, scratch);
    if (!run) return Error{run.error()};
    out.push_back({deg, run->final_position_error, run->final_orientation_error, run->swing_spread,
                   run->torsion_sign_changes, run->equalities_hold});
  }
  return out;
}

nlohmann::json sweepSummary(const std::vector<SlackSweepPoint>& sweep) {
  nlohmann::json j = nlohmann::json::array();
  for (const SlackSweepPoint& p : sweep)
    j.push_back({{"band_slack_deg", p.slack_deg},
                 {"final_position_error_m", p.position_error},
                 {"final_orientation_error_deg", p.orientation_error / kDeg},
                 {"swing_spread", p.swing_spread},
                 {"torsion_sign_changes_within_regions", p.torsion_sign_changes},
                 {"equalities_hold", p.equalities_hold}});
  return j;
}

nlohmann::json experimentSummary(const ExperimentResult& r, const ExperimentOptions& o) {
  nlohmann::json j;
  j["coupled"] = runJson(r.coupled);
  j["uncoupled"] = runJson(r.uncoupled);
  j["setup"] = {{"model", r.coupled.description.name},
                {"vertebrae", r.coupled.description.vertebrae.size()},
                {"height_m", o.height},
                {"pull_m", o.pull},
                {"axis_coupling", o.axis_coupling},
                {"neck_start_m", {r.neck_start.x(), r.neck_start.y(), r.neck_start.z()}},
                {"neck_target_m", {r.neck_target.x(), r.neck_target.y(), r.neck_target.z()}},
                {"priorities", {{"head_orientation", 0}, {"neck_position", 1}}}};
  return j;
}

}  // namespace embody::ik::spine
