#pragma once
// The prioritized IK solver: one iteration exactly as in ../shared/reference/pik.md, repeated by
// solve() until every task is within tolerance, an iteration cap, or a deadline.
//
//   const Model& model = ...;                 // built once (model.h)
//   ik::Data data(model);                     // all buffers allocated here, once
//   data.setTarget(head, headPose);           // per frame: targets, weights, on/off
//   const ik::SolveReport& r = ik::solve(model, data, options);   // allocation-free
//   use(data.q());                            // warm start: the next solve starts from here
//
// Two implementations of the priority loop give the same Δq (to round-off):
//   Path::Fast      orthonormal null-space basis of the active rows, reduced coordinates, a small
//                   m_k x m_k Cholesky per level (eigen-decomposition only for rank-deficient
//                   levels) (the default);
//   Path::Reference plain n x n projectors and a JacobiSVD per level (what Fast is tested against).
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "ik/model.h"
#include "core/result.h"

namespace embody::ik {

enum class Path : std::uint8_t { Fast, Reference };

// Injectable time source, so deadline behaviour is testable deterministically.
class Clock {
 public:
  using time_point = std::chrono::steady_clock::time_point;
  virtual ~Clock() = default;
  virtual time_point now() const = 0;
};
// std::chrono::steady_clock.
const Clock& steadyClock();

struct SolveOptions {
  Path path = Path::Fast;
  int max_iterations = 100;
  // Iterations run even when every task is already within its tolerance (then a new frame's
  // targets move the body every frame instead of only once the error exceeds a tolerance).
  int min_iterations = 0;
  int max_clamp_passes = 16;    // clamping-loop cap per iteration
  bool clamping = true;         // false: inequalities are ignored (tests of the priority loop)
  // Warm active set: each iteration's clamping loop starts from the rows pinned in the previous
  // one (kept in Data, across solve() calls) that still hold at their bounds, reusing their
  // factorisation, and releases those whose multiplier says the tasks now pull them inside.
  // false: every iteration starts from the equality rows (the textbook loop). docs/ik.md.
  bool warm_active_set = false;
  // Smooth damping (iTaSC rule), one λ per level from its smallest singular value σ:
  // λ² = (1 - (σ/eps)²) λmax² when σ < eps, else 0. Projectors are never damped.
  double damping_max = 0.1;     // λmax
  double damping_eps = 0.2;     // eps
  double rank_tolerance = 1e-6; // singular values below this are rank-deficient (projectors)
  // Trust region per level: the norm of one level's contribution to Δq is capped here (scaling a
  // level's contribution keeps every level above it exact: it lies in their null space). A
  // lower level that conflicts with higher ones keeps a large compensated error e_k - J_k Δq
  // every iteration; near its singular directions the damped step can still reach
  // |e|/(2 λmax), and steps that large make the second-order disturbance of the higher levels
  // (the linear model only protects them to first order) large enough to drag them off and
  // drift. 0 or infinity: no cap.
  double max_level_step = 0.1;
  double inequality_tolerance = 1e-9;  // a row counts as violated above rhs + this
  // Scale the task part of the step down when it reverses the previous one (damps period-2
  // cycles near unreachable targets; priorities and pinned rows stay exact). See docs/ik.md.
  bool oscillation_guard = true;
  double min_step = 1e-12;      // |Δq| below this: stalled (e.g. an unreachable target), stop
  // Deadline: checked before each iteration, so solve() returns by the deadline plus at most one
  // iteration. `clock` defaults to steadyClock(); it must outlive the call.
  std::optional<Clock::time_point> deadline;
  const Clock* clock = nullptr;
};

enum class StopReason : std::uint8_t { Converged, IterationCap, Deadline, Stalled, InvalidState };
const char* toString(StopReason reason);

struct TaskResidual {
  double position = 0.0;  // metres (0 for orientation-only tasks)
  double rotation = 0.0;  // radians (0 for position / CoM tasks)
  bool satisfied = false;
  bool enabled = false;
};

// Filled by solve() into storage owned by Data (no allocation per call).
struct SolveReport {
  int iterations = 0;
  std::chrono::nanoseconds elapsed{0};
  StopReason stop = StopReason::IterationCap;
  std::vector<TaskResidual> tasks;    // per task (model.tasks order), after the last iteration
  std::vector<double> levels;         // per level: norm of the stacked (unclamped) error
  std::vector<int> active_clamps;     // inequality rows pinned in the last iteration
  std::vector<int> unsatisfiable;     // inequality rows violated and dependent on the active set,
                                      // or still violated after the pass cap (last iteration)
  int clamp_passes = 0;               // passes in the last iteration
  bool converged() const { return stop == StopReason::Converged; }
};

// What one iteration needs and produces; tests and benchmarks use the pieces separately.
struct Workspace;  // defined in solver_detail.h (private)

// The mutable side: configuration, per-frame task state, and every buffer the solver needs.
class Data {
 public:
  explicit Data(const Model& model);
  ~Data();
  Data(Data&&) noexcept;
  Data& operator=(Data&&) noexcept;
  Data(const Data&);
  Data& operator=(const Data&);

  // Configuration (warm start). Rejected with the state unchanged when the size is wrong or an
  // entry is not finite.
  Status setConfiguration(const Eigen::VectorXd& q);
  const Eigen::VectorXd& q() const;
  // The next iteration's clamping loop starts from the equality rows only (a cold start of the
  // warm active set). Not needed for correctness: carried rows no longer at their bounds (after
  // setConfiguration, for example) are dropped by the solver itself.
  void forgetActiveSet();

  // Per-frame task state. Every setter validates (task index, finite numbers, task type) and
  // leaves the state unchanged on error.
  Status setTarget(TaskId task, const Eigen::Vector3d& position);       // Position, CoM
  Status setTarget(TaskId task, const Eigen::Quaterniond& orientation); // Orientation
  Status setTarget(TaskId task, const Eigen::Isometry3d& pose);         // Pose (any type: parts)
  Status setWeight(TaskId task, double weight);                         // > 0, finite
  Status setEnabled(TaskId task, bool enabled);
  // Per-frame bound of an inequality row (model.inequalities index): Σ coefficient q <= rhs from
  // the next iteration on, e.g. a band between spine regions that widens with a posture. Starts
  // at the model's rhs. A pinned row whose bound moves is re-pinned or released by the clamping
  // loop like any other (its carried value is re-read each iteration).
  Status setInequalityBound(int row, double rhs);
  double inequalityBound(int row) const;
  bool enabled(TaskId task) const;
  const Eigen::Vector3d& targetPosition(TaskId task) const;
  const Eigen::Quaterniond& targetOrientation(TaskId task) const;

  // Forward kinematics results of the last kinematics() call (or solve()).
  const Eigen::Isometry3d& jointFrame(JointId joint) const;
  Eigen::Vector3d taskPosition(TaskId task) const;     // world point / CoM
  Eigen::Quaterniond taskOrientation(TaskId task) const;
  const Eigen::Vector3d& centerOfMass() const;

  const SolveReport& report() const;

  Workspace& workspace() { return *ws_; }
  const Workspace& workspace() const { return *ws_; }

 private:
  std::unique_ptr<Workspace> ws_;
};

// Forward kinematics of data.q(): joint frames, CoM, and (when `jacobians`) the stacked task
// Jacobian and clamped errors. Public for tests and benchmarks.
void kinematics(const Model& model, Data& data, bool jacobians = true);

// The stacked task Jacobian (task_rows x n, recruitment and weights applied) and error vector of
// the last kinematics() call; rows of disabled tasks are zero.
const Eigen::MatrixXd& taskJacobian(const Data& data);
const Eigen::VectorXd& taskError(const Data& data);

// One pass of the priority loop from the current Jacobians with the equality rows as the active
// set (no FK, no clamping). Does not change q. Returns Δq.
const Eigen::VectorXd& priorityPass(const Model& model, Data& data, const SolveOptions& options);

// One full iteration: kinematics, active set reset, every clamping pass, q += Δq.
void iterate(const Model& model, Data& data, const SolveOptions& options);

// Iterates from data.q() until converged / cap / deadline / stalled. Allocation-free.
const SolveReport& solve(const Model& model, Data& data, const SolveOptions& options = {});

}  // namespace embody::ik
