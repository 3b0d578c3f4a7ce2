// Data and its Workspace: every buffer the solver needs is sized here, once; the setters validate
// and leave the state unchanged on error.
#include <algorithm>
#include <cmath>

#include "ik/solver.h"
#include "ik/solver_detail.h"
#include "ik/solver_internal.h"

namespace embody::ik {

using detail::fail;


Workspace::Workspace(const Model& model)
    : n(model.dofs), task_count(static_cast<int>(model.tasks.size())), rows(model.task_rows) {
  sizeTaskState(model);
  factorEqualities(model);
  sizeActiveSet();
  sizeLevelScratch(model);
  sizeInequalities(model);
}

// Per-task state and the forward-kinematics buffers.
void Workspace::sizeTaskState(const Model& model) {
  q = model.neutral;
  target_position.assign(task_count, Eigen::Vector3d::Zero());
  target_orientation.assign(task_count, Eigen::Quaterniond::Identity());
  weight.resize(task_count);
  enabled.resize(task_count);
  task_dofs.resize(task_count);
  for (int t = 0; t < task_count; ++t) {
    const Model::Task& task = model.tasks[t];
    weight[t] = task.desc.weight;
    task_type.push_back(task.desc.type);
    task_joint.push_back(task.desc.joint);
    task_offset.push_back(task.desc.offset);
    enabled[t] = task.desc.enabled ? 1 : 0;
    for (size_t j = 0; j < model.joints.size(); ++j)
      if (task.recruited[j])
        for (int k = 0; k < model.joints[j].dof_count; ++k) task_dofs[t].push_back(model.joints[j].first_dof + k);
  }
  const size_t nj = model.joints.size();
  frames.assign(nj, Eigen::Isometry3d::Identity());
  subtree_mass.assign(nj, 0.0);
  subtree_moment.assign(nj, Eigen::Vector3d::Zero());
  dof_linear.setZero(3, n);
  dof_angular.setZero(3, n);
  dof_joint.resize(n);
  for (size_t j = 0; j < nj; ++j)
    for (int k = 0; k < model.joints[j].dof_count; ++k) dof_joint[model.joints[j].first_dof + k] = static_cast<int>(j);

  dof_task_row_begin.assign(n, rows);
  dof_task_row_end.assign(n, 0);
  for (int t = 0; t < task_count; ++t) {
    const Model::Task& task = model.tasks[t];
    for (int dof : task_dofs[t]) {
      dof_task_row_begin[dof] = std::min(dof_task_row_begin[dof], task.first_row);
      dof_task_row_end[dof] = std::max(dof_task_row_end[dof], task.first_row + task.rows);
    }
  }
  for (int i = 0; i < n; ++i) dof_task_row_begin[i] = std::min(dof_task_row_begin[i], dof_task_row_end[i]);
  jacobian.setZero(rows, n);
  error.setZero(rows);
  residual.resize(task_count);
}

// The equality rows factored once: Gram-Schmidt basis, null space, sparse terms.
void Workspace::factorEqualities(const Model& model) {
  // Equality rows: Gram-Schmidt (twice, for orthogonality to round-off) with the same dependency
  // test as the model's corrected Algorithm 1.
  const Eigen::MatrixXd& a = model.equality_matrix;
  eq_basis.setZero(n, n);
  eq_factor.setZero(n, n);
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    const Eigen::VectorXd c = a.row(i).transpose();
    Eigen::VectorXd t = eq_basis.leftCols(eq_rank).transpose() * c;
    Eigen::VectorXd u = c - eq_basis.leftCols(eq_rank) * t;
    if (!(u.norm() > 1e-9 * c.norm())) continue;
    const Eigen::VectorXd t2 = eq_basis.leftCols(eq_rank).transpose() * u;
    u -= eq_basis.leftCols(eq_rank) * t2;
    t += t2;
    eq_basis.col(eq_rank) = u / u.norm();
    eq_factor.row(eq_rank).head(eq_rank) = t.transpose();
    eq_factor(eq_rank, eq_rank) = u.norm();
    eq_rows.push_back(static_cast<int>(i));
    ++eq_rank;
  }
  // null(A) as [unit columns of the dofs no equality row touches | a basis of the constrained
  // dofs' null space]: sparse, so J N costs a copy per free dof plus a product over the
  // constrained dofs only (the coupled spine's 42 of the avatar's 87), where a QR of the whole
  // basis would spread every column over the first rank rows.
  eq_nullspace.setZero(n, n);
  if (eq_rank > 0) {
    std::vector<char> constrained(n, 0);
    for (Eigen::Index i = 0; i < a.rows(); ++i)
      for (int c = 0; c < n; ++c)
        if (a(i, c) != 0.0) constrained[c] = 1;
    std::vector<int> cdofs;
    int col = 0;
    for (int c = 0; c < n; ++c) {
      if (constrained[c])
        cdofs.push_back(c);
      else
        eq_nullspace(c, col++) = 1.0;
    }
    const int nc = static_cast<int>(cdofs.size());
    Eigen::MatrixXd basisC(nc, eq_rank);
    for (int i = 0; i < nc; ++i) basisC.row(i) = eq_basis.row(cdofs[i]).head(eq_rank);
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(basisC);
    const Eigen::MatrixXd full = qr.householderQ();
    for (int i = 0; i < nc; ++i) eq_nullspace.row(cdofs[i]).segment(col, nc - eq_rank) = full.row(i).tail(nc - eq_rank);
  }
  eq_rhs.setZero(eq_rank);
  eq_begin.push_back(0);
  for (int i = 0; i < eq_rank; ++i) {
    eq_rhs(i) = model.equality_rhs(eq_rows[i]);
    for (int c = 0; c < n; ++c)
      if (a(eq_rows[i], c) != 0.0) {
        eq_dof.push_back(c);
        eq_coef.push_back(a(eq_rows[i], c));
      }
    eq_begin.push_back(static_cast<int>(eq_dof.size()));
  }
}

// The active set's buffers, starting as the equality rows; the step vectors.
void Workspace::sizeActiveSet() {
  basis.setZero(n, n);
  factor.setZero(n, n);
  basis.leftCols(eq_rank) = eq_basis.leftCols(eq_rank);
  factor.topLeftCorner(eq_rank, eq_rank) = eq_factor.topLeftCorner(eq_rank, eq_rank);
  active_rhs.setZero(n);
  mask.setOnes(n);
  nullspace = eq_nullspace;
  eq_projector0 = Eigen::MatrixXd::Identity(n, n) - eq_basis.leftCols(eq_rank) * eq_basis.leftCols(eq_rank).transpose();
  dq0.setZero(n);
  dq.setZero(n);
  tmp_n.setZero(n);
  tmp_n2.setZero(n);
  y.setZero(n);
  guard_full.setZero(n);
  previous_task_step.setZero(n);
}

// The priority passes' per-level scratch and the levels' supports.
void Workspace::sizeLevelScratch(const Model& model) {
  reduced_jacobian.setZero(rows, n);
  row_space.setZero(n, n);
  projector.setZero(n, n);
  projector0 = eq_projector0;
  // Reserve first: growing a vector moves its elements, and moving an Eigen decomposition that
  // has not computed anything yet reads its uninitialised flags (UBSan reports it).
  const size_t levels = model.levels.size();
  null_groups.reserve(n);
  eq_null_groups.reserve(n);
  for (auto* v : {&level_j, &level_gram, &level_jw, &level_factor, &level_factor2, &level_inverse}) v->reserve(levels);
  for (auto* v : {&level_factor_inv, &level_factor2_inv}) v->reserve(levels);
  level_perm.reserve(levels);
  for (auto* v : {&level_res, &level_coef, &level_tmp}) v->reserve(levels);
  for (auto* v : {&level_step, &level_previous_step, &warm_saved_level_step}) v->reserve(levels);
  warm_saved_level_step_set.assign(levels, 0);
  level_step_set.assign(levels, 0);
  level_has_previous.assign(levels, 0);
  for (const Model::Level& level : model.levels) {
    const int m = level.rows;
    level_j.emplace_back(Eigen::MatrixXd::Zero(m, n));
    level_gram.emplace_back(Eigen::MatrixXd::Zero(m, m));
    level_res.emplace_back(Eigen::VectorXd::Zero(m));
    level_coef.emplace_back(Eigen::VectorXd::Zero(m));
    level_tmp.emplace_back(Eigen::VectorXd::Zero(m));
    level_jw.emplace_back(Eigen::MatrixXd::Zero(m, n));
    level_factor.emplace_back(Eigen::MatrixXd::Zero(m, m));
    level_factor2.emplace_back(Eigen::MatrixXd::Zero(m, m));
    level_factor_inv.emplace_back(Eigen::VectorXd::Zero(m));
    level_factor2_inv.emplace_back(Eigen::VectorXd::Zero(m));
    level_inverse.emplace_back(Eigen::MatrixXd::Zero(m, m));
    level_perm.emplace_back(Eigen::VectorXi::Zero(m));
    level_y.emplace_back(Eigen::VectorXd::Zero(m));
    level_step.emplace_back(Eigen::VectorXd::Zero(n));
    level_previous_step.emplace_back(Eigen::VectorXd::Zero(n));
    warm_saved_level_step.emplace_back(Eigen::VectorXd::Zero(n));
    level_svd.emplace_back(m, n, Eigen::ComputeThinU | Eigen::ComputeThinV);
    max_level_rows = std::max(max_level_rows, m);
    std::vector<char> used(n, 0);
    for (TaskId t : level.tasks)
      for (int dof : task_dofs[t]) used[dof] = 1;
    std::vector<int>& support = level_support.emplace_back();
    for (int i = 0; i < n; ++i)
      if (used[i]) support.push_back(i);
  }
  gathered_j.setZero(max_level_rows, n);
  dense_support.reserve(n);
  dense_support_ranges.reserve(n);
  for (const std::vector<int>& support : level_support) {
    std::vector<Range>& ranges = level_ranges.emplace_back();
    for (size_t i = 0; i < support.size();) {
      const int lo = support[i];
      int hi = lo + 1;
      while (++i < support.size() && support[i] == hi) ++hi;
      ranges.push_back({lo, hi});
    }
  }
  basis_span.assign(n, Range{});
  for (int k = 0; k < eq_rank; ++k) basis_span[k] = detail::nonZeroSpan(eq_basis.col(k));  // pinned rows add theirs
  eq_null_span.assign(n, Range{});
  for (int k = 0; k < n; ++k) eq_null_span[k] = detail::nonZeroSpan(eq_nullspace.col(k));
  null_span = eq_null_span;
  row_mark.assign(n, 0);
  block_begin.assign(levels, 0);
  block_size.assign(levels, 0);
  block_touched.assign(levels, 0);
  block_level.assign(levels, 0);
  block_pivoted.assign(levels, 0);
  block_ranges.resize(levels);
  for (std::vector<Range>& ranges : block_ranges) ranges.reserve(n);
  level_solve.setZero(max_level_rows, max_level_rows);
  level_cols.setZero(n, max_level_rows);
  small_a.setZero(n);
  small_b.setZero(n);
  small_z.setZero(n);
  small_rows.setZero(rows);
}

// The inequality rows in sparse form, the warm active set's buffers, the report.
void Workspace::sizeInequalities(const Model& model) {
  ineq_begin.push_back(0);
  for (const InequalityRow& row : model.inequalities) {
    for (const LinearTerm& t : row.terms) {
      ineq_dof.push_back(model.dofIndex(t.dof));
      ineq_coef.push_back(t.coefficient);
    }
    ineq_begin.push_back(static_cast<int>(ineq_dof.size()));
    ineq_rhs.push_back(row.rhs);
  }
  ineq_active.assign(model.inequalities.size(), 0);
  ineq_reported.assign(model.inequalities.size(), 0);
  carried.reserve(model.inequalities.size());
  warm_residual.setZero(rows);
  warm_gradient.setZero(n);
  warm_multiplier.setZero(n);
  warm_force.setZero(rows);
  warm_reduced.setZero(n);
  warm_released.assign(model.inequalities.size(), 0);
  warm_saved_dq.setZero(n);
  warm_saved_dq0.setZero(n);
  warm_released_rows.reserve(model.inequalities.size());
  warm_deciding.assign(model.inequalities.size(), 0.0);
  warm_undecided.assign(model.inequalities.size(), 0);
  warm_hold_multiplier.assign(model.inequalities.size(), 0.0);
  warm_hold_since.assign(model.inequalities.size(), 0);

  report.tasks.resize(task_count);
  report.levels.resize(model.levels.size());
  report.active_clamps.reserve(model.inequalities.size());
  report.unsatisfiable.reserve(model.inequalities.size());
}

Data::Data(const Model& model) : ws_(std::make_unique<Workspace>(model)) {
  kinematics(model, *this, false);
  // Start with every task on its current value, so a fresh Data is already solved.
  for (int t = 0; t < ws_->task_count; ++t) {
    ws_->target_position[t] = taskPosition(t);
    ws_->target_orientation[t] = taskOrientation(t);
    const JointId reference = model.tasks[size_t(t)].desc.reference;
    if (reference != kNoParent)
      ws_->target_orientation[t] = Eigen::Quaterniond(ws_->frames[reference].linear()).conjugate() * ws_->target_orientation[t];
  }
}

Data::~Data() = default;
Data::Data(Data&&) noexcept = default;
Data& Data::operator=(Data&&) noexcept = default;
Data::Data(const Data& other) : ws_(std::make_unique<Workspace>(*other.ws_)) {}
Data& Data::operator=(const Data& other) {
  if (this != &other) ws_ = std::make_unique<Workspace>(*other.ws_);
  return *this;
}

Status Data::setConfiguration(const Eigen::VectorXd& q) {
  if (q.size() != ws_->n)
    return fail("configuration has " + std::to_string(q.size()) + " entries, the model " + std::to_string(ws_->n));
  if (!q.allFinite()) return fail("configuration is not finite");
  ws_->q = q;
  detail::forgetSteps(*ws_);
  return Status::success();
}

const Eigen::VectorXd& Data::q() const { return ws_->q; }

void Data::forgetActiveSet() { detail::clearCarriedActiveSet(*ws_); }

namespace {
Status checkTask(const Workspace& w, TaskId task) {
  if (task < 0 || task >= w.task_count) return fail("task " + std::to_string(task) + " does not exist");
  return Status::success();
}
}  // namespace

Status Data::setTarget(TaskId task, const Eigen::Vector3d& position) {
  if (Status s = checkTask(*ws_, task); !s) return s;
  if (!position.allFinite()) return fail("target position of task " + std::to_string(task) + " is not finite");
  ws_->target_position[task] = position;
  return Status::success();
}

Status Data::setTarget(TaskId task, const Eigen::Quaterniond& orientation) {
  if (Status s = checkTask(*ws_, task); !s) return s;
  const double norm = orientation.norm();
  if (!orientation.coeffs().allFinite() || !(norm > 1e-9))
    return fail("target orientation of task " + std::to_string(task) + " is not a finite non-zero quaternion");
  ws_->target_orientation[task] = Eigen::Quaterniond(orientation.coeffs() / norm);
  return Status::success();
}

Status Data::setTarget(TaskId task, const Eigen::Isometry3d& pose) {
  if (Status s = checkTask(*ws_, task); !s) return s;
  if (!pose.matrix().allFinite()) return fail("target pose of task " + std::to_string(task) + " is not finite");
  const Eigen::Matrix3d r = pose.linear();
  if (!(r.transpose() * r).isApprox(Eigen::Matrix3d::Identity(), 1e-6) || r.determinant() <= 0)
    return fail("target pose of task " + std::to_string(task) + " has a linear part that is not a rotation");
  ws_->target_position[task] = pose.translation();
  ws_->target_orientation[task] = Eigen::Quaterniond(r).normalized();
  return Status::success();
}

Status Data::setWeight(TaskId task, double weight) {
  if (Status s = checkTask(*ws_, task); !s) return s;
  if (!(std::isfinite(weight) && weight > 0)) return fail("weight of task " + std::to_string(task) + " must be finite and > 0");
  ws_->weight[task] = weight;
  return Status::success();
}

Status Data::setInequalityBound(int row, double rhs) {
  if (row < 0 || static_cast<size_t>(row) >= ws_->ineq_rhs.size())
    return fail("inequality row " + std::to_string(row) + " out of range (" + std::to_string(ws_->ineq_rhs.size()) + " rows)");
  if (!std::isfinite(rhs)) return fail("bound of inequality row " + std::to_string(row) + " is not finite");
  ws_->ineq_rhs[static_cast<size_t>(row)] = rhs;
  return Status::success();
}

double Data::inequalityBound(int row) const { return ws_->ineq_rhs.at(static_cast<size_t>(row)); }

Status Data::setEnabled(TaskId task, bool enabled) {
  if (Status s = checkTask(*ws_, task); !s) return s;
  ws_->enabled[task] = enabled ? 1 : 0;
  return Status::success();
}

bool Data::enabled(TaskId task) const { return ws_->enabled.at(task) != 0; }
const Eigen::Vector3d& Data::targetPosition(TaskId task) const { return ws_->target_position.at(task); }
const Eigen::Quaterniond& Data::targetOrientation(TaskId task) const { return ws_->target_orientation.at(task); }
const Eigen::Isometry3d& Data::jointFrame(JointId joint) const { return ws_->frames.at(joint); }
const Eigen::Vector3d& Data::centerOfMass() const { return ws_->com; }
const SolveReport& Data::report() const { return ws_->report; }

const Eigen::MatrixXd& taskJacobian(const Data& data) { return data.workspace().jacobian; }
const Eigen::VectorXd& taskError(const Data& data) { return data.workspace().error; }

}  // namespace embody::ik
