// embody_random_ik: solves random IK problems on the body models (the default mannequin's, with
// the coupled spine and with one uncoupled ball per spine site) and reports what must hold on
// every one of them: no NaN, the equality (coupling) rows met to 1e-9, the inequalities (joint
// limits, coupling ranges) violated by at most the solver's tolerance, and iterations to converge.
//
//   embody_random_ik [--problems N] [--threads T] [--max-iterations I] [--seed S] [--walk-step RAD]
//                    [--json FILE]
//
// A problem: a random configuration, its task targets by forward kinematics (head pose, hands,
// feet, centre of mass, as the runtime sets them), solved warm-started from the previous
// problem's solution. Per model, half the problems are uniform inside the limits (the hips within
// 0.3 m and 0.5 rad of neutral: far apart, a stress test), half a random walk of --walk-step per
// dof (consecutive tracking frames). docs/performance.md has the figures.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "avatar/body/body_model.h"
#include "avatar/procedural/default_avatar.h"
#include "ik/solver.h"

using namespace embody;

namespace {

struct Figures {
  long problems = 0, nanSolutions = 0, converged = 0;
  double equalityResidualMax = 0.0, inequalityViolationMax = 0.0;
  int worstInequality = -1;        // the row of inequalityViolationMax
  bool worstReported = false;      // ... listed in SolveReport::unsatisfiable by the solver
  std::vector<int> worstActive;    // ... and the rows pinned in that solve's last iteration
  std::vector<int> iterations;  // of converged problems
  void merge(const Figures& o) {
    problems += o.problems;
    nanSolutions += o.nanSolutions;
    converged += o.converged;
    equalityResidualMax = std::max(equalityResidualMax, o.equalityResidualMax);
    if (o.inequalityViolationMax > inequalityViolationMax) {
      inequalityViolationMax = o.inequalityViolationMax;
      worstInequality = o.worstInequality;
      worstReported = o.worstReported;
      worstActive = o.worstActive;
    }
    iterations.insert(iterations.end(), o.iterations.begin(), o.iterations.end());
  }
};

// step = 0: uniform inside the limits (the hips within 0.3 m / 0.5 rad of neutral). step > 0: a
// random walk from `previous`, each dof moving by at most `step` (radians; hips metres / 2), kept
// inside the same box: consecutive tracking frames.
Eigen::VectorXd randomConfiguration(const ik::Model& m, std::mt19937_64& rng, const Eigen::VectorXd& previous,
                                    double step) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Eigen::VectorXd q = m.neutral;
  for (const auto& j : m.joints) {
    for (int c = 0; c < j.dof_count; ++c) {
      const int i = j.first_dof + c;
      double lo, hi;
      if (j.desc.type == ik::JointType::Free) {
        const double r = c < 3 ? 0.3 : 0.5;
        lo = q[i] - r;
        hi = q[i] + r;
      } else {
        lo = c < static_cast<int>(j.desc.lower.size()) ? j.desc.lower[c] : -ik::kUnbounded;
        hi = c < static_cast<int>(j.desc.upper.size()) ? j.desc.upper[c] : ik::kUnbounded;
        lo = std::isfinite(lo) ? lo : q[i] - 1.0;
        hi = std::isfinite(hi) ? hi : q[i] + 1.0;
      }
      if (step > 0.0) {
        const double s = j.desc.type == ik::JointType::Free && c < 3 ? 0.5 * step : step;
        q[i] = std::clamp(previous[i] + s * (2.0 * unit(rng) - 1.0), lo, hi);
      } else {
        q[i] = lo + (hi - lo) * unit(rng);
      }
    }
  }
  return q;
}

// Targets of every enabled task at configuration q (forward kinematics on a scratch Data).
void setTargetsFrom(const ik::Model& m, ik::Data& scratch, const Eigen::VectorXd& q, ik::Data& data) {
  (void)scratch.setConfiguration(q);
  ik::kinematics(m, scratch, false);
  for (size_t t = 0; t < m.tasks.size(); ++t) {
    const auto id = static_cast<ik::TaskId>(t);
    if (!data.enabled(id)) continue;
    switch (m.tasks[t].desc.type) {
      case ik::TaskType::Orientation: (void)data.setTarget(id, scratch.taskOrientation(id)); break;
      case ik::TaskType::Pose: {
        Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
        p.linear() = scratch.taskOrientation(id).toRotationMatrix();
        p.translation() = scratch.taskPosition(id);
        (void)data.setTarget(id, p);
        break;
      }
      default: (void)data.setTarget(id, scratch.taskPosition(id)); break;
    }
  }
}

double equalityResidual(const ik::Model& m, const Eigen::VectorXd& q) {
  double worst = 0.0;
  for (int r = 0; r < m.equality_matrix.rows(); ++r) {
    if (std::find(m.dependent_equalities.begin(), m.dependent_equalities.end(), r) != m.dependent_equalities.end())
      continue;
    worst = std::max(worst, std::abs(m.equality_matrix.row(r).dot(q) - m.equality_rhs[r]));
  }
  return worst;
}

// The largest max(Σ c q − rhs, 0) and its row (-1 when none is violated).
std::pair<double, int> inequalityViolation(const ik::Model& m, const Eigen::VectorXd& q) {
  std::pair<double, int> worst{0.0, -1};
  for (size_t r = 0; r < m.inequalities.size(); ++r) {
    double lhs = 0.0;
    for (const auto& t : m.inequalities[r].terms) lhs += t.coefficient * q[m.dofIndex(t.dof)];
    if (lhs - m.inequalities[r].rhs > worst.first) worst = {lhs - m.inequalities[r].rhs, static_cast<int>(r)};
  }
  return worst;
}

Figures solveRandom(const ik::Model& m, long problems, uint64_t seed, int maxIterations, double step) {
  std::mt19937_64 rng(seed);
  ik::Data data(m), scratch(m);
  (void)data.setEnabled(m.findTask("hips"), false);
  ik::SolveOptions o;
  o.max_iterations = maxIterations;
  Figures f;
  f.iterations.reserve(static_cast<size_t>(problems));
  Eigen::VectorXd previous = m.neutral;
  for (long p = 0; p < problems; ++p) {
    previous = randomConfiguration(m, rng, previous, step);
    setTargetsFrom(m, scratch, previous, data);
    const ik::SolveReport& r = ik::solve(m, data, o);
    const Eigen::VectorXd& q = data.q();
    ++f.problems;
    if (!q.allFinite()) {
      ++f.nanSolutions;
      (void)data.setConfiguration(m.neutral);
      continue;
    }
    f.equalityResidualMax = std::max(f.equalityResidualMax, equalityResidual(m, q));
    if (const auto [v, row] = inequalityViolation(m, q); v > f.inequalityViolationMax) {
      f.inequalityViolationMax = v;
      f.worstInequality = row;
      f.worstReported = std::find(r.unsatisfiable.begin(), r.unsatisfiable.end(), row) != r.unsatisfiable.end();
      f.worstActive = r.active_clamps;
    }
    if (r.converged()) {
      ++f.converged;
      f.iterations.push_back(r.iterations);
    }
  }
  return f;
}

nlohmann::json activeRowNames(const ik::Model& m, const std::vector<int>& rows) {
  nlohmann::json names = nlohmann::json::array();
  for (int r : rows) names.push_back(m.inequalities[static_cast<size_t>(r)].name);
  return names;
}

nlohmann::json run(const std::string& name, const ik::Model& m, long problems, int threads, uint64_t seed,
                   int maxIterations, double step) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Figures> parts(static_cast<size_t>(threads));
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([&, t] {
      const long share = problems / threads + (t < problems % threads ? 1 : 0);
      parts[static_cast<size_t>(t)] = solveRandom(m, share, seed + 7919u * static_cast<uint64_t>(t), maxIterations, step);
    });
  for (auto& th : pool) th.join();
  Figures all;
  for (const auto& p : parts) all.merge(p);
  std::sort(all.iterations.begin(), all.iterations.end());
  auto pct = [&](double p) {
    return all.iterations.empty() ? 0 : all.iterations[static_cast<size_t>(p * (all.iterations.size() - 1))];
  };
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return {{"model", name},
          {"problems_kind", step > 0.0 ? "walk, step " + std::to_string(step) + " rad" : std::string("uniform")},
          {"dofs", m.dofs},
          {"equality_rows", m.equality_matrix.rows()},
          {"inequality_rows", m.inequalities.size()},
          {"problems", all.problems},
          {"nan_solutions", all.nanSolutions},
          {"equality_residual_max", all.equalityResidualMax},
          {"inequality_violation_max", all.inequalityViolationMax},
          {"inequality_violation_row", all.worstInequality < 0 ? "" : m.inequalities[all.worstInequality].name},
          {"inequality_violation_reported_unsatisfiable", all.worstReported},
          {"inequality_violation_active_rows", activeRowNames(m, all.worstActive)},
          {"converged_fraction", all.problems ? double(all.converged) / double(all.problems) : 0.0},
          {"iterations_p50", pct(0.5)},
          {"iterations_p99", pct(0.99)},
          {"iterations_max", all.iterations.empty() ? 0 : all.iterations.back()},
          {"max_iterations", maxIterations},
          {"seconds", seconds},
          {"threads", threads}};
}

}  // namespace

int main(int argc, char** argv) {
  long problems = 1000000;
  int threads = std::max(1u, std::thread::hardware_concurrency());
  int maxIterations = 40;  // the runtime's AvatarBodyOptions::maxIterations
  uint64_t seed = 1;
  double walkStep = 0.05;  // radians per dof per problem: about a 72 Hz frame of brisk motion
  std::string jsonPath;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool hasValue = i + 1 < argc;
    if (a == "--problems" && hasValue) problems = std::stol(argv[++i]);
    else if (a == "--threads" && hasValue) threads = std::max(1, std::stoi(argv[++i]));
    else if (a == "--max-iterations" && hasValue) maxIterations = std::max(1, std::stoi(argv[++i]));
    else if (a == "--seed" && hasValue) seed = std::stoull(argv[++i]);
    else if (a == "--walk-step" && hasValue) walkStep = std::stod(argv[++i]);
    else if (a == "--json" && hasValue) jsonPath = argv[++i];
    else {
      std::fprintf(stderr, "usage: embody_random_ik [--problems N] [--threads T] [--max-iterations I] [--seed S] "
                           "[--walk-step RAD] [--json FILE]\n");
      return 2;
    }
  }
  const avatar::AvatarAsset asset = avatar::buildDefaultAvatar();
  nlohmann::json out = nlohmann::json::array();
  bool ok = true;
  for (bool coupled : {true, false}) {
    avatar::BodyModelOptions bo;
    bo.coupledSpine = coupled;
    auto body = avatar::buildBodyModel(asset, bo);
    if (!body) return std::fprintf(stderr, "embody_random_ik: error: %s\n", body.error().c_str()), 1;
    for (double step : {0.0, walkStep}) {
      const auto j = run(coupled ? "mannequin, coupled spine" : "mannequin, uncoupled spine", body->model,
                         problems / 2, threads, seed, maxIterations, step);
      std::printf("%s\n", j.dump(2).c_str());
      ok = ok && j["nan_solutions"] == 0 && j["equality_residual_max"].get<double>() <= 1e-9;
      out.push_back(j);
    }
  }
  if (!jsonPath.empty()) std::ofstream(jsonPath) << out.dump(2) << "\n";
  return ok ? 0 : 1;
}
