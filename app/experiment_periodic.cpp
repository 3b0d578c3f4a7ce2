// `embody experiment periodic` (Raunhardt & Boulic 2008, §5.2.2): both hands follow a figure-eight
// in the vertical plane in front of the chest (priority 2), the heels and toes of both feet stay
// where they are (priority 1), the centre of mass stays between the feet (priority 0), for many
// cycles. A redundant IK is not cyclic: the configuration at the same phase can drift from cycle
// to cycle. Measured per cycle, coupled vs uncoupled: the joint-space distance of the
// configuration at phase 0 from cycle 1, and the spine's shape; postures rendered at cycles
// 1, 10, 100, 1000, 2000 (the paper's fig. 11).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "app/experiments.h"
#include "avatar/procedural/default_avatar.h"

namespace embody::app::experiment {
namespace {

constexpr double kTau = 2.0 * std::numbers::pi;

struct PeriodicTasks {
  ik::TaskId com = -1;
  std::array<ik::TaskId, 4> feet{};  // left heel, left toes, right heel, right toes
  std::array<Eigen::Vector3d, 4> feetTargets;
  ik::TaskId leftHand = -1, rightHand = -1;
  Eigen::Vector3d comTarget, centre;  // centre of the figure-eight
};

// The lemniscate of Gerono of `synthetic:figure8` (x = A sin phi, y = B sin 2 phi, A = 0.2 m,
// B = 0.15 m), in the frontal plane, the hands 0.16 m apart.
std::pair<Eigen::Vector3d, Eigen::Vector3d> handTargets(const PeriodicTasks& t, double phi) {
  const Eigen::Vector3d p = t.centre + Eigen::Vector3d(0.2 * std::sin(phi), 0.15 * std::sin(2.0 * phi), 0.0);
  const Eigen::Vector3d apart(0.08, 0.0, 0.0);  // +x is the mannequin's left
  return {p + apart, p - apart};
}

TaskAdder periodicTasks(const avatar::AvatarAsset& asset, PeriodicTasks& t) {
  return [&asset, &t](ik::ModelBuilder& b, const avatar::BodyModel& body) {
    using avatar::HumanBone;
    const ik::Model& m = body.model;
    auto ik = [&](HumanBone bone) {
      return body.ikJointOfAvatar[static_cast<size_t>(asset.humanoid.joint(bone))];
    };
    auto task = [&b](const char* name, ik::TaskType type, ik::JointId joint, int level,
                     const Eigen::Vector3d& offset) { return addExperimentTask(b, name, type, joint, level, offset); };
    const char* names[4] = {"left_heel", "left_toes", "right_heel", "right_toes"};
    const ik::JointId ankles[2] = {body.leftFoot, body.rightFoot};
    const ik::JointId toes[2] = {ik(HumanBone::leftToes), ik(HumanBone::rightToes)};
    t.comTarget.setZero();
    t.com = task("com", ik::TaskType::CenterOfMass, 0, 0, Eigen::Vector3d::Zero());
    for (int side = 0; side < 2; ++side) {
      const Eigen::Isometry3d ankle = restFrame(m, ankles[side]);
      const Eigen::Vector3d heel(ankle.translation().x(), std::min(ankle.translation().y(), 0.03),
                                 ankle.translation().z() - 0.05);
      t.feetTargets[2 * side] = heel;
      t.feetTargets[2 * side + 1] = restFrame(m, toes[side]).translation();
      t.feet[2 * side] =
          task(names[2 * side], ik::TaskType::Position, ankles[side], 1, ankle.inverse() * heel);
      t.feet[2 * side + 1] =
          task(names[2 * side + 1], ik::TaskType::Position, toes[side], 1, Eigen::Vector3d::Zero());
      t.comTarget += 0.25 * (t.feetTargets[2 * side] + t.feetTargets[2 * side + 1]);
    }
    const Eigen::Vector3d shoulders = 0.5 * (restFrame(m, ik(HumanBone::leftUpperArm)).translation() +
                                             restFrame(m, ik(HumanBone::rightUpperArm)).translation());
    t.centre = shoulders + Eigen::Vector3d(0.0, -0.22, 0.32);  // in front of the chest
    t.leftHand = task("left_hand", ik::TaskType::Position, body.leftHand, 2, Eigen::Vector3d::Zero());
    t.rightHand = task("right_hand", ik::TaskType::Position, body.rightHand, 2, Eigen::Vector3d::Zero());
  };
}

struct PeriodicRun {
  ExperimentBody body;
  PeriodicTasks tasks;
  std::string cyclesCsv;
  std::vector<std::pair<int, Eigen::VectorXd>> snapshots;  // (cycle, q at phase 0)
  double seconds = 0.0;
  long iterations = 0;
  nlohmann::json summary;
};

// Dofs that are angles (every dof but the root's translation) and the spine's dofs.
void dofMasks(const ExperimentBody& body, std::vector<int>& angles, std::vector<int>& spine) {
  const ik::Model& m = body.body.model;
  for (const ik::Model::Joint& j : m.joints)
    for (int k = 0; k < j.dof_count; ++k)
      if (!(j.desc.type == ik::JointType::Free && k < 3)) angles.push_back(j.first_dof + k);
  for (const auto& s : body.spineJoints.sites)
    for (ik::JointId id : {s.swing, s.revolute, s.ball})
      if (id >= 0)
        for (int k = 0; k < m.joints[static_cast<size_t>(id)].dof_count; ++k)
          spine.push_back(m.joints[static_cast<size_t>(id)].first_dof + k);
}

double maskedNorm(const Eigen::VectorXd& v, const std::vector<int>& mask) {
  double s = 0.0;
  for (int i : mask) s += v[i] * v[i];
  return std::sqrt(s);
}

bool isSnapshotCycle(int c, int last) {
  return c == 1 || c == 10 || c == 100 || c == 1000 || c == 2000 || c == last;
}

// One cycle's CSV row from the configuration at phase 0.
std::string cycleRow(int cycle, const PeriodicRun& run, const ik::Data& data, const Eigen::VectorXd& q1,
                     const std::vector<int>& angles, const std::vector<int>& spine, double& handErrorSum) {
  const ik::Model& m = run.body.body.model;
  const Eigen::VectorXd d = data.q() - q1;
  const auto [l, r] = handTargets(run.tasks, 0.0);
  const double hand = 0.5 * ((data.taskPosition(run.tasks.leftHand) - l).norm() +
                             (data.taskPosition(run.tasks.rightHand) - r).norm());
  handErrorSum += hand;
  const double com = (m.ground_axes.transpose() * (data.centerOfMass() - run.tasks.comTarget)).norm();
  const SpineShape shape = spineShape(run.body, data.q());
  char line[320];
  std::snprintf(line, sizeof line, "%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%d,%d,%.3g\n", cycle,
                maskedNorm(d, angles), maskedNorm(d, angles) / std::sqrt(double(angles.size())),
                maskedNorm(d, spine), hand, com, shape.swingSpread, shape.maxNormalisedSwing,
                shape.torsionChangesWithin, shape.torsionChangesBetween, equalityResidual(m, data.q()));
  return line;
}

void setHands(Targets& targets, const PeriodicTasks& t, double phi) {
  const auto [l, r] = handTargets(t, phi);
  targets.set(t.leftHand, l);
  targets.set(t.rightHand, r);
}

Result<PeriodicRun> solvePeriodic(const avatar::AvatarAsset& asset, avatar::SpineMode mode, bool coupled,
                                  const PeriodicOptions& o) {
  PeriodicRun run;
  auto body = buildExperimentBody(asset, mode, coupled, periodicTasks(asset, run.tasks));
  if (!body) return Error{body.error()};
  run.body = std::move(*body);
  const ik::Model& m = run.body.body.model;
  ik::Data data(m);
  Targets targets{data, {}};
  targets.set(run.tasks.com, run.tasks.comTarget);
  for (size_t k = 0; k < 4; ++k) targets.set(run.tasks.feet[k], run.tasks.feetTargets[k]);
  ik::SolveOptions so;
  setHands(targets, run.tasks, 0.0);
  for (int i = 0; i < o.settleIterations; ++i) ik::iterate(m, data, so);
  std::vector<int> angles, spine;
  dofMasks(run.body, angles, spine);
  run.cyclesCsv =
      "cycle,drift_rad,drift_rms_rad,spine_drift_rad,hand_error_m,com_error_m,swing_spread,"
      "max_normalised_swing,torsion_changes_within,torsion_changes_between,equality_residual\n";
  Eigen::VectorXd q1;
  double handErrorSum = 0.0;
  const auto t0 = std::chrono::steady_clock::now();
  for (int c = 1; c <= o.cycles; ++c)
    for (int s = 0; s < o.stepsPerCycle; ++s) {
      setHands(targets, run.tasks, kTau * s / o.stepsPerCycle);
      for (int i = 0; i < o.iterationsPerStep; ++i) ik::iterate(m, data, so);
      run.iterations += o.iterationsPerStep;
      if (s != 0) continue;
      ik::kinematics(m, data, false);
      if (c == 1) q1 = data.q();
      run.cyclesCsv += cycleRow(c, run, data, q1, angles, spine, handErrorSum);
      if (isSnapshotCycle(c, o.cycles)) run.snapshots.emplace_back(c, data.q());
    }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!targets.error.empty()) return Error{targets.error};
  const Eigen::VectorXd dLast = run.snapshots.back().second - q1;
  const SpineShape shape = spineShape(run.body, run.snapshots.back().second);
  run.summary = bodySummary(run.body, shape, run.snapshots.back().second);
  run.summary["final_drift_rad"] = maskedNorm(dLast, angles);
  run.summary["final_drift_rms_rad"] = maskedNorm(dLast, angles) / std::sqrt(double(angles.size()));
  run.summary["final_spine_drift_rad"] = maskedNorm(dLast, spine);
  run.summary["hand_error_mean_m"] = handErrorSum / o.cycles;  // at phase 0, over the cycles
  run.summary["angle_dofs"] = angles.size();
  run.summary["spine_dofs"] = spine.size();
  run.summary["seconds"] = run.seconds;
  run.summary["iterations"] = run.iterations;
  run.summary["mean_iteration_us"] = 1e6 * run.seconds / double(std::max(1L, run.iterations));
  return run;
}

std::string periodicPlots() {
  return gnuplotHeader("periodic", "size 1200,480") +
         multiplotFigure("fig11_drift.png", "1,2", "Periodic figure-eight: drift of the configuration at the same phase from cycle 1") +
         R"gp(set grid
set logscale x
set xlabel 'cycle'
set key top left
)gp" +
         runsPanels({{"RMS joint-angle distance from cycle 1 (rad)", "whole body (angle dofs)", "cycles", "1:3", "lines lw 2"},
                     {"spine distance from cycle 1 (rad)", "spine dofs", "cycles", "1:4", "lines lw 2"}}) +
         R"gp(unset multiplot

)gp" +
         multiplotFigure("fig_periodic_spine.png", "1,3", "Periodic figure-eight: spine shape at phase 0 per cycle") +
         runsPanels({{"swing spread", "swing spread (0 = proportional)", "cycles", "1:7", "lines lw 2"},
                     {"|swing| / limit", "largest swing over its limit", "cycles", "1:8", "lines lw 2"},
                     {"count", "torsion sign changes within regions", "cycles", "1:9", "steps lw 2"}}) +
         R"gp(unset multiplot
)gp";
}

}  // namespace

int runPeriodic(const PeriodicOptions& o, nlohmann::json& summary) {
  avatar::SpineMode mode;
  if (!spineModeOf(o.spine, mode)) return fail("periodic: unknown spine '" + o.spine + "'");
  const avatar::AvatarAsset asset = avatar::buildDefaultAvatar();
  std::string error;
  if (!makeFolder(o.common.out, error)) return fail(error);
  std::vector<PeriodicRun> runs;
  for (bool coupled : {true, false}) {
    auto run = solvePeriodic(asset, mode, coupled, o);
    if (!run) return fail("periodic: " + run.error());
    const std::string v = coupled ? "coupled" : "uncoupled";
    if (!writeFile(o.common.out / (v + "_cycles.csv"), run->cyclesCsv))
      return fail("cannot write in " + o.common.out.string());
    summary[v] = run->summary;
    std::printf(
        "%-9s %d cycles x %d steps x %d iterations in %.2f s (%.1f us/iteration): drift %.3g rad RMS, "
        "spine %.3g rad\n",
        v.c_str(), o.cycles, o.stepsPerCycle, o.iterationsPerStep, run->seconds,
        run->summary["mean_iteration_us"].get<double>(), run->summary["final_drift_rms_rad"].get<double>(),
        run->summary["final_spine_drift_rad"].get<double>());
    runs.push_back(std::move(*run));
  }
  summary["setup"] = {{"cycles", o.cycles},
                      {"steps_per_cycle", o.stepsPerCycle},
                      {"iterations_per_step", o.iterationsPerStep},
                      {"settle_iterations", o.settleIterations},
                      {"spine", o.spine},
                      {"avatar", "default"},
                      {"path", "fast"}};
  if (o.common.plots)
    if (auto e = runGnuplot(o.common.out, "plots.gp", periodicPlots()); !e.empty()) return fail(e);
  if (o.common.frames) {
    auto renderer = PostureRenderer::create(asset, o.common.frameSize, o.common.frameSize);
    if (!renderer) return fail("periodic: rendering: " + renderer.error());
    for (const PeriodicRun& run : runs) {
      const std::string v = run.body.coupled ? "coupled" : "uncoupled";
      std::vector<std::pair<const ExperimentBody*, Eigen::VectorXd>> poses;
      std::vector<std::string> names;
      for (const auto& [cycle, q] : run.snapshots) {
        poses.emplace_back(&run.body, q);
        char name[64];
        std::snprintf(name, sizeof name, "fig11_%s_cycle%04d", v.c_str(), cycle);
        names.emplace_back(name);
      }
      auto shots = renderPostures(**renderer, o.common.out, poses, names, {0.6f}, "fig11_" + v + ".png");
      if (!shots) return fail("periodic: rendering: " + shots.error());
    }
  }
  if (!writeFile(o.common.out / "summary.json", summary.dump(2) + "\n"))
    return fail("cannot write summary.json");
  std::printf("wrote periodic results to %s\n", o.common.out.string().c_str());
  return 0;
}

}  // namespace embody::app::experiment
