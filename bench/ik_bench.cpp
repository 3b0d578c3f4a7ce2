// PIK benchmarks (Google Benchmark). Names are stable so scripts can find them:
//   BM_PikPass/<model>/<path>    one pass of the priority loop from given Jacobians (no FK, no
//                                clamping re-evaluation)
//   BM_Iteration/<model>/<path>  a full iteration: FK, Jacobians, every clamping pass, q += Δq
//   BM_Peer/kdl/pass, BM_Peer/kdl/solve   Orocos KDL on the same humanoid targets (when found)
// <model>: humanoid60 | spine24_coupled | spine24_uncoupled;  <path>: fast | reference.
// The spine models are ik's sample spine (sample_models.h), not the anatomical spine.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "tests/support/sample_models.h"
#include "ik/solver.h"

#ifdef EMBODY_HAVE_KDL
#include <kdl/tree.hpp>
#include <kdl/treefksolverpos_recursive.hpp>
#include <kdl/treeiksolverpos_nr_jl.hpp>
#include <kdl/treeiksolvervel_wdls.hpp>
#endif

namespace {

using namespace embody;
using namespace embody::ik;

const Model& modelByName(const std::string& name) {
  static const Model humanoid = test::sampleHumanoid().value();
  static const Model coupled = test::sampleSpine(true).value();
  static const Model uncoupled = test::sampleSpine(false).value();
  if (name == "humanoid60") return humanoid;
  if (name == "spine24_coupled") return coupled;
  return uncoupled;
}

// A configuration drawn from the middle half of every joint's range (root rotation ±0.5 rad).
Eigen::VectorXd randomConfiguration(const Model& model, std::mt19937& rng, double shrink = 0.5) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::VectorXd q(model.dofs);
  for (const Model::Joint& j : model.joints) {
    for (int k = 0; k < j.dof_count; ++k) {
      double lo = j.desc.lower[k], hi = j.desc.upper[k];
      if (!std::isfinite(lo)) lo = -0.5;
      if (!std::isfinite(hi)) hi = 0.5;
      const double mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo) * shrink;
      q(j.first_dof + k) = mid - half + 2 * half * u(rng);
    }
  }
  return q;
}

// Sets every task's target to its value at configuration q.
void targetsFrom(const Model& model, Data& data, const Eigen::VectorXd& q) {
  Data probe(model);
  (void)probe.setConfiguration(q);
  kinematics(model, probe, false);
  for (size_t t = 0; t < model.tasks.size(); ++t) {
    const TaskId id = static_cast<TaskId>(t);
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = probe.taskOrientation(id).toRotationMatrix();
    pose.translation() = probe.taskPosition(id);
    (void)data.setTarget(id, pose);
  }
}

// A problem a few iterations away from its solution: targets from one random configuration,
// the state from the neutral pose (every task has a real error, some joints clamp).
Data problem(const Model& model, unsigned seed) {
  std::mt19937 rng(seed);
  Data data(model);
  targetsFrom(model, data, randomConfiguration(model, rng));
  return data;
}

void pikPass(benchmark::State& state, const std::string& name, Path path) {
  const Model& model = modelByName(name);
  Data data = problem(model, 42);
  kinematics(model, data);
  SolveOptions o;
  o.path = path;
  for (auto _ : state) benchmark::DoNotOptimize(priorityPass(model, data, o).data());
  state.counters["dofs"] = model.dofs;
  state.counters["rows"] = model.task_rows;
}

void iteration(benchmark::State& state, const std::string& name, Path path) {
  const Model& model = modelByName(name);
  Data data = problem(model, 42);
  const Eigen::VectorXd start = data.q();
  SolveOptions o;
  o.path = path;
  double passes = 0, clamps = 0;
  for (auto _ : state) {
    (void)data.setConfiguration(start);  // the same iteration every time (not a converged one)
    iterate(model, data, o);
    passes += data.report().clamp_passes;
    clamps += static_cast<double>(data.report().active_clamps.size());
    benchmark::DoNotOptimize(data.q().data());
  }
  state.counters["clamp_passes"] = passes / static_cast<double>(state.iterations());
  state.counters["clamps"] = clamps / static_cast<double>(state.iterations());
}

#ifdef EMBODY_HAVE_KDL
// The sample humanoid as a KDL tree: each joint becomes a fixed segment for its rest transform,
// then one 1-dof segment per dof (free root: 3 translations + 3 rotations; ball: X, Y, Z Euler
// rotations; swing: rotations about the two swing axes; revolute: its axis). The five
// end-effector frames carry the task offsets. Limits map per dof (Euler angles for ball joints).
struct KdlHumanoid {
  KDL::Tree tree{"world"};
  std::vector<std::string> endpoints;
  std::vector<TaskId> endpoint_tasks;
  KDL::JntArray q_min, q_max, neutral;

  explicit KdlHumanoid(const Model& model) {
    std::vector<std::string> tipOf(model.joints.size());
    std::vector<double> lo, hi, mid;
    auto frame = [](const Eigen::Isometry3d& t) {
      const Eigen::Matrix3d r = t.linear();
      return KDL::Frame(KDL::Rotation(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)),
                        KDL::Vector(t.translation().x(), t.translation().y(), t.translation().z()));
    };
    auto add = [&](const std::string& name, const KDL::Joint& joint, const KDL::Frame& f, const std::string& parent) {
      tree.addSegment(KDL::Segment(name, joint, f), parent);
      return name;
    };
    for (size_t j = 0; j < model.joints.size(); ++j) {
      const Model::Joint& joint = model.joints[j];
      const JointDesc& d = joint.desc;
      std::string parent = d.parent == kNoParent ? "world" : tipOf[d.parent];
      parent = add(d.name + "_rest", KDL::Joint(KDL::Joint::None), frame(d.rest), parent);
      std::vector<KDL::Joint> dofs;
      auto vec = [](const Eigen::Vector3d& v) { return KDL::Vector(v.x(), v.y(), v.z()); };
      switch (d.type) {
        case JointType::Free:
          dofs = {KDL::Joint(KDL::Joint::TransX), KDL::Joint(KDL::Joint::TransY), KDL::Joint(KDL::Joint::TransZ),
                  KDL::Joint(KDL::Joint::RotX), KDL::Joint(KDL::Joint::RotY), KDL::Joint(KDL::Joint::RotZ)};
          break;
        case JointType::Ball:
          dofs = {KDL::Joint(KDL::Joint::RotX), KDL::Joint(KDL::Joint::RotY), KDL::Joint(KDL::Joint::RotZ)};
          break;
        case JointType::Swing:
          dofs = {KDL::Joint(d.name + "_s0", KDL::Vector::Zero(), vec(joint.swing_basis.col(0)), KDL::Joint::RotAxis),
                  KDL::Joint(d.name + "_s1", KDL::Vector::Zero(), vec(joint.swing_basis.col(1)), KDL::Joint::RotAxis)};
          break;
        case JointType::Revolute:
          dofs = {KDL::Joint(d.name + "_r", KDL::Vector::Zero(), vec(d.axis), KDL::Joint::RotAxis)};
          break;
        case JointType::Fixed: break;
      }
      for (size_t k = 0; k < dofs.size(); ++k) {
        parent = add(d.name + "_" + std::to_string(k), dofs[k], KDL::Frame::Identity(), parent);
        const double l = std::isfinite(d.lower[k]) ? d.lower[k] : (d.type == JointType::Free && k < 3 ? -10.0 : -std::numbers::pi);
        const double h = std::isfinite(d.upper[k]) ? d.upper[k] : (d.type == JointType::Free && k < 3 ? 10.0 : std::numbers::pi);
        lo.push_back(l);
        hi.push_back(h);
        mid.push_back(d.neutral[k]);
      }
      tipOf[j] = parent;
    }
    for (const char* name : {"left_foot", "right_foot", "head", "left_hand", "right_hand"}) {
      const TaskId t = model.findTask(name);
      const TaskDesc& d = model.tasks[t].desc;
      Eigen::Isometry3d offset = Eigen::Isometry3d::Identity();
      offset.translation() = d.offset;
      endpoints.push_back(add(std::string(name) + "_ee", KDL::Joint(KDL::Joint::None), frame(offset), tipOf[d.joint]));
      endpoint_tasks.push_back(t);
    }
    const unsigned n = tree.getNrOfJoints();
    q_min.resize(n);
    q_max.resize(n);
    neutral.resize(n);
    for (unsigned i = 0; i < n; ++i) {
      q_min(i) = lo[i];
      q_max(i) = hi[i];
      neutral(i) = mid[i];
    }
  }
};

KDL::Frame kdlFrame(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  return KDL::Frame(KDL::Rotation::Quaternion(q.x(), q.y(), q.z(), q.w()), KDL::Vector(p.x(), p.y(), p.z()));
}

struct PeerTargets {
  std::vector<KDL::Frames> frames;               // per problem: the five end-effector frames
  std::vector<Eigen::VectorXd> configurations;   // the configurations they come from
};

PeerTargets peerTargets(const Model& model, const KdlHumanoid& kdl, int count) {
  PeerTargets out;
  std::mt19937 rng(2024);
  for (int i = 0; i < count; ++i) {
    const Eigen::VectorXd q = randomConfiguration(model, rng);
    Data probe(model);
    (void)probe.setConfiguration(q);
    kinematics(model, probe, false);
    KDL::Frames f;
    for (size_t e = 0; e < kdl.endpoints.size(); ++e)
      f[kdl.endpoints[e]] = kdlFrame(probe.taskPosition(kdl.endpoint_tasks[e]), probe.taskOrientation(kdl.endpoint_tasks[e]));
    out.frames.push_back(std::move(f));
    out.configurations.push_back(q);
  }
  return out;
}

bool kdlReached(const KdlHumanoid& kdl, KDL::TreeFkSolverPos_recursive& fk, const KDL::JntArray& q, const KDL::Frames& target) {
  for (const std::string& e : kdl.endpoints) {
    KDL::Frame f;
    if (fk.JntToCart(q, f, e) < 0) return false;
    if ((f.p - target.at(e).p).Norm() > 1e-4) return false;
  }
  return true;
}

// Embody on the same problems from the neutral pose: success rate and mean solve time.
std::pair<double, double> embodyOnPeerProblems(const Model& model, const PeerTargets& problems) {
  int ok = 0;
  double seconds = 0;
  SolveOptions o;
  o.max_iterations = 100;
  for (const Eigen::VectorXd& q : problems.configurations) {
    Data data(model);
    targetsFrom(model, data, q);
    const auto t0 = std::chrono::steady_clock::now();
    const SolveReport& r = solve(model, data, o);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    bool reached = r.converged();
    for (const TaskResidual& t : r.tasks) reached = reached && t.position <= 1e-4;
    ok += reached ? 1 : 0;
  }
  return {static_cast<double>(ok) / static_cast<double>(problems.configurations.size()),
          seconds / static_cast<double>(problems.configurations.size())};
}

double embodyPassSeconds(const Model& model) {
  Data data = problem(model, 42);
  kinematics(model, data);
  const int reps = 2000;
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < reps; ++i) benchmark::DoNotOptimize(priorityPass(model, data, {}).data());
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / reps;
}

void peerPass(benchmark::State& state) {
  const Model& model = modelByName("humanoid60");
  const KdlHumanoid kdl(model);
  KDL::TreeIkSolverVel_wdls solver(kdl.tree, kdl.endpoints);
  const PeerTargets problems = peerTargets(model, kdl, 1);
  KDL::TreeFkSolverPos_recursive fk(kdl.tree);
  KDL::Twists twists;
  for (const std::string& e : kdl.endpoints) {
    KDL::Frame f;
    fk.JntToCart(kdl.neutral, f, e);
    twists[e] = KDL::diff(f, problems.frames[0].at(e));
  }
  KDL::JntArray qdot(kdl.tree.getNrOfJoints());
  for (auto _ : state) benchmark::DoNotOptimize(solver.CartToJnt(kdl.neutral, twists, qdot));
  // The ratio needs both timings in one place: time a few hundred KDL passes here too.
  const int reps = 300;
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < reps; ++i) benchmark::DoNotOptimize(solver.CartToJnt(kdl.neutral, twists, qdot));
  const double theirs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / reps;
  const double ours = embodyPassSeconds(model);
  state.counters["dofs"] = kdl.tree.getNrOfJoints();
  state.counters["embody_pass_us"] = ours * 1e6;
  state.counters["kdl_over_embody"] = theirs / ours;
}

void peerSolve(benchmark::State& state) {
  const Model& model = modelByName("humanoid60");
  const KdlHumanoid kdl(model);
  KDL::TreeFkSolverPos_recursive fk(kdl.tree);
  KDL::TreeIkSolverVel_wdls vel(kdl.tree, kdl.endpoints);
  KDL::TreeIkSolverPos_NR_JL pos(kdl.tree, kdl.endpoints, kdl.q_min, kdl.q_max, fk, vel, 100, 1e-5);
  static const PeerTargets problems = peerTargets(model, kdl, 50);
  KDL::JntArray q(kdl.tree.getNrOfJoints());
  // Success rates over all problems (untimed, once: Google Benchmark calls this function several
  // times), then the timed loop cycles through the problems.
  static const double kdlRate = [&] {
    int solved = 0;
    for (const KDL::Frames& target : problems.frames) {
      pos.CartToJnt(kdl.neutral, target, q);
      solved += kdlReached(kdl, fk, q, target) ? 1 : 0;
    }
    return static_cast<double>(solved) / static_cast<double>(problems.frames.size());
  }();
  static const std::pair<double, double> embody = embodyOnPeerProblems(model, problems);
  size_t next = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(pos.CartToJnt(kdl.neutral, problems.frames[next], q));
    next = (next + 1) % problems.frames.size();
  }
  state.counters["kdl_success_rate"] = kdlRate;
  state.counters["embody_success_rate"] = embody.first;
  state.counters["embody_solve_us"] = embody.second * 1e6;
}
#endif

int registerAll() {
  for (const char* model : {"humanoid60", "spine24_coupled", "spine24_uncoupled"}) {
    for (const auto& [pathName, path] : {std::pair{"fast", Path::Fast}, std::pair{"reference", Path::Reference}}) {
      const std::string m = model, p = pathName;
      const Path pa = path;
      benchmark::RegisterBenchmark(("BM_PikPass/" + m + "/" + p).c_str(),
                                   [m, pa](benchmark::State& s) { pikPass(s, m, pa); })
          ->Unit(benchmark::kMicrosecond);
      benchmark::RegisterBenchmark(("BM_Iteration/" + m + "/" + p).c_str(),
                                   [m, pa](benchmark::State& s) { iteration(s, m, pa); })
          ->Unit(benchmark::kMicrosecond);
    }
  }
#ifdef EMBODY_HAVE_KDL
  benchmark::RegisterBenchmark("BM_Peer/kdl/pass", peerPass)->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("BM_Peer/kdl/solve", peerSolve)->Unit(benchmark::kMillisecond);
#endif
  return 0;
}

const int registered = registerAll();

}  // namespace

BENCHMARK_MAIN();
