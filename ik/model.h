#pragma once
// The kinematic model of the prioritized IK solver (Baerlocher & Boulic 2004, with the linear joint
// constraints of Raunhardt & Boulic 2008). See docs/ik.md and ../shared/reference/pik.md.
//
// A `Model` is built once by `ModelBuilder` and then only read (Pinocchio's const Model): joints,
// linear equality / inequality rows over joint dofs, and the task descriptions with their
// priority levels and recruited joints. Everything that changes per frame (configuration q, task
// targets, weights, on/off switches) and every scratch buffer lives in `ik::Data` (solver.h).
//
// Conventions
// - A joint's frame in world space is  T_j = T_parent * rest_j * M_j(q_j)  (T_parent = identity
//   for a root). `rest` places the joint in its parent's frame; M_j is the joint's motion:
//     Free      6 dofs [tx ty tz vx vy vz]: M = Translation(t) * exp(v), t in the rest frame
//     Ball      3 dofs [vx vy vz]: M = exp(v), v an exponential-map rotation vector (Grassia 1998)
//     Swing     2 dofs [s0 s1]: M = exp(s0 u + s1 w), (u, w, axis) right-handed and orthonormal,
//               so the rotation vector has no component along the twist `axis`
//     Revolute  1 dof  [angle]: M = AngleAxis(angle, axis)
//     Fixed     0 dofs
// - Angles in radians, lengths in metres, masses in kg. `up` is the world's vertical axis (the
//   centre-of-mass task works in the ground plane orthogonal to it).
// - Priority levels: a smaller number is more important (level 0 is the highest). Any number of
//   strict levels; tasks on the same level are blended by their weights.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/result.h"

namespace embody::ik {

using JointId = int;
using TaskId = int;
inline constexpr JointId kNoParent = -1;
inline constexpr double kUnbounded = std::numeric_limits<double>::infinity();

enum class JointType : std::uint8_t { Free, Ball, Swing, Revolute, Fixed };

// Number of dofs a joint of this type carries (6, 3, 2, 1, 0).
int dofCount(JointType type);
const char* toString(JointType type);

struct JointDesc {
  std::string name;
  JointId parent = kNoParent;  // must be added before the child; kNoParent for a root
  JointType type = JointType::Fixed;
  Eigen::Isometry3d rest = Eigen::Isometry3d::Identity();  // joint frame in the parent frame
  // Revolute: the rotation axis; Swing: the twist axis the swing is orthogonal to. Joint frame.
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  // Per-dof limits (size dofCount(type)); empty = unbounded. Use ±kUnbounded for one-sided.
  std::vector<double> lower;
  std::vector<double> upper;
  // Neutral configuration of this joint's dofs (size dofCount(type)); empty = zeros. A fresh
  // ik::Data starts here (keep it inside the limits and away from singular poses).
  std::vector<double> neutral;
  // The rigid segment this joint moves: mass and centre of mass in the joint frame.
  double mass = 0.0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
};

// One component of one joint's dofs, e.g. {spine3, 0} = the first swing component of spine3.
struct DofRef {
  JointId joint = 0;
  int component = 0;
};

struct LinearTerm {
  DofRef dof;
  double coefficient = 0.0;
};

// Σ coefficient * q[dof] = rhs. Folded into P0 and Δq0 ("infinite priority").
struct EqualityRow {
  std::string name;
  std::vector<LinearTerm> terms;
  double rhs = 0.0;
};

enum class InequalityKind : std::uint8_t {
  UserCoupling,  // checked first by the clamping loop
  JointLimit,    // generated from JointDesc limits (one row per finite bound), checked after
};

// Σ coefficient * q[dof] <= rhs. Pinned as an equality at its bound when a step would violate it.
struct InequalityRow {
  std::string name;
  std::vector<LinearTerm> terms;
  double rhs = 0.0;
  InequalityKind kind = InequalityKind::UserCoupling;
};

enum class TaskType : std::uint8_t {
  Position,      // a point on a segment; any subset of world axes (TaskDesc::axes)
  Orientation,   // the segment's world orientation, 3 rows
  Pose,          // position (all three axes) + orientation, 6 rows
  CenterOfMass,  // the whole-body centre of mass projected on the ground plane, 2 rows
};
const char* toString(TaskType type);

// Which joints a task may move (Rec(T) in pik.md). Always a subset of the task joint's ancestors
// (the joint itself included); for the centre of mass every joint is an "ancestor".
enum class Recruit : std::uint8_t {
  ToRoot,    // every ancestor up to the root
  Depth,     // the task joint and its ancestors, `depth` joints in all
  Explicit,  // exactly `joints`
};

inline constexpr std::uint8_t kAxisX = 1, kAxisY = 2, kAxisZ = 4, kAxesXYZ = 7;

struct TaskDesc {
  std::string name;
  TaskType type = TaskType::Position;
  JointId joint = 0;                                 // the end effector (unused for CoM)
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  // point of the segment, joint frame
  std::uint8_t axes = kAxesXYZ;                      // Position only: world axes constrained
  int level = 0;                                     // priority: 0 is the most important
  double weight = 1.0;                               // inside the level (initial; Data can change it)
  Recruit recruit = Recruit::ToRoot;
  int depth = 0;                                     // Recruit::Depth
  std::vector<JointId> joints;                       // Recruit::Explicit
  // Orientation only: the target is the joint's turn in this ancestor's frame (kNoParent: in the
  // world), e.g. a clavicle held at its rest turn on the chest whatever the chest does. The
  // error is then unchanged by the reference's own motion, so the task must not recruit the
  // reference or any joint that moves it (checked, couplings included).
  JointId reference = kNoParent;
  // Per-iteration error clamp: |e| <= max_error (metres for positions, radians for rotations).
  double max_position_error = 0.1;
  double max_rotation_error = 0.5;
  // The task counts as satisfied when its position / rotation error is at or below these.
  double position_tolerance = 1e-4;
  double rotation_tolerance = 1e-3;
  bool enabled = true;  // initial state; Data::setEnabled switches it per frame
};

// The immutable model. Build with ModelBuilder; share as `const Model` (e.g. shared_ptr<const>).
// Fields are public for the solver and tests but describe a validated structure: do not edit.
struct Model {
  struct Joint {
    JointDesc desc;
    int first_dof = 0;  // index of the joint's first dof in q
    int dof_count = 0;
    Eigen::Matrix<double, 3, 2> swing_basis = Eigen::Matrix<double, 3, 2>::Zero();  // [u w]
    bool reparameterize = false;  // exp-map joint free of constraint rows (see docs/ik.md)
  };
  struct Task {
    TaskDesc desc;
    int rows = 0;                  // rows this task contributes (axes, 3, 6 or 2)
    int first_row = 0;             // first row in the stacked task Jacobian (all levels)
    int level_index = 0;           // index into `levels` (dense, sorted by priority)
    std::vector<char> recruited;   // per joint: 1 when Rec(T) contains it
    std::vector<char> ancestors;   // per joint: 1 when Anc(T) contains it
  };
  struct Level {
    int priority = 0;              // TaskDesc::level value
    int first_row = 0;             // rows of one level are contiguous
    int rows = 0;
    std::vector<TaskId> tasks;
  };

  std::vector<Joint> joints;       // parents before children
  std::vector<EqualityRow> equalities;
  std::vector<InequalityRow> inequalities;  // user couplings first, then joint limits
  std::vector<Task> tasks;
  std::vector<Level> levels;       // sorted, most important first
  int dofs = 0;
  int task_rows = 0;
  Eigen::VectorXd neutral;         // neutral configuration (JointDesc::neutral), size dofs
  double total_mass = 0.0;
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  Eigen::Matrix<double, 3, 2> ground_axes = Eigen::Matrix<double, 3, 2>::Zero();  // ⟂ up
  // Dense rows of the equalities (g x n) and rhs, with the rows skipped as linearly dependent on
  // earlier ones (first added wins) listed by index.
  Eigen::MatrixXd equality_matrix;
  Eigen::VectorXd equality_rhs;
  std::vector<int> dependent_equalities;

  int dofIndex(DofRef ref) const { return joints[ref.joint].first_dof + ref.component; }
  JointId findJoint(const std::string& name) const;  // -1 when absent
  TaskId findTask(const std::string& name) const;    // -1 when absent
  int findInequality(const std::string& name) const; // index into inequalities, -1 when absent
  std::string dofName(int dof) const;                // "spine3[1]"
};

// Collects joints, constraint rows and tasks; build() validates everything (sizes, indices,
// finite numbers, limits, recruiting rules eqs. 3-5) and returns the model or a readable error.
class ModelBuilder {
 public:
  ModelBuilder() = default;

  JointId addJoint(JointDesc joint);
  // Convenience: the same as addJoint with the fields filled in.
  JointId addJoint(std::string name, JointId parent, JointType type,
                   const Eigen::Isometry3d& rest = Eigen::Isometry3d::Identity(),
                   const Eigen::Vector3d& axis = Eigen::Vector3d::UnitZ());
  // Limits of one dof (replaces the joint's lower/upper entry for that component).
  void setLimits(DofRef dof, double lower, double upper);
  void setSegment(JointId joint, double mass, const Eigen::Vector3d& com);
  // Neutral value of one dof (see JointDesc::neutral).
  void setNeutral(DofRef dof, double value);

  void addEquality(EqualityRow row);
  // q[a] * ca + q[b] * cb = rhs, e.g. coupleDofs({j, 0}, 1.0, {i, 0}, -r) for q_j - r q_i = 0.
  void addEquality(std::string name, DofRef a, double ca, DofRef b, double cb, double rhs = 0.0);
  void addInequality(InequalityRow row);  // kind UserCoupling or JointLimit (extra limit rows)

  TaskId addTask(TaskDesc task);

  void setUp(const Eigen::Vector3d& up);  // default +Y

  const std::vector<JointDesc>& joints() const { return joints_; }

  Result<Model> build() const;

 private:
  std::vector<JointDesc> joints_;
  std::vector<EqualityRow> equalities_;
  std::vector<InequalityRow> inequalities_;
  std::vector<TaskDesc> tasks_;
  Eigen::Vector3d up_ = Eigen::Vector3d::UnitY();
};

// Checks pik.md's recruiting rules on a model's tasks (build() calls it): eq. 3 (no strict-priority
// leak), eq. 4 (the same with joints recruited implicitly through equality coupling), eq. 5 (every
// coupled joint is recruited by some task). The error names the tasks and joints.
Status checkRecruiting(const Model& model);

}  // namespace embody::ik
