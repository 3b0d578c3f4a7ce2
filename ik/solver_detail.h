#pragma once
// The solver's workspace (private to ik and its tests): every buffer is sized once in
// Data's constructor, so an iteration only writes into existing storage.
#include <Eigen/Core>
#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <vector>

#include "ik/model.h"
#include "ik/solver.h"

namespace embody::ik {

struct Workspace {
  explicit Workspace(const Model& model);

  // The constructor's parts (data.cpp), in order.
  void sizeTaskState(const Model& model);
  void factorEqualities(const Model& model);
  void sizeActiveSet();
  void sizeLevelScratch(const Model& model);
  void sizeInequalities(const Model& model);

  int n = 0;          // dofs
  int task_count = 0;
  int rows = 0;       // stacked task rows

  Eigen::VectorXd q;

  // Per-frame task state.
  std::vector<Eigen::Vector3d> target_position;
  std::vector<Eigen::Quaterniond> target_orientation;
  std::vector<double> weight;
  std::vector<char> enabled;
  std::vector<std::vector<int>> task_dofs;  // recruited dof indices per task
  std::vector<TaskType> task_type;
  std::vector<JointId> task_joint;
  std::vector<Eigen::Vector3d> task_offset;

  // Forward kinematics.
  std::vector<Eigen::Isometry3d> frames;  // world frame of each joint
  std::vector<double> subtree_mass;       // Σ mass over the joint's subtree
  std::vector<Eigen::Vector3d> subtree_moment;  // Σ mass * world CoM over the subtree
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Matrix3Xd dof_linear;   // translation dofs: world direction; others 0
  Eigen::Matrix3Xd dof_angular;  // rotation dofs: world angular-velocity direction; others 0
  std::vector<int> dof_joint;    // joint owning each dof
  // Per dof: the span [begin, end) of task rows whose task recruits it (J is zero elsewhere in
  // its column; begin = end when no task does).
  std::vector<int> dof_task_row_begin, dof_task_row_end;

  // Task Jacobian (rows x n; recruitment, weights and on/off applied) and errors.
  Eigen::MatrixXd jacobian;
  Eigen::VectorXd error;             // clamped and weighted: what the priority loop tracks
  std::vector<TaskResidual> residual;  // unclamped

  // Active set A (equalities + pinned inequalities): orthonormal rows `basis` (n x rank) from
  // Gram-Schmidt with the lower-triangular factor `factor` (A_independent = factor * basisᵀ) and
  // `active_rhs` = b_A - A q. Equality part precomputed once (`eq_*`).
  Eigen::MatrixXd basis;
  Eigen::MatrixXd factor;
  Eigen::VectorXd active_rhs;
  int rank = 0;
  Eigen::MatrixXd eq_basis, eq_factor;
  Eigen::VectorXd eq_rhs;  // the independent equality rows' right-hand sides
  std::vector<int> eq_rows;  // independent equality row indices
  std::vector<int> eq_begin, eq_dof;  // the same rows' non-zero terms (sparse), for b - A q
  std::vector<double> eq_coef;
  int eq_rank = 0;

  // Null space of A. Mask mode (only single-dof rows active, no equality rows): the projector is
  // diagonal, `mask` zeroes pinned dofs. Dense mode: `nullspace` (n x null_dim) orthonormal.
  bool mask_mode = true;
  Eigen::VectorXd mask;
  Eigen::MatrixXd nullspace;
  int null_dim = 0;
  Eigen::MatrixXd eq_nullspace;  // equality-only null space, restored when pinned rows changed it
  bool nullspace_dirty = false;
  // N's columns grouped by the span of rows they are non-zero on (see nullspaceProduct), and the
  // span of task rows (rows of J) that can be non-zero on those dofs.
  struct ColumnGroup {
    int col_begin = 0, col_end = 0, row_begin = 0, row_end = 0;
    int task_row_begin = 0, task_row_end = 0;
  };
  std::vector<ColumnGroup> null_groups;     // reserved to n
  std::vector<ColumnGroup> eq_null_groups;  // the same for the equality rows' N (set on first use)
  bool null_ranges_dirty = true;
  int null_groups_cols = -1;

  Eigen::VectorXd dq0, dq, tmp_n, tmp_n2, y;
  // Oscillation guard (iteration.cpp): each level's contribution to the last pass's Δq (in the
  // pass's coordinates: n for the reference path, z for the fast path; `level_step_set` says
  // which levels took one); per level the previous iteration's contribution in joint space and
  // whether there is one; the task part of the previous step and the current step scale.
  std::vector<Eigen::VectorXd> level_step;
  std::vector<char> level_step_set;
  bool level_step_reduced = false;  // level_step holds z (fast path, dense mode): Δq = Δq0 + N z
  std::vector<Eigen::VectorXd> level_previous_step;
  std::vector<char> level_has_previous;
  Eigen::VectorXd previous_task_step, guard_full;
  double step_scale = 1.0;
  bool has_previous_step = false;

  // Fast path scratch.
  Eigen::MatrixXd reduced_jacobian;  // rows x null_dim (J N)
  Eigen::MatrixXd row_space;         // null_dim x n: accumulated orthonormal task rows (W)
  int row_space_dim = 0;
  std::vector<Eigen::MatrixXd> level_j;      // m_k x n
  std::vector<Eigen::MatrixXd> level_gram;   // m_k x m_k
  std::vector<Eigen::VectorXd> level_res, level_coef, level_tmp;
  std::vector<Eigen::MatrixXd> level_jw;     // m_k x n (J W)
  std::vector<Eigen::MatrixXd> level_inverse;  // G⁻¹ (damping estimate)
  // Cholesky factors (lower, small_cholesky.h) and their diagonals' reciprocals: of G, and of
  // G shifted by -eps² (the damping test) or +λ² (the damped solve).
  std::vector<Eigen::MatrixXd> level_factor, level_factor2;
  std::vector<Eigen::VectorXd> level_factor_inv, level_factor2_inv;
  std::vector<Eigen::VectorXi> level_perm;  // pivoted Cholesky's row order (rank-deficient levels)
  std::vector<Eigen::VectorXd> level_y;
  // Columns a level's Jacobian can be non-zero in (its tasks' recruited dofs, sorted): in mask
  // mode the pass works on these columns only.
  std::vector<std::vector<int>> level_support;
  int max_level_rows = 0;
  Eigen::MatrixXd gathered_j;  // max_level_rows x n: J̃ of one level on its support
  struct Range {
    int begin = 0, end = 0;  // [begin, end)
  };
  std::vector<int> dense_support;            // dense mode: the current level's reduced columns
  std::vector<Range> dense_support_ranges;   // the same as ranges (both reserved to n)
  std::vector<std::vector<Range>> level_ranges;  // each level's support as ranges
  std::vector<Range> basis_span;  // per column of `basis`: the rows it is non-zero on (active_set.cpp)
  // Per column of `nullspace` / `eq_nullspace`: the rows it is non-zero on, kept by addActiveRow
  // for the columns a reflection changes, so that N's column groups need no scan of N.
  std::vector<Range> null_span, eq_null_span;
  // W's blocks (one per level that added rows): first column, width, the row ranges it is
  // non-zero on (each reserved to n), and whether the current level overlaps it.
  std::vector<int> block_begin, block_size;
  std::vector<std::vector<Range>> block_ranges;
  std::vector<char> block_touched;
  // After a pass: how many blocks W has, the level each came from and whether that level's rows
  // were picked by the pivoted Cholesky (rank-deficient) (multipliers.cpp reads them).
  int block_count = 0;
  std::vector<int> block_level;
  std::vector<char> block_pivoted;
  std::vector<char> row_mark;  // n
  Eigen::MatrixXd level_solve; // max_level_rows²: V Σ⁻¹ (rank-deficient levels)
  Eigen::MatrixXd level_cols;  // n x max_level_rows: Ĵᵀ
  Eigen::VectorXd small_a, small_b, small_z;  // n each
  Eigen::VectorXd small_rows;  // rows: J Δq0

  // Reference path scratch.
  Eigen::MatrixXd projector, projector0, eq_projector0;
  bool projector0_dirty = false;
  std::vector<Eigen::JacobiSVD<Eigen::MatrixXd>> level_svd;

  // Inequalities in sparse form.
  std::vector<int> ineq_begin;  // into ineq_dof / ineq_coef, size rows + 1
  std::vector<int> ineq_dof;
  std::vector<double> ineq_coef;
  std::vector<double> ineq_rhs;  // per row: the model's rhs until Data::setInequalityBound
  std::vector<char> ineq_active;
  std::vector<char> ineq_reported;

  // Warm active set (warm_active_set.cpp): the rows pinned at the end of the last iteration, in
  // the order they were added; whether basis / factor / null space still hold exactly the
  // equality rows followed by them (built for carried_path); how many of this iteration's
  // pinned rows were carried. Scratch for their multipliers.
  std::vector<int> carried;  // reserved to the inequality count
  bool carried_structure = false;
  Path carried_path = Path::Fast;
  int carried_count = 0;
  Eigen::VectorXd warm_residual;    // task rows
  Eigen::VectorXd warm_gradient;    // n
  double warm_gradient_norm = 0.0;  // |J_kᵀ r_k| of the last carriedMultipliers call
  Eigen::VectorXd warm_multiplier;  // n (rank used)
  Eigen::VectorXd warm_force;       // task rows: the higher levels' multipliers (multipliers.cpp)
  Eigen::VectorXd warm_reduced;     // n: a gradient in reduced coordinates / projected
  std::vector<char> warm_released;  // inequality count
  // A release the next pass undid (the released row violated again: a lower level pushes it back
  // out): the step with the rows kept, restored, and per row the deciding multiplier and the
  // iteration of the failed release (held rows are not released again until the multiplier
  // doubles or kRetryAfter iterations have passed; warm_active_set.cpp).
  Eigen::VectorXd warm_saved_dq, warm_saved_dq0;  // n
  std::vector<Eigen::VectorXd> warm_saved_level_step;  // the same step's level contributions, joint space
  std::vector<char> warm_saved_level_step_set;
  std::vector<int> warm_released_rows;            // reserved to the inequality count
  std::vector<double> warm_deciding;              // per carried row: the deciding multiplier
  std::vector<char> warm_undecided;               // per carried row (scratch)
  bool warm_one_at_a_time = false;                // the last joint release was undone
  std::vector<double> warm_hold_multiplier;       // per inequality row; 0: not held
  std::vector<long> warm_hold_since;              // per inequality row
  long warm_iteration = 0;

  SolveReport report;
};

}  // namespace embody::ik
