// `embody experiment balance` (Raunhardt & Boulic 2008, §5.2.1): the default mannequin with the
// simplified spine (8 swing + 5 revolute joints) stands on its left foot. Priorities, every task
// recruiting up to the root:
//   0  centre of mass over the left foot (ground plane)
//   1  left heel and left toes stay where they are on the ground
//   2  right toes attracted backwards (and a little up), both hands attracted forwards
//   3  the head keeps looking forward (its rest orientation)
// Coupled vs uncoupled: the postures (the paper's fig. 9), the torsion per spine site (fig. 10)
// and the torsion sign changes inside a region vs between regions.
#include <chrono>
#include <cstdio>

#include "core/angles.h"
#include "app/experiments.h"
#include "avatar/procedural/default_avatar.h"

namespace embody::app::experiment {
namespace {

struct BalanceTasks {
  ik::TaskId com = -1, leftHeel = -1, leftToes = -1, rightToes = -1, leftHand = -1, rightHand = -1, head = -1;
  Eigen::Vector3d comTarget, leftHeelTarget, leftToesTarget, rightToesTarget, leftHandTarget, rightHandTarget;
  Eigen::Quaterniond headTarget;
};

// Task definitions and targets, from the body's rest pose.
TaskAdder balanceTasks(const avatar::AvatarAsset& asset, BalanceTasks& t) {
  return [&asset, &t](ik::ModelBuilder& b, const avatar::BodyModel& body) {
    using avatar::HumanBone;
    const ik::Model& m = body.model;
    auto ik = [&](HumanBone bone) {
      return body.ikJointOfAvatar[static_cast<size_t>(asset.humanoid.joint(bone))];
    };
    auto at = [&](ik::JointId j) { return restFrame(m, j); };
    auto task = [&b](const char* name, ik::TaskType type, ik::JointId joint, int level,
                     const Eigen::Vector3d& offset) { return addExperimentTask(b, name, type, joint, level, offset); };
    const Eigen::Isometry3d ankle = at(body.leftFoot), toes = at(ik(HumanBone::leftToes));
    // The heel: under the ankle, a little behind it, near the sole.
    const Eigen::Vector3d heel(ankle.translation().x(), std::min(ankle.translation().y(), 0.03),
                               ankle.translation().z() - 0.05);
    t.leftHeelTarget = heel;
    t.leftToesTarget = toes.translation();
    t.comTarget = 0.5 * (heel + toes.translation());
    t.rightToesTarget = at(ik(HumanBone::rightToes)).translation() + Eigen::Vector3d(0, 0.15, -0.6);
    t.leftHandTarget = at(ik(HumanBone::leftUpperArm)).translation() + Eigen::Vector3d(0, 0, 0.8);
    t.rightHandTarget = at(ik(HumanBone::rightUpperArm)).translation() + Eigen::Vector3d(0, 0, 0.8);
    t.headTarget = Eigen::Quaterniond(at(body.head).linear());
    t.com = task("com", ik::TaskType::CenterOfMass, 0, 0, Eigen::Vector3d::Zero());
    t.leftHeel = task("left_heel", ik::TaskType::Position, body.leftFoot, 1, ankle.inverse() * heel);
    t.leftToes =
        task("left_toes", ik::TaskType::Position, ik(HumanBone::leftToes), 1, Eigen::Vector3d::Zero());
    t.rightToes =
        task("right_toes", ik::TaskType::Position, ik(HumanBone::rightToes), 2, Eigen::Vector3d::Zero());
    t.leftHand = task("left_hand", ik::TaskType::Position, body.leftHand, 2, Eigen::Vector3d::Zero());
    t.rightHand = task("right_hand", ik::TaskType::Position, body.rightHand, 2, Eigen::Vector3d::Zero());
    t.head = task("head", ik::TaskType::Orientation, body.head, 3, Eigen::Vector3d::Zero());
  };
}

struct BalanceRun {
  ExperimentBody body;
  BalanceTasks tasks;
  Eigen::VectorXd q;
  std::string iterationsCsv;
  double meanIterationUs = 0.0;
  nlohmann::json summary;
};

double groundDistance(const ik::Model& m, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return (m.ground_axes.transpose() * (a - b)).norm();
}

// Task errors of the current kinematics: com (ground), left foot (worst of heel and toes),
// right toes, hands (mean), head orientation (radians).
std::array<double, 5> balanceErrors(const ik::Model& m, const ik::Data& data, const BalanceTasks& t) {
  return {groundDistance(m, data.centerOfMass(), t.comTarget),
          std::max((data.taskPosition(t.leftHeel) - t.leftHeelTarget).norm(),
                   (data.taskPosition(t.leftToes) - t.leftToesTarget).norm()),
          (data.taskPosition(t.rightToes) - t.rightToesTarget).norm(),
          0.5 * ((data.taskPosition(t.leftHand) - t.leftHandTarget).norm() +
                 (data.taskPosition(t.rightHand) - t.rightHandTarget).norm()),
          data.taskOrientation(t.head).angularDistance(t.headTarget)};
}

Result<BalanceRun> solveBalance(const avatar::AvatarAsset& asset, avatar::SpineMode mode, bool coupled,
                                int iterations) {
  BalanceRun run;
  auto body = buildExperimentBody(asset, mode, coupled, balanceTasks(asset, run.tasks));
  if (!body) return Error{body.error()};
  run.body = std::move(*body);
  const ik::Model& m = run.body.body.model;
  const BalanceTasks& t = run.tasks;
  ik::Data data(m);
  Targets targets{data, {}};
  targets.set(t.com, t.comTarget);
  targets.set(t.leftHeel, t.leftHeelTarget);
  targets.set(t.leftToes, t.leftToesTarget);
  targets.set(t.rightToes, t.rightToesTarget);
  targets.set(t.leftHand, t.leftHandTarget);
  targets.set(t.rightHand, t.rightHandTarget);
  targets.set(t.head, t.headTarget);
  if (!targets.error.empty()) return Error{targets.error};
  ik::SolveOptions so;
  run.iterationsCsv =
      "iteration,com_error_m,left_foot_error_m,right_toes_distance_m,hand_distance_m,head_error_deg\n";
  double totalUs = 0.0;
  char line[200];
  for (int i = 1; i <= iterations; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    ik::iterate(m, data, so);
    totalUs += std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    ik::kinematics(m, data, false);
    const auto e = balanceErrors(m, data, t);
    std::snprintf(line, sizeof line, "%d,%.9g,%.9g,%.9g,%.9g,%.9g\n", i, e[0], e[1], e[2], e[3], e[4] / kDeg);
    run.iterationsCsv += line;
  }
  run.q = data.q();
  run.meanIterationUs = totalUs / std::max(1, iterations);
  const auto e = balanceErrors(m, data, t);
  const SpineShape shape = spineShape(run.body, run.q);
  run.summary = bodySummary(run.body, shape, run.q);
  run.summary["com_error_m"] = e[0];
  run.summary["left_foot_error_m"] = e[1];
  run.summary["right_toes_distance_m"] = e[2];
  run.summary["hand_distance_m"] = e[3];
  run.summary["head_orientation_error_deg"] = e[4] / kDeg;
  run.summary["mean_iteration_us"] = run.meanIterationUs;
  return run;
}

std::string balancePlots() {
  return gnuplotHeader("balance", "noenhanced size 1100,820") +
         multiplotFigure("fig10_torsion.png", "2,1", "Balance: torsion along the spine (the paper''s fig. 10), + = front turning to the left") +
         R"gp(set style fill solid 0.8 border -1
set boxwidth 0.38
set grid y
set key top left
set ylabel 'torsion (deg)'
set title 'per vertebra (each carrier joint''s torsion shared by axial range)'
set xtics rotate by 90 right font ',9'
plot 'coupled_vertebrae.csv' skip 1 using ($1-0.2):5:xtic(3) with boxes lc rgb '#1f77b4' title 'coupled', \
     'uncoupled_vertebrae.csv' skip 1 using ($1+0.2):5 with boxes lc rgb '#d62728' title 'uncoupled', \
     0 with lines lc rgb 'gray' notitle
set title 'per spine site (a coupled site without a revolute joint shows 0)'
set xtics rotate by 20 right font ',10'
plot 'coupled_spine.csv' skip 1 using ($1-0.2):6:xtic(2) with boxes lc rgb '#1f77b4' title 'coupled', \
     'uncoupled_spine.csv' skip 1 using ($1+0.2):6 with boxes lc rgb '#d62728' title 'uncoupled', \
     0 with lines lc rgb 'gray' notitle
unset multiplot

set output 'fig_balance_convergence.png'
set terminal pngcairo noenhanced size 1100,420 font 'Sans,11'
set multiplot layout 1,2 title 'Balance: task errors per iteration'
set xtics norotate font ",11"
set style fill empty
set logscale y
set xlabel 'iteration'
set ylabel 'metres'
set key top right
set title 'centre of mass (priority 0) and left foot (1)'
plot 'coupled_iterations.csv' skip 1 using 1:($2+1e-12) with lines lw 2 lc rgb '#1f77b4' title 'CoM, coupled', \
     'uncoupled_iterations.csv' skip 1 using 1:($2+1e-12) with lines lw 2 lc rgb '#d62728' title 'CoM, uncoupled', \
     'coupled_iterations.csv' skip 1 using 1:($3+1e-12) with lines dt 2 lw 2 lc rgb '#1f77b4' title 'foot, coupled', \
     'uncoupled_iterations.csv' skip 1 using 1:($3+1e-12) with lines dt 2 lw 2 lc rgb '#d62728' title 'foot, uncoupled'
unset logscale y
set title 'attractions (priority 2): distance left'
plot 'coupled_iterations.csv' skip 1 using 1:4 with lines lw 2 lc rgb '#1f77b4' title 'right toes, coupled', \
     'uncoupled_iterations.csv' skip 1 using 1:4 with lines lw 2 lc rgb '#d62728' title 'right toes, uncoupled', \
     'coupled_iterations.csv' skip 1 using 1:5 with lines dt 2 lw 2 lc rgb '#1f77b4' title 'hands, coupled', \
     'uncoupled_iterations.csv' skip 1 using 1:5 with lines dt 2 lw 2 lc rgb '#d62728' title 'hands, uncoupled'
unset multiplot
)gp";
}

}  // namespace

bool spineModeOf(const std::string& name, avatar::SpineMode& mode) {
  if (name == "full")
    mode = avatar::SpineMode::Full;
  else if (name == "simplified")
    mode = avatar::SpineMode::Simplified;
  else
    return false;
  return true;
}

int runBalance(const BalanceOptions& o, nlohmann::json& summary) {
  avatar::SpineMode mode;
  if (!spineModeOf(o.spine, mode)) return fail("balance: unknown spine '" + o.spine + "'");
  const avatar::AvatarAsset asset = avatar::buildDefaultAvatar();
  auto coupled = solveBalance(asset, mode, true, o.iterations);
  if (!coupled) return fail("balance: " + coupled.error());
  auto uncoupled = solveBalance(asset, mode, false, o.iterations);
  if (!uncoupled) return fail("balance: " + uncoupled.error());
  std::string error;
  if (!makeFolder(o.common.out, error)) return fail(error);
  for (const BalanceRun* r : {&*coupled, &*uncoupled}) {
    const std::string v = r->body.coupled ? "coupled" : "uncoupled";
    const SpineShape shape = spineShape(r->body, r->q);
    if (!writeFile(o.common.out / (v + "_spine.csv"), spineCsv(r->body, shape)) ||
        !writeFile(o.common.out / (v + "_vertebrae.csv"), vertebraCsv(r->body, shape)) ||
        !writeFile(o.common.out / (v + "_iterations.csv"), r->iterationsCsv))
      return fail("cannot write in " + o.common.out.string());
    summary[v] = r->summary;
  }
  summary["setup"] = {{"iterations", o.iterations}, {"spine", o.spine}, {"avatar", "default"}};
  if (o.common.plots)
    if (auto e = runGnuplot(o.common.out, "plots.gp", balancePlots()); !e.empty()) return fail(e);
  if (o.common.frames) {
    auto renderer = PostureRenderer::create(asset, o.common.frameSize, o.common.frameSize);
    if (!renderer) return fail("balance: rendering: " + renderer.error());
    auto shots = renderPostures(**renderer, o.common.out,
                                {{&coupled->body, coupled->q}, {&uncoupled->body, uncoupled->q}},
                                {"fig9_coupled", "fig9_uncoupled"}, {0.6f, 1.57f}, "fig9_postures.png");
    if (!shots) return fail("balance: rendering: " + shots.error());
  }
  if (!writeFile(o.common.out / "summary.json", summary.dump(2) + "\n"))
    return fail("cannot write summary.json");
  for (const char* v : {"coupled", "uncoupled"}) {
    const auto& s = summary[v];
    std::printf(
        "%-9s CoM error %.2g m, left foot %.2g m, right toes %.3f m, hands %.3f m, head %.2f deg; "
        "torsion sign changes: %d within regions, %d between\n",
        v, s["com_error_m"].get<double>(), s["left_foot_error_m"].get<double>(),
        s["right_toes_distance_m"].get<double>(), s["hand_distance_m"].get<double>(),
        s["head_orientation_error_deg"].get<double>(), s["torsion_sign_changes_within_regions"].get<int>(),
        s["torsion_sign_changes_between_regions"].get<int>());
  }
  std::printf("wrote balance results to %s\n", o.common.out.string().c_str());
  return 0;
}

}  // namespace embody::app::experiment
