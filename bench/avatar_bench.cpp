// Avatar timings: loading, building the default mannequin and the body model, retargeting, and
// one solve + retarget frame on the default avatar.
#include <benchmark/benchmark.h>

#include <algorithm>

#include <cmath>

#include "avatar/body/body_model.h"
#include "avatar/gltf/gltf_loader.h"
#include "avatar/hand/finger_retarget.h"
#include "avatar/avatar_loader.h"
#include "avatar/gltf/glb_writer.h"
#include "avatar/procedural/default_avatar.h"
#include "avatar/vrm/secondary_motion.h"
#include "test_paths.h"
#include "tests/support/vrm_test_avatar.h"

using namespace embody;
using namespace embody::avatar;

static void BM_LoadCesiumMan(benchmark::State& state) {
  const std::string path = test::sharedAsset("CesiumMan.glb");
  if (path.empty()) {
    state.SkipWithError("CesiumMan.glb not found");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(loadAvatarFile(path));
}
BENCHMARK(BM_LoadCesiumMan)->Unit(benchmark::kMillisecond);

static void BM_BuildDefaultAvatar(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(buildDefaultAvatar());
}
BENCHMARK(BM_BuildDefaultAvatar)->Unit(benchmark::kMillisecond);

// Both hands' 30 finger bones from 26 tracked joints each (the mannequin with fingers, a
// relaxed hand curling and uncurling so the result changes every iteration).
static void BM_FingerRetarget(benchmark::State& state) {
  const AvatarAsset a = buildDefaultAvatar(DefaultAvatarOptions{.fingers = true});
  const FingerRig rig = buildFingerRig(a.skeleton, a.humanoid);
  std::array<TrackedHandJoints, 2> hands;
  std::vector<glm::mat4> g;
  computeGlobals(a.skeleton, SkeletonPose::rest(a.skeleton), g);
  for (int h = 0; h < 2; ++h) {  // the avatar's own rest hand as the tracked one
    hands[h].active = true;
    hands[h].position[static_cast<size_t>(HandJoint::Wrist)] = glm::vec3(g[rig.hands[h].hand][3]);
    for (const FingerBone& b : rig.hands[h].bones) {
      hands[h].position[static_cast<size_t>(b.trackedFrom)] = glm::vec3(g[b.joint][3]);
      hands[h].position[static_cast<size_t>(b.trackedTo)] =
          glm::vec3(g[b.joint][3]) + 0.02f * glm::mat3(g[b.joint]) * b.axis;
    }
    hands[h].orientation.fill(glm::quat(1, 0, 0, 0));
    hands[h].valid.fill(true);
  }
  FingerRetargetState st;
  SkeletonPose pose = SkeletonPose::rest(a.skeleton);
  FingerRetargetJob job;
  job.skeleton = &a.skeleton;
  job.rig = &rig;
  job.hands = {&hands[0], &hands[1]};
  job.deltaTime = 0.011f;
  job.state = &st;
  job.pose = &pose;
  int i = 0;
  for (auto _ : state) {
    const size_t tip = static_cast<size_t>(HandJoint::IndexTip);
    hands[0].position[tip].y += (i++ & 1) ? 0.01f : -0.01f;
    job.Run();
    benchmark::DoNotOptimize(pose.local.data());
  }
}
BENCHMARK(BM_FingerRetarget)->Unit(benchmark::kMicrosecond);

static void BM_BuildBodyModel(benchmark::State& state) {
  const AvatarAsset a = buildDefaultAvatar();
  for (auto _ : state) benchmark::DoNotOptimize(buildBodyModel(a));
}
BENCHMARK(BM_BuildBodyModel)->Unit(benchmark::kMillisecond);

static void BM_Retarget(benchmark::State& state) {
  const AvatarAsset a = buildDefaultAvatar();
  auto body = buildBodyModel(a);
  ik::Data data(body->model);
  ik::kinematics(body->model, data, false);
  SkeletonPose pose;
  for (auto _ : state) {
    retarget(body.value(), a, data, pose);
    benchmark::DoNotOptimize(pose.local.data());
  }
}
BENCHMARK(BM_Retarget)->Unit(benchmark::kMicrosecond);

// A frame: the left hand target moves on a small circle; solve (warm start) then retarget.
static void BM_SolveAndRetargetDefault(benchmark::State& state) {
  const AvatarAsset a = buildDefaultAvatar();
  auto body = buildBodyModel(a);
  ik::Data data(body->model);
  ik::kinematics(body->model, data, false);
  for (ik::TaskId t :
       {body->leftFootTask, body->rightFootTask, body->headTask, body->leftHandTask, body->rightHandTask})
    (void)data.setTarget(t, data.jointFrame(body->model.tasks[static_cast<size_t>(t)].desc.joint));
  (void)data.setTarget(body->comTask, data.centerOfMass());
  const Eigen::Isometry3d hand0 = data.jointFrame(body->leftHand);
  SkeletonPose pose;
  int frame = 0;
  for (auto _ : state) {
    Eigen::Isometry3d hand = hand0;
    const double phase = 0.05 * frame++;
    hand.translation() += Eigen::Vector3d(0.0, 0.1 + 0.05 * std::sin(phase), 0.25 + 0.05 * std::cos(phase));
    (void)data.setTarget(body->leftHandTask, hand);
    benchmark::DoNotOptimize(ik::solve(body->model, data));
    retarget(body.value(), a, data, pose);
  }
}
BENCHMARK(BM_SolveAndRetargetDefault)->Unit(benchmark::kMicrosecond);

// The default avatar's body model, coupled spine or uncoupled (the body-iteration benchmarks').
static BodyModel defaultBodyModel(bool coupled) {
  BodyModelOptions options;
  options.coupledSpine = coupled;
  return std::move(buildBodyModel(buildDefaultAvatar(), options)).value();
}

// The avatar's body model with its spine sites' joints fixed (the uncoupled body without its 72
// spine dofs; the hips carry the neck and arms rigidly): 45 dofs, the same tasks, levels and limb
// limits. Whatever a spine model costs, the rest of the body costs at least what this body does,
// so its iteration bounds any spine model's from below (docs/performance.md).
static ik::Model bodyWithoutSpineDofs() {
  const BodyModel body = defaultBodyModel(false);
  const ik::Model& m = body.model;
  std::vector<char> spine(m.joints.size(), 0);  // the head's ancestors below the hips
  for (ik::JointId j = m.joints[static_cast<size_t>(body.head)].desc.parent; j != ik::kNoParent && j != body.hips;
       j = m.joints[static_cast<size_t>(j)].desc.parent)
    spine[static_cast<size_t>(j)] = 1;
  ik::ModelBuilder builder;
  for (size_t j = 0; j < m.joints.size(); ++j) {
    ik::JointDesc d = m.joints[j].desc;
    if (spine[j]) {
      d.type = ik::JointType::Fixed;
      d.lower.clear();
      d.upper.clear();
      d.neutral.clear();
    }
    builder.addJoint(std::move(d));
  }
  for (const ik::InequalityRow& row : m.inequalities)
    if (row.kind == ik::InequalityKind::UserCoupling) builder.addInequality(row);
  for (const ik::Model::Task& task : m.tasks) builder.addTask(task.desc);
  return std::move(builder.build()).value();
}

// The three spines the body-iteration benchmarks compare.
enum class BodySpine { Coupled, Uncoupled, NoDofs };

static ik::Model bodyIkModel(BodySpine spine) {
  if (spine == BodySpine::NoDofs) return bodyWithoutSpineDofs();
  return defaultBodyModel(spine == BodySpine::Coupled).model;
}

// The body-iteration benchmarks' problem: solver state at rest, every task's target taken from a
// bent pose (each dof past the root moved by up to 0.15 rad).
static ik::Data bentPoseProblem(const ik::Model& model) {
  ik::Data probe(model);
  Eigen::VectorXd bent = probe.q();
  for (Eigen::Index i = 6; i < bent.size(); ++i) bent(i) += 0.15 * std::sin(1.7 * static_cast<double>(i));
  (void)probe.setConfiguration(bent);
  ik::kinematics(model, probe, false);
  ik::Data data(model);
  for (size_t t = 0; t < model.tasks.size(); ++t) {
    const auto id = static_cast<ik::TaskId>(t);
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = probe.taskOrientation(id).toRotationMatrix();
    pose.translation() = probe.taskPosition(id);
    (void)data.setTarget(id, pose);
  }
  return data;
}

// One PIK iteration (FK, Jacobians, every clamping pass, q += Δq) of the default avatar's body
// model, the model the runtime solves every frame: coupled spine (24 vertebrae, 33 equality
// rows) or uncoupled. The same state each time: targets from a bent pose, solved from rest.
static void BM_BodyIteration(benchmark::State& state, BodySpine spine, ik::Path path) {
  const ik::Model model = bodyIkModel(spine);
  ik::Data data = bentPoseProblem(model);
  const Eigen::VectorXd start = data.q();
  ik::SolveOptions o;
  o.path = path;
  double passes = 0;
  for (auto _ : state) {
    (void)data.setConfiguration(start);
    ik::iterate(model, data, o);
    passes += data.report().clamp_passes;
    benchmark::DoNotOptimize(data.q().data());
  }
  state.counters["dofs"] = model.dofs;
  state.counters["rows"] = model.task_rows;
  state.counters["equalities"] = static_cast<double>(model.equalities.size());
  state.counters["clamp_passes"] = passes / static_cast<double>(state.iterations());
}
BENCHMARK_CAPTURE(BM_BodyIteration, default_coupled_fast, BodySpine::Coupled, ik::Path::Fast)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_BodyIteration, default_uncoupled_fast, BodySpine::Uncoupled, ik::Path::Fast)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_BodyIteration, default_nospinedofs_fast, BodySpine::NoDofs, ik::Path::Fast)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_BodyIteration, default_coupled_reference, BodySpine::Coupled, ik::Path::Reference)->Unit(benchmark::kMicrosecond);

// One frame of VRM secondary motion on the test bust (8 hair springs of 4 joints, 2 colliders,
// expression look-at, blinking): 90 Hz frames, so 1 or 2 fixed 120 Hz spring steps each.
static void BM_SecondaryMotionBust(benchmark::State& state) {
  const test::VrmTestAvatar bust = test::buildVrmTestAvatar();
  auto bytes = encodeGlb(bust.asset, nullptr, bust.extensionsJson);
  auto asset = loadGltfFromMemory(*bytes, ".");
  if (!asset || !prepareAvatar(*asset, "")) {
    state.SkipWithError("the test bust did not load");
    return;
  }
  SecondaryMotion motion(*asset);
  SkeletonPose pose = SkeletonPose::rest(asset->skeleton);
  const SkeletonPose rest = pose;
  const int head = asset->humanoid.joint(HumanBone::head);
  int frame = 0;
  for (auto _ : state) {
    pose = rest;
    pose.local[static_cast<size_t>(head)].rotation = glm::angleAxis(0.6f * std::sin(0.05f * float(frame++)), glm::vec3(0, 1, 0));
    motion.update(pose, 1.0 / 90.0, glm::vec3(0.5f, 1.6f, 1.0f));
    benchmark::DoNotOptimize(pose.local.data());
  }
}
BENCHMARK(BM_SecondaryMotionBust)->Unit(benchmark::kMicrosecond);

// The same problem, iteration 9 of the solve (the limits and bands the body touches are in
// contact by then), cold (every iteration's clamping loop starts from the equality rows) or warm
// (SolveOptions::warm_active_set: it starts from the rows pinned in the iteration before,
// docs/ik.md). The Data is restored outside the timed region before each timed iteration, in all
// four variants alike (the pause itself costs a few µs of each figure).
static void BM_BodyIterationInSolve(benchmark::State& state, BodySpine spine, bool warm) {
  const ik::Model model = bodyIkModel(spine);
  ik::Data data = bentPoseProblem(model);
  ik::SolveOptions o;
  o.warm_active_set = warm;
  for (int i = 0; i < 8; ++i) ik::iterate(model, data, o);
  const ik::Data snapshot = data;
  double passes = 0, pinned = 0;
  for (auto _ : state) {
    state.PauseTiming();
    data = snapshot;
    state.ResumeTiming();
    ik::iterate(model, data, o);
    passes += data.report().clamp_passes;
    pinned += static_cast<double>(data.report().active_clamps.size());
    benchmark::DoNotOptimize(data.q().data());
  }
  const double n = static_cast<double>(std::max<benchmark::IterationCount>(state.iterations(), 1));
  state.counters["dofs"] = model.dofs;
  state.counters["clamp_passes"] = passes / n;
  state.counters["pinned"] = pinned / n;
}
BENCHMARK_CAPTURE(BM_BodyIterationInSolve, default_coupled_cold, BodySpine::Coupled, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_BodyIterationInSolve, default_uncoupled_cold, BodySpine::Uncoupled, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_BodyIterationInSolve, default_coupled_warm, BodySpine::Coupled, true)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_BodyIterationInSolve, default_uncoupled_warm, BodySpine::Uncoupled, true)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_BodyIterationInSolve, default_nospinedofs_cold, BodySpine::NoDofs, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_BodyIterationInSolve, default_nospinedofs_warm, BodySpine::NoDofs, true)->Unit(benchmark::kMicrosecond);

// The runtime's per-frame use (runtime/avatar_body_solver.cpp): targets that move every frame
// (both hands on 10 cm circles, the head bobbing 3 cm), solve() called for one iteration at a
// time with the runtime's trust region (0.05), until converged or 8 iterations per frame, from
// a state settled on the moving targets. Time per frame; iterations per frame and clamping
// passes per iteration as counters (the per-iteration cost is time / iterations).
static void BM_BodyFrames(benchmark::State& state, BodySpine spine, bool warm) {
  // The body without spine dofs has the uncoupled body's tasks, added in the same order.
  const BodyModel body = defaultBodyModel(spine == BodySpine::Coupled);
  const ik::Model model = bodyIkModel(spine);
  ik::Data data = bentPoseProblem(model);
  ik::SolveOptions o;
  o.max_iterations = 1;
  o.max_level_step = 0.05;
  o.warm_active_set = warm;
  const Eigen::Vector3d left = data.targetPosition(body.leftHandTask), right = data.targetPosition(body.rightHandTask);
  const Eigen::Vector3d head = data.targetPosition(body.headTask);
  long frame = 0, iterations = 0, passes = 0;
  const auto runFrame = [&] {
    const double phase = 0.07 * static_cast<double>(frame++);
    (void)data.setTarget(body.leftHandTask, Eigen::Vector3d(left + 0.1 * Eigen::Vector3d(std::cos(phase), std::sin(phase), 0.0)));
    (void)data.setTarget(body.rightHandTask, Eigen::Vector3d(right + 0.1 * Eigen::Vector3d(0.0, std::sin(phase), std::cos(phase))));
    (void)data.setTarget(body.headTask, Eigen::Vector3d(head + Eigen::Vector3d(0.0, 0.03 * std::sin(0.5 * phase), 0.0)));
    for (int i = 0; i < 8; ++i) {
      const ik::SolveReport& r = ik::solve(model, data, o);
      iterations += r.iterations;
      passes += r.clamp_passes;
      if (r.iterations == 0 || r.stop != ik::StopReason::IterationCap) break;
    }
  };
  for (int settle = 0; settle < 90; ++settle) runFrame();
  iterations = passes = 0;
  for (auto _ : state) {
    runFrame();
    benchmark::DoNotOptimize(data.q().data());
  }
  const double frames = static_cast<double>(std::max<benchmark::IterationCount>(state.iterations(), 1));
  state.counters["iterations"] = static_cast<double>(iterations) / frames;
  state.counters["clamp_passes"] = static_cast<double>(passes) / std::max(1.0, static_cast<double>(iterations));
}
BENCHMARK_CAPTURE(BM_BodyFrames, default_coupled_cold, BodySpine::Coupled, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_BodyFrames, default_uncoupled_cold, BodySpine::Uncoupled, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_BodyFrames, default_coupled_warm, BodySpine::Coupled, true)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_BodyFrames, default_uncoupled_warm, BodySpine::Uncoupled, true)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_BodyFrames, default_nospinedofs_cold, BodySpine::NoDofs, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_BodyFrames, default_nospinedofs_warm, BodySpine::NoDofs, true)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
