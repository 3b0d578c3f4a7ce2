#include "ik/solver.h"

#include <algorithm>
#include <cmath>

#include "ik/expmap.h"
#include "ik/small_cholesky.h"
#include "ik/solver_detail.h"

namespace embody::ik {
namespace {

Error fail(const std::string& what) { return Error{"ik: " + what}; }

class SteadyClock final : public Clock {
 public:
  time_point now() const override { return std::chrono::steady_clock::now(); }
};

bool sameShape(const Model& model, const Workspace& w) {
  return w.n == model.dofs && w.task_count == static_cast<int>(model.tasks.size()) &&
         w.rows == model.task_rows;
}

}  // namespace

const Clock& steadyClock() {
  static const SteadyClock clock;
  return clock;
}

const char* toString(StopReason reason) {
  switch (reason) {
    case StopReason::Converged: return "converged";
    case StopReason::IterationCap: return "iteration cap";
    case StopReason::Deadline: return "deadline";
    case StopReason::Stalled: return "stalled";
    case StopReason::InvalidState: return "invalid state";
  }
  return "?";
}

// ---------------------------------------------------------------------------------------------
// Workspace / Data

Workspace::Workspace(const Model& model)
    : n(model.dofs), task_count(static_cast<int>(model.tasks.size())), rows(model.task_rows) {
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

  jacobian.setZero(rows, n);
  error.setZero(rows);
  residual.resize(task_count);

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
  previous_task_step.setZero(n);

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
  row_mark.assign(n, 0);
  block_begin.assign(levels, 0);
  block_size.assign(levels, 0);
  block_touched.assign(levels, 0);
  block_ranges.resize(levels);
  for (std::vector<Range>& ranges : block_ranges) ranges.reserve(n);
  level_solve.setZero(max_level_rows, max_level_rows);
  level_cols.setZero(n, max_level_rows);
  small_a.setZero(n);
  small_b.setZero(n);
  small_z.setZero(n);
  small_rows.setZero(rows);

  ineq_begin.push_back(0);
  for (const InequalityRow& row : model.inequalities) {
    for (const LinearTerm& t : row.terms) {
      ineq_dof.push_back(model.dofIndex(t.dof));
      ineq_coef.push_back(t.coefficient);
    }
    ineq_begin.push_back(static_cast<int>(ineq_dof.size()));
  }
  ineq_active.assign(model.inequalities.size(), 0);
  ineq_reported.assign(model.inequalities.size(), 0);

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
  ws_->has_previous_step = false;
  ws_->step_scale = 1.0;
  return Status::success();
}

const Eigen::VectorXd& Data::q() const { return ws_->q; }

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

// ---------------------------------------------------------------------------------------------
// Kinematics

namespace {

Eigen::Vector3d clampNorm(const Eigen::Vector3d& v, double max) {
  const double n = v.norm();
  return n > max ? Eigen::Vector3d(v * (max / n)) : v;
}

Eigen::Vector2d clampNorm(const Eigen::Vector2d& v, double max) {
  const double n = v.norm();
  return n > max ? Eigen::Vector2d(v * (max / n)) : v;
}

void forward(const Model& model, Workspace& w) {
  const size_t nj = model.joints.size();
  for (size_t j = 0; j < nj; ++j) {
    const Model::Joint& joint = model.joints[j];
    const JointDesc& d = joint.desc;
    const Eigen::Isometry3d pre = d.parent == kNoParent ? d.rest : Eigen::Isometry3d(w.frames[d.parent] * d.rest);
    const Eigen::Matrix3d preR = pre.linear();
    const int f = joint.first_dof;
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
    switch (d.type) {
      case JointType::Free: {
        const Eigen::Vector3d v = w.q.segment<3>(f + 3);
        motion.translation() = w.q.segment<3>(f);
        motion.linear() = expMapRotation(v);
        w.dof_linear.middleCols<3>(f) = preR;
        w.dof_angular.middleCols<3>(f).setZero();
        w.dof_linear.middleCols<3>(f + 3).setZero();
        w.dof_angular.middleCols<3>(f + 3).noalias() = preR * leftJacobian(v);
        break;
      }
      case JointType::Ball: {
        const Eigen::Vector3d v = w.q.segment<3>(f);
        motion.linear() = expMapRotation(v);
        w.dof_linear.middleCols<3>(f).setZero();
        w.dof_angular.middleCols<3>(f).noalias() = preR * leftJacobian(v);
        break;
      }
      case JointType::Swing: {
        const Eigen::Vector3d v = joint.swing_basis * w.q.segment<2>(f);
        motion.linear() = expMapRotation(v);
        w.dof_linear.middleCols<2>(f).setZero();
        w.dof_angular.middleCols<2>(f).noalias() = preR * leftJacobian(v) * joint.swing_basis;
        break;
      }
      case JointType::Revolute:
        motion.linear() = Eigen::AngleAxisd(w.q(f), d.axis).toRotationMatrix();
        w.dof_linear.col(f).setZero();
        w.dof_angular.col(f).noalias() = preR * d.axis;
        break;
      case JointType::Fixed: break;
    }
    w.frames[j] = pre * motion;
  }
  // Subtree masses and mass moments (children come after parents: sweep backwards).
  for (size_t j = 0; j < nj; ++j) {
    const JointDesc& d = model.joints[j].desc;
    w.subtree_mass[j] = d.mass;
    w.subtree_moment[j] = d.mass * (w.frames[j] * d.com);
  }
  for (size_t j = nj; j-- > 0;) {
    const JointId p = model.joints[j].desc.parent;
    if (p != kNoParent) {
      w.subtree_mass[p] += w.subtree_mass[j];
      w.subtree_moment[p] += w.subtree_moment[j];
    }
  }
  w.com.setZero();
  if (model.total_mass > 0) {
    for (size_t j = 0; j < nj; ++j)
      if (model.joints[j].desc.parent == kNoParent) w.com += w.subtree_moment[j];
    w.com /= model.total_mass;
  }
}

void taskRows(const Model& model, Workspace& w, TaskId t) {
  const Model::Task& task = model.tasks[t];
  const TaskDesc& d = task.desc;
  const int row = task.first_row;
  const double s = w.enabled[t] ? std::sqrt(w.weight[t]) : 0.0;
  TaskResidual& res = w.residual[t];
  res = TaskResidual{};
  res.enabled = w.enabled[t] != 0;
  switch (d.type) {
    case TaskType::CenterOfMass: {
      const Eigen::Vector2d e = model.ground_axes.transpose() * (w.target_position[t] - w.com);
      res.position = e.norm();
      w.error.segment<2>(row) = s * clampNorm(e, d.max_position_error);
      const double invM = 1.0 / model.total_mass;
      for (int dof : w.task_dofs[t]) {
        const int j = w.dof_joint[dof];
        const Eigen::Vector3d o = w.frames[j].translation();
        const Eigen::Vector3d col = invM * (w.subtree_mass[j] * w.dof_linear.col(dof) +
                                            w.dof_angular.col(dof).cross(w.subtree_moment[j] - w.subtree_mass[j] * o));
        w.jacobian.block<2, 1>(row, dof) = s * (model.ground_axes.transpose() * col);
      }
      break;
    }
    case TaskType::Position:
    case TaskType::Orientation:
    case TaskType::Pose: {
      const Eigen::Isometry3d& frame = w.frames[d.joint];
      const Eigen::Vector3d p = frame * d.offset;
      const bool hasPos = d.type != TaskType::Orientation;
      const bool hasRot = d.type != TaskType::Position;
      int r = row;
      Eigen::Vector3d ep = Eigen::Vector3d::Zero();
      if (hasPos) {
        const Eigen::Vector3d full = w.target_position[t] - p;
        const std::uint8_t axes = d.type == TaskType::Pose ? kAxesXYZ : d.axes;
        for (int k = 0; k < 3; ++k)
          if (axes & (1 << k)) ep(k) = full(k);
        res.position = ep.norm();
        const Eigen::Vector3d clamped = clampNorm(ep, d.max_position_error);
        for (int k = 0; k < 3; ++k) {
          if (!(axes & (1 << k))) continue;
          w.error(r) = s * clamped(k);
          for (int dof : w.task_dofs[t]) {
            const int j = w.dof_joint[dof];
            const Eigen::Vector3d col =
                w.dof_linear.col(dof) + w.dof_angular.col(dof).cross(p - w.frames[j].translation());
            w.jacobian(r, dof) = s * col(k);
          }
          ++r;
        }
      }
      if (hasRot) {
        const Eigen::Quaterniond current(frame.linear());
        Eigen::Quaterniond err = w.target_orientation[t] * current.conjugate();
        if (err.w() < 0) err.coeffs() = -err.coeffs();
        const Eigen::AngleAxisd aa(err);
        const Eigen::Vector3d er = aa.angle() * aa.axis();
        res.rotation = er.norm();
        w.error.segment<3>(r) = s * clampNorm(er, d.max_rotation_error);
        for (int dof : w.task_dofs[t]) w.jacobian.block<3, 1>(r, dof) = s * w.dof_angular.col(dof);
      }
      break;
    }
  }
  res.satisfied = !res.enabled || (res.position <= d.position_tolerance && res.rotation <= d.rotation_tolerance);
}

}  // namespace

Eigen::Vector3d Data::taskPosition(TaskId task) const {
  const Workspace& w = *ws_;
  if (w.task_type.at(task) == TaskType::CenterOfMass) return w.com;
  return w.frames[w.task_joint[task]] * w.task_offset[task];
}

Eigen::Quaterniond Data::taskOrientation(TaskId task) const {
  const Workspace& w = *ws_;
  if (w.task_type.at(task) == TaskType::CenterOfMass) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(w.frames[w.task_joint[task]].linear());
}

void kinematics(const Model& model, Data& data, bool jacobians) {
  Workspace& w = data.workspace();
  if (!sameShape(model, w)) return;
  forward(model, w);
  if (!jacobians) return;
  for (int t = 0; t < w.task_count; ++t) taskRows(model, w, t);
}

// ---------------------------------------------------------------------------------------------
// Active set: equality rows plus pinned inequalities

namespace {

constexpr double kDriftTolerance = 1e-14;
constexpr Eigen::Index kLazyProductLimit = 400;  // |b - A q| below this is round-off, not drift

// Back to the equality rows only. The equality part of basis / factor is written once (in the
// constructor) and pinned rows only append after it; the null-space basis and the reference
// projector are restored only when pinned rows changed them.
void resetActiveSet(Workspace& w, Path path) {
  const int r = w.eq_rank;
  w.rank = r;
  if (r > 0) {
    for (int i = 0; i < r; ++i) {  // b - A q over the rows' few non-zero terms
      double v = w.eq_rhs(i);
      for (int t = w.eq_begin[i]; t < w.eq_begin[i + 1]; ++t) v -= w.eq_coef[t] * w.q(w.eq_dof[t]);
      w.active_rhs(i) = v;
    }
  }
  w.mask_mode = r == 0;
  w.mask.setOnes();
  w.null_dim = w.n - r;
  if (!w.mask_mode && w.nullspace_dirty) {
    w.nullspace.leftCols(w.null_dim) = w.eq_nullspace.leftCols(w.null_dim);
    w.nullspace_dirty = false;
    w.null_groups = w.eq_null_groups;  // reserved: no allocation
    w.null_groups_cols = w.null_dim;
    w.null_ranges_dirty = w.eq_null_groups.empty();
  }
  if (path == Path::Reference && w.projector0_dirty) {
    w.projector0 = w.eq_projector0;
    w.projector0_dirty = false;
  }
  std::fill(w.ineq_active.begin(), w.ineq_active.end(), 0);
  std::fill(w.ineq_reported.begin(), w.ineq_reported.end(), 0);
}

// Δq0 = A⁺ (b_A - A q) = basis * factor⁻¹ * active_rhs (minimum-norm solution). Rows that hold
// to round-off (|b - A q| ≤ 1e-14, the usual case for equalities between iterations) need no
// correction, so Δq0 is zero without the two products.
void computeDq0(Workspace& w) {
  const int r = w.rank;
  w.dq0.setZero();
  if (r == 0 || !(w.active_rhs.head(r).cwiseAbs().maxCoeff() > kDriftTolerance)) return;
  auto y = w.y.head(r);
  y = w.active_rhs.head(r);
  w.factor.topLeftCorner(r, r).triangularView<Eigen::Lower>().solveInPlace(y);
  w.dq0.noalias() = w.basis.leftCols(r) * y;
}

// Adds row c (in w.tmp_n) pinned so that c^T (q + Δq) = c^T q + rhs_delta. Returns false when
// the row depends linearly on the active set (then nothing changes).
bool addActiveRow(Workspace& w, double rhs_delta, int single_dof, Path path, double tolerance) {
  const int r = w.rank;
  const Eigen::VectorXd& c = w.tmp_n;
  auto t = w.y.head(r);
  Eigen::VectorXd& u = w.tmp_n2;
  u = c;
  if (r > 0) {
    t.noalias() = w.basis.leftCols(r).transpose() * c;
    u.noalias() -= w.basis.leftCols(r) * t;
  }
  const double cn = c.norm();
  if (!(u.norm() > tolerance * cn)) return false;
  if (r > 0) {  // second Gram-Schmidt sweep keeps the basis orthonormal to round-off
    auto t2 = w.dq0.head(r);  // dq0 is recomputed after rows are added
    t2.noalias() = w.basis.leftCols(r).transpose() * u;
    u.noalias() -= w.basis.leftCols(r) * t2;
    t += t2;
    w.factor.row(r).head(r) = t.transpose();
  }
  const double un = u.norm();
  u /= un;
  w.basis.col(r) = u;
  w.factor(r, r) = un;
  w.active_rhs(r) = rhs_delta;
  w.rank = r + 1;

  if (w.mask_mode && single_dof >= 0) {
    w.mask(single_dof) = 0.0;
  } else {
    w.nullspace_dirty = true;
    w.null_ranges_dirty = true;
    if (w.mask_mode) {  // materialise the diagonal projector's basis: the unmasked unit vectors
      w.nullspace.setZero();
      int k = 0;
      for (int i = 0; i < w.n; ++i)
        if (w.mask(i) != 0.0) w.nullspace(i, k++) = 1.0;
      w.mask_mode = false;
    }
    // Householder reflection H with H (Nᵀ u) = α e_last; then N H's last column is ±u: drop it.
    const int d = w.null_dim;
    auto v = w.tmp_n.head(d);  // c is no longer needed
    v.noalias() = w.nullspace.leftCols(d).transpose() * u;
    const double yn = v.norm();
    const double alpha = v(d - 1) > 0 ? -yn : yn;
    v(d - 1) -= alpha;
    const double vv = v.squaredNorm();
    if (vv > 0) {
      Eigen::VectorXd& nv = w.tmp_n2;  // u is no longer needed (copied into basis)
      nv.noalias() = w.nullspace.leftCols(d) * v;
      w.nullspace.leftCols(d).noalias() -= (2.0 / vv) * nv * v.transpose();
    }
  }
  w.null_dim -= 1;
  if (path == Path::Reference) {
    w.projector0.noalias() -= w.basis.col(r) * w.basis.col(r).transpose();
    w.projector0_dirty = true;
  }
  return true;
}

double smoothDampingSquared(double sigma, const SolveOptions& o) {
  if (sigma >= o.damping_eps) return 0.0;
  const double x = sigma / o.damping_eps;
  return (1.0 - x * x) * o.damping_max * o.damping_max;
}

bool levelActive(const Model::Level& level, const Workspace& w) {
  for (TaskId t : level.tasks)
    if (w.enabled[t]) return true;
  return false;
}

// The level's damping λ² from the smallest singular value of Ĵ, computed on G = Ĵ Ĵᵀ (the same
// m x m matrix in both paths up to round-off: the reference path forms it from J P, the fast
// path as J̃J̃ᵀ - (J̃W)(J̃W)ᵀ). Cheap in the common cases:
//   G - eps² I positive definite      -> σ_min > eps, λ = 0;
//   G not positive definite           -> σ_min = 0, λ = λmax;
//   otherwise inverse iteration on G (Cholesky) for σ_min² = λ_min(G).
// Leaves the Cholesky factor of G in w.level_factor[k] (valid when gram_pd); sigma_min is eps when
// undamped (a lower bound) and 0 when G is singular. Three inverse-iteration steps from G⁻¹'s
// largest column match the converged σ_min to 5 digits on random 12-row levels whose smallest
// singular value is separated (8 steps from a fixed vector did not always); with two nearly equal
// smallest values the estimate lies between them, which is all the smooth rule needs.
constexpr int kInverseIterations = 3;

struct LevelDamping {
  double lambda2 = 0.0;
  double sigma_min = 0.0;
  bool gram_pd = false;
};

LevelDamping levelDamping(const Eigen::MatrixXd& gram, Workspace& w, size_t k, const SolveOptions& o) {
  LevelDamping d;
  Eigen::MatrixXd& l = w.level_factor[k];
  Eigen::VectorXd& lInv = w.level_factor_inv[k];
  l = gram;
  d.gram_pd = detail::choleskyInPlace(l, lInv);
  if (!d.gram_pd) {
    d.lambda2 = o.damping_max * o.damping_max;
    return d;
  }
  Eigen::MatrixXd& shifted = w.level_factor2[k];
  shifted = gram;
  shifted.diagonal().array() -= o.damping_eps * o.damping_eps;
  if (detail::choleskyInPlace(shifted, w.level_factor2_inv[k])) {
    d.sigma_min = o.damping_eps;
    return d;
  }
  // Inverse iteration: the Rayleigh quotient of G⁻¹ converges to 1/λ_min(G) as (σ1/σ2)^(2k).
  // A fixed number of steps (no round-off-dependent stopping test) keeps both paths identical;
  // the estimate lies between σ1 and σ2, and the rule only needs it to grow smoothly. G⁻¹ is
  // formed once, so each step is one (vectorised) matrix-vector product, and the start is its
  // column with the largest diagonal entry: G⁻¹ e_i, one step ahead of the best unit vector.
  Eigen::VectorXd& x = w.level_coef[k];
  Eigen::VectorXd& z = w.level_tmp[k];
  Eigen::MatrixXd& inverse = w.level_inverse[k];
  detail::choleskyInverse(l, lInv, w.level_factor2[k], inverse);
  Eigen::Index start = 0;
  inverse.diagonal().maxCoeff(&start);
  x = inverse.col(start);
  double mu = 0.0;
  for (int it = 0; it < kInverseIterations; ++it) {
    const double xn = x.norm();
    if (!(xn > 0) || !std::isfinite(xn)) break;
    x *= 1.0 / xn;
    z.noalias() = inverse * x;
    mu = x.dot(z);
    x.swap(z);
  }
  d.sigma_min = mu > 0 ? std::sqrt(1.0 / mu) : 0.0;
  d.lambda2 = smoothDampingSquared(d.sigma_min, o);
  return d;
}

// Scale for one level's contribution to Δq of norm `norm` (1 when within the trust region).
// The undamped step on a rank-deficient level (damping_max = 0): y := G⁺ y, so that Ĵᵀ y = Ĵ⁺ res
// (least squares, minimum norm), as the reference path's SVD with σ ≤ rank_tolerance dropped.
// A pivoted Cholesky gives G's rank and, with C the m x rank lower-trapezoidal factor of the
// permuted G ≈ C Cᵀ, G⁺ = C (CᵀC)⁻² Cᵀ. Without it the plain solve divides by a round-off pivot
// (|Δq| ~ 1e7 on two copies of one task).
void truncatedSolve(const Eigen::MatrixXd& gram, Workspace& w, size_t k, const SolveOptions& o, Eigen::VectorXd& y) {
  const auto m = gram.rows();
  Eigen::MatrixXd& work = w.level_factor2[k];
  const Eigen::VectorXi& perm = w.level_perm[k];
  const int a = detail::pivotedCholesky(gram, o.rank_tolerance * o.rank_tolerance, static_cast<int>(m), work,
                                        w.level_perm[k], w.level_factor2_inv[k]);
  if (a == 0) {
    y.setZero();
    return;
  }
  work.topLeftCorner(a, a).triangularView<Eigen::StrictlyUpper>().setZero();
  const auto c = work.leftCols(a);
  Eigen::VectorXd& t = w.level_tmp[k];
  for (Eigen::Index i = 0; i < m; ++i) t(i) = y(perm(i));
  auto u = w.level_coef[k].head(a);
  u.noalias() = c.transpose() * t;
  auto gram_c = w.level_solve.topLeftCorner(a, a);
  gram_c.noalias() = c.transpose() * c;
  Eigen::internal::llt_inplace<double, Eigen::Lower>::blocked(gram_c);
  for (int twice = 0; twice < 2; ++twice) {
    gram_c.triangularView<Eigen::Lower>().solveInPlace(u);
    gram_c.triangularView<Eigen::Lower>().transpose().solveInPlace(u);
  }
  t.noalias() = c * u;
  for (Eigen::Index i = 0; i < m; ++i) y(perm(i)) = t(i);
}

double levelStepScale(double norm, const SolveOptions& o) {
  if (!(o.max_level_step > 0) || !std::isfinite(o.max_level_step) || !(norm > o.max_level_step)) return 1.0;
  return o.max_level_step / norm;
}

// dst += sign * a * b. Small products (a few hundred multiply-adds, the usual size here) skip
// Eigen's blocked GEMM, whose packing costs more than the arithmetic at these sizes.
template <typename Dst, typename A, typename B>
void addProduct(Dst&& dst, const A& a, const B& b, double sign) {
  if (a.rows() * a.cols() * b.cols() <= kLazyProductLimit) {
    if (sign > 0)
      dst.noalias() += a.lazyProduct(b);
    else
      dst.noalias() -= a.lazyProduct(b);
  } else {
    if (sign > 0)
      dst.noalias() += a * b;
    else
      dst.noalias() -= a * b;
  }
}

// J̃ = J N over N's sparsity: consecutive columns with the same span of non-zero rows form a
// group (a free dof's unit column, or the constrained dofs' block), and each group costs a
// product over its rows only. The groups are found again only after N changed.
void nullspaceProduct(Workspace& w, int r) {
  if (w.null_ranges_dirty || w.null_groups_cols != r) {
    w.null_groups.clear();
    for (int c = 0; c < r; ++c) {
      int lo = 0, hi = w.n;
      while (lo < hi && w.nullspace(lo, c) == 0.0) ++lo;
      while (hi > lo && w.nullspace(hi - 1, c) == 0.0) --hi;
      if (!w.null_groups.empty() && w.null_groups.back().row_begin == lo && w.null_groups.back().row_end == hi &&
          w.null_groups.back().col_end == c)
        w.null_groups.back().col_end = c + 1;
      else
        w.null_groups.push_back({c, c + 1, lo, hi});
    }
    w.null_ranges_dirty = false;
    w.null_groups_cols = r;
    if (!w.nullspace_dirty && r == w.n - w.eq_rank && w.eq_null_groups.empty()) w.eq_null_groups = w.null_groups;
  }
  for (const Workspace::ColumnGroup& g : w.null_groups) {
    const int rows = g.row_end - g.row_begin, cols = g.col_end - g.col_begin;
    auto dst = w.reduced_jacobian.middleCols(g.col_begin, cols);
    if (rows == 0)
      dst.setZero();
    else if (rows == 1 && cols == 1)  // a free dof's unit column (±1 after a reflection)
      dst.col(0) = w.nullspace(g.row_begin, g.col_begin) * w.jacobian.col(g.row_begin);
    else if (rows == 1)
      dst.noalias() = w.jacobian.col(g.row_begin) * w.nullspace.block(g.row_begin, g.col_begin, 1, cols);
    else
      dst.noalias() = w.jacobian.middleCols(g.row_begin, rows) * w.nullspace.block(g.row_begin, g.col_begin, rows, cols);
  }
}

// Dense mode: the reduced columns (and their ranges) whose column group of N reaches any of the
// dof ranges `dofs` (a level's recruited dofs), into w.dense_support / w.dense_support_ranges.
void denseSupport(Workspace& w, const std::vector<Workspace::Range>& dofs, int r) {
  w.dense_support.clear();
  w.dense_support_ranges.clear();
  for (const Workspace::ColumnGroup& g : w.null_groups) {
    bool reaches = false;
    for (const Workspace::Range& d : dofs)
      if (d.begin < g.row_end && g.row_begin < d.end) {
        reaches = true;
        break;
      }
    if (!reaches || g.col_begin >= r) continue;
    const int end = std::min(g.col_end, r);
    for (int c = g.col_begin; c < end; ++c) w.dense_support.push_back(c);
    if (!w.dense_support_ranges.empty() && w.dense_support_ranges.back().end == g.col_begin)
      w.dense_support_ranges.back().end = end;
    else
      w.dense_support_ranges.push_back({g.col_begin, end});
  }
}

// Calls f(lo, hi) for every non-empty intersection of two sorted lists of disjoint [lo, hi).
template <typename F>
void forEachOverlap(const std::vector<Workspace::Range>& a, const std::vector<Workspace::Range>& b, F&& f) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const int lo = std::max(a[i].begin, b[j].begin), hi = std::min(a[i].end, b[j].end);
    if (lo < hi) f(lo, hi);
    if (a[i].end < b[j].end)
      ++i;
    else
      ++j;
  }
}

// The rows marked in `mark` (first r entries) as sorted ranges.
void markedRanges(const std::vector<char>& mark, int r, std::vector<Workspace::Range>& out) {
  out.clear();
  for (int i = 0; i < r;) {
    if (!mark[i]) {
      ++i;
      continue;
    }
    const int lo = i;
    while (i < r && mark[i]) ++i;
    out.push_back({lo, i});
  }
}

// The fast pass works in reduced coordinates z (Δq = Δq0 + N Δz, or a diagonal mask when only
// single-dof rows are active) and never forms a projected Jacobian Ĵ = J̃ (I - W Wᵀ): with W the
// orthonormal rows the higher levels took (r x s),
//   G       = Ĵ Ĵᵀ = J̃ J̃ᵀ - (J̃W)(J̃W)ᵀ
//   Ĵᵀ y    = J̃ᵀ y - W (J̃W)ᵀ y
//   Ĵᵀ L⁻ᵀ  = (J̃ᵀ - W (J̃W)ᵀ) L⁻ᵀ         (the level's new orthonormal rows, G = L Lᵀ)
// and it exploits sparsity. In mask mode a level's J̃ is non-zero only on the dofs its tasks
// recruit (a foot: 20 of the humanoid's 61), kept as sorted ranges of dof indices; W is kept as
// one block of columns per level, each non-zero only on the ranges of rows of its level and of
// the blocks it was projected against. Products with W then run over the overlapping ranges
// only (a hand shares just the root with the feet), and the last active level skips the
// projector update altogether. Dense mode (equality rows, N = [free dofs' unit columns | the
// constrained dofs' block]) does the same over the reduced columns whose group of N reaches a
// level's dofs (denseSupport).
void fastPass(const Model& model, Workspace& w, const SolveOptions& o) {
  const bool maskMode = w.mask_mode;
  const int r = maskMode ? w.n : w.null_dim;
  // The levels' steps accumulate in reduced coordinates z; Δq = Δq0 + N z (or Δq0 + z) once at
  // the end. The compensated errors use J Δq = J Δq0 + J̃ z.
  auto z = w.small_z.head(r);
  z.setZero();
  auto jdq0 = w.small_rows.head(w.rows);
  if (w.rank > 0)
    jdq0.noalias() = w.jacobian * w.dq0;
  else
    jdq0.setZero();
  // Mask mode reads J̃ = J diag(mask) straight from J. Products with W may even use J itself:
  // W's rows at pinned dofs are zero, as W lies in the null space of the active rows.
  if (!maskMode) nullspaceProduct(w, r);
  const Eigen::MatrixXd& jFull = maskMode ? w.jacobian : w.reduced_jacobian;
  int lastActive = -1;
  for (size_t k = 0; k < model.levels.size(); ++k)
    if (levelActive(model.levels[k], w)) lastActive = static_cast<int>(k);
  int s = 0;       // columns of W
  int blocks = 0;  // W's blocks: block b has columns block_begin[b] + [0, block_size[b])
  for (size_t k = 0; k < model.levels.size(); ++k) {
    const Model::Level& level = model.levels[k];
    if (!levelActive(level, w) || s >= r) continue;
    const int m = level.rows;
    // The level's support in reduced coordinates: its recruited dofs in mask mode; in dense mode
    // the columns of N that reach any of them (N's column groups over the level's dof ranges).
    if (!maskMode) denseSupport(w, w.level_ranges[k], r);
    const std::vector<int>& support = maskMode ? w.level_support[k] : w.dense_support;
    const std::vector<Workspace::Range>& ranges = maskMode ? w.level_ranges[k] : w.dense_support_ranges;
    const int p = static_cast<int>(support.size());
    const bool gather = maskMode || p < r;
    const auto jRows = jFull.middleRows(level.first_row, m);

    // J̃ on the level's support: gathered (mask mode: J diag(mask) read straight from J), or the
    // block of J N when the level reaches every reduced coordinate.
    if (gather) {
      auto g = w.gathered_j.topLeftCorner(m, p);
      for (int i = 0; i < p; ++i) {
        const int c = support[i];
        if (!maskMode)
          g.col(i) = w.reduced_jacobian.col(c).segment(level.first_row, m);
        else if (w.rank == 0 || w.mask(c) != 0.0)  // no pinned dof: J̃ = J
          g.col(i) = w.jacobian.col(c).segment(level.first_row, m);
        else
          g.col(i).setZero();
      }
    }
    const Eigen::Ref<const Eigen::MatrixXd> js =
        gather ? Eigen::Ref<const Eigen::MatrixXd>(w.gathered_j.topLeftCorner(m, p))
               : Eigen::Ref<const Eigen::MatrixXd>(w.reduced_jacobian.block(level.first_row, 0, m, r));
    // J̃W block by block, over the rows the level shares with each block.
    auto jw = w.level_jw[k].leftCols(s);
    for (int b = 0; b < blocks; ++b) {
      auto jwb = jw.middleCols(w.block_begin[b], w.block_size[b]);
      jwb.setZero();
      bool touched = false;
      forEachOverlap(ranges, w.block_ranges[b], [&](int lo, int hi) {
        addProduct(jwb, jRows.middleCols(lo, hi - lo), w.row_space.block(lo, w.block_begin[b], hi - lo, w.block_size[b]), 1.0);
        touched = true;
      });
      w.block_touched[b] = touched ? 1 : 0;
    }

    Eigen::VectorXd& res = w.level_res[k];
    res = w.error.segment(level.first_row, m);
    res -= jdq0.segment(level.first_row, m);  // compensated error
    if (gather) {
      auto zs = w.small_b.head(p);
      for (int i = 0; i < p; ++i) zs(i) = z(support[i]);
      res.noalias() -= js * zs;
    } else {
      res.noalias() -= js * z;
    }

    Eigen::MatrixXd& gram = w.level_gram[k];  // lower triangle only: the kernels read just that
    gram.setZero();
    gram.selfadjointView<Eigen::Lower>().rankUpdate(js);
    if (s > 0) gram.selfadjointView<Eigen::Lower>().rankUpdate(jw, -1.0);
    const LevelDamping d = levelDamping(gram, w, k, o);

    // Damped step: Δz = Ĵᵀ (G + λ² I)⁻¹ res.
    Eigen::VectorXd& y = w.level_y[k];
    y = res;
    if (d.lambda2 > 0) {
      Eigen::MatrixXd& damped = w.level_factor2[k];
      damped = gram;
      damped.diagonal().array() += d.lambda2;
      // G + λ² I with λ² > 0 is positive definite unless round-off made G indefinite by more
      // than λ²; then this level takes no step rather than a wrong one.
      if (detail::choleskyInPlace(damped, w.level_factor2_inv[k]))
        detail::choleskySolve(damped, w.level_factor2_inv[k], y.data());
      else
        y.setZero();
    } else if (d.gram_pd && d.sigma_min > o.rank_tolerance) {
      detail::choleskySolve(w.level_factor[k], w.level_factor_inv[k], y.data());
    } else {  // λ = 0 on a rank-deficient level: only with damping_max = 0
      truncatedSolve(gram, w, k, o, y);
    }
    auto dz = w.tmp_n.head(r);
    if (gather) {
      auto jty = w.small_a.head(p);
      jty.noalias() = js.transpose() * y;
      dz.setZero();
      for (int i = 0; i < p; ++i) dz(support[i]) = jty(i);
    } else {
      dz.noalias() = js.transpose() * y;
    }
    for (int b = 0; b < blocks; ++b) {
      if (!w.block_touched[b]) continue;
      const int c0 = w.block_begin[b], nb = w.block_size[b];
      auto wy = w.small_b.head(nb);
      wy.noalias() = jw.middleCols(c0, nb).transpose() * y;
      for (const Workspace::Range& g : w.block_ranges[b])
        dz.segment(g.begin, g.end - g.begin).noalias() -= w.row_space.block(g.begin, c0, g.end - g.begin, nb) * wy;
    }
    if (const double cap = levelStepScale(dz.norm(), o); cap < 1.0) dz *= cap;
    z += dz;

    if (static_cast<int>(k) == lastActive) break;  // nothing below needs this level's rows

    // Projector update (undamped, rank-thresholded): append an orthonormal basis of Ĵ's rows to
    // W as a new block. Ĵᵀ = J̃ᵀ - W (J̃W)ᵀ first (in `jt`, r x m, non-zero on the marked rows).
    auto jt = w.level_cols.topLeftCorner(r, m);
    std::fill(w.row_mark.begin(), w.row_mark.begin() + r, 0);
    if (gather) {
      for (const Workspace::Range& g : ranges) {
        jt.middleRows(g.begin, g.end - g.begin).setZero();
        std::fill(w.row_mark.begin() + g.begin, w.row_mark.begin() + g.end, 1);
      }
      for (int i = 0; i < p; ++i) jt.row(support[i]) = js.col(i).transpose();
    } else {
      jt = js.transpose();
      std::fill(w.row_mark.begin(), w.row_mark.begin() + r, 1);
    }
    for (int b = 0; b < blocks; ++b) {
      if (!w.block_touched[b]) continue;
      const int c0 = w.block_begin[b], nb = w.block_size[b];
      for (const Workspace::Range& g : w.block_ranges[b]) {
        const int len = g.end - g.begin;
        for (int i = g.begin; i < g.end; ++i)
          if (!w.row_mark[i]) {
            jt.row(i).setZero();
            w.row_mark[i] = 1;
          }
        addProduct(jt.middleRows(g.begin, len), w.row_space.block(g.begin, c0, len, nb), jw.middleCols(c0, nb).transpose(), -1.0);
      }
    }
    std::vector<Workspace::Range>& newRanges = w.block_ranges[blocks];
    markedRanges(w.row_mark, r, newRanges);

    int added = 0;
    double smallest = 0.0;
    if (d.gram_pd && d.sigma_min > o.rank_tolerance && m <= r - s) {
      // Full rank: U = Ĵᵀ L⁻ᵀ (no eigen-decomposition), row range by row range.
      added = m;
      smallest = d.sigma_min;
      auto u = w.row_space.block(0, s, r, m);
      for (int i = 0, next = 0; i < static_cast<int>(newRanges.size()); ++i) {
        const Workspace::Range& g = newRanges[i];
        u.middleRows(next, g.begin - next).setZero();
        auto rows = u.middleRows(g.begin, g.end - g.begin);
        rows = jt.middleRows(g.begin, g.end - g.begin);
        detail::solveRightLowerTransposed(w.level_factor[k], w.level_factor_inv[k], rows);
        next = g.end;
        if (i + 1 == static_cast<int>(newRanges.size())) u.bottomRows(r - g.end).setZero();
      }
    } else {
      // Rank-deficient level: a pivoted Cholesky of G picks rows I of Ĵ that span its row space
      // (pivots > tolerance²); then U = Ĵ_Iᵀ L_II⁻ᵀ as for a full-rank level. An eigen-
      // decomposition would do too, at ten times the cost for a 24-row level (the seated legs).
      Eigen::MatrixXd& work = w.level_factor2[k];
      Eigen::VectorXi& perm = w.level_perm[k];
      added = detail::pivotedCholesky(gram, o.rank_tolerance * o.rank_tolerance, r - s, work, perm,
                                      w.level_factor2_inv[k]);
      if (added == 0) continue;
      auto lower = work.topLeftCorner(added, added);
      auto linvT = w.level_inverse[k].topLeftCorner(added, added);  // L_II⁻ᵀ
      linvT.setIdentity();
      detail::solveRightLowerTransposed(lower, w.level_factor2_inv[k], linvT);
      auto coef = w.level_solve.topLeftCorner(m, added);
      coef.setZero();
      for (int a = 0; a < added; ++a) coef.row(perm(a)) = linvT.row(a);
      auto u = w.row_space.block(0, s, r, added);
      u.setZero();
      for (const Workspace::Range& g : newRanges)
        u.middleRows(g.begin, g.end - g.begin).noalias() = jt.middleRows(g.begin, g.end - g.begin) * coef;
      smallest = std::numeric_limits<double>::infinity();
      for (int a = 0; a < added; ++a) smallest = std::min(smallest, work(a, a));
    }
    // The new rows are analytically orthogonal to W; round-off grows like eps |J̃| / σ, so
    // re-orthogonalise (densely; rare) when a kept singular value is small.
    if (smallest < 1e-3 && s > 0) {
      for (int c = 0; c < added; ++c) {
        auto col = w.row_space.col(s + c).head(r);
        auto proj = w.small_b.head(s + c);
        proj.noalias() = w.row_space.topLeftCorner(r, s + c).transpose() * col;
        col.noalias() -= w.row_space.topLeftCorner(r, s + c) * proj;
        col.normalize();
      }
      newRanges.clear();
      newRanges.push_back({0, r});
    }
    w.block_begin[blocks] = s;
    w.block_size[blocks] = added;
    ++blocks;
    s += added;
  }
  w.dq = w.dq0;
  if (maskMode)
    w.dq += z;
  else
    for (const Workspace::ColumnGroup& g : w.null_groups)
      w.dq.segment(g.row_begin, g.row_end - g.row_begin).noalias() +=
          w.nullspace.block(g.row_begin, g.col_begin, g.row_end - g.row_begin, g.col_end - g.col_begin) *
          z.segment(g.col_begin, g.col_end - g.col_begin);
}


void referencePass(const Model& model, Workspace& w, const SolveOptions& o) {
  w.dq = w.dq0;
  w.projector = w.projector0;
  for (size_t k = 0; k < model.levels.size(); ++k) {
    const Model::Level& level = model.levels[k];
    if (!levelActive(level, w)) continue;
    const int m = level.rows;
    const auto j = w.jacobian.middleRows(level.first_row, m);
    Eigen::VectorXd& res = w.level_res[k];
    res = w.error.segment(level.first_row, m);
    res.noalias() -= j * w.dq;
    Eigen::MatrixXd& jh = w.level_j[k];
    jh.noalias() = j * w.projector;
    Eigen::MatrixXd& gram = w.level_gram[k];
    gram.noalias() = jh * jh.transpose();
    const double lambda2 = levelDamping(gram, w, k, o).lambda2;
    auto& svd = w.level_svd[k];
    svd.compute(jh);
    const auto& sv = svd.singularValues();
    Eigen::VectorXd& coef = w.level_y[k];
    const int p = static_cast<int>(sv.size());
    coef.head(p).noalias() = svd.matrixU().transpose() * res;
    for (int i = 0; i < p; ++i) {
      const double sigma = sv(i);
      const double denom = sigma * sigma + lambda2;
      // λ = 0 (damping_max = 0) drops the rank-deficient directions as the projector does.
      const bool kept = lambda2 > 0 || sigma > o.rank_tolerance;
      coef(i) = kept && denom > 0 ? coef(i) * sigma / denom : 0.0;
    }
    if (const double cap = levelStepScale(coef.head(p).norm(), o); cap < 1.0) coef.head(p) *= cap;  // |V c| = |c|
    w.dq.noalias() += svd.matrixV() * coef.head(p);
    for (int i = 0; i < p; ++i)
      if (sv(i) > o.rank_tolerance) w.projector.noalias() -= svd.matrixV().col(i) * svd.matrixV().col(i).transpose();
  }
}

void runPass(const Model& model, Workspace& w, const SolveOptions& o) {
  if (o.path == Path::Fast)
    fastPass(model, w, o);
  else
    referencePass(model, w, o);
}

double rowValue(const Workspace& w, size_t i, const Eigen::VectorXd& x) {
  double v = 0.0;
  for (int k = w.ineq_begin[i]; k < w.ineq_begin[i + 1]; ++k) v += w.ineq_coef[k] * x(w.ineq_dof[k]);
  return v;
}

// Loads inequality row i into w.tmp_n and pins it at its bound (c^T (q + Δq) = rhs). Returns
// false when it depends on the active set (nothing changes then).
bool pinRow(const Model& model, Workspace& w, size_t i, Path path) {
  const double current = rowValue(w, i, w.q);
  w.tmp_n.setZero();
  for (int k = w.ineq_begin[i]; k < w.ineq_begin[i + 1]; ++k) w.tmp_n(w.ineq_dof[k]) += w.ineq_coef[k];
  const int single = w.ineq_begin[i + 1] - w.ineq_begin[i] == 1 ? w.ineq_dof[w.ineq_begin[i]] : -1;
  return addActiveRow(w, model.inequalities[i].rhs - current, single, path, 1e-9);
}

// The active set again from the equality rows: the pinned rows (report.active_clamps, in the
// order they were added) except `skip`.
void rebuildActiveSet(const Model& model, Workspace& w, Path path, int skip) {
  resetActiveSet(w, path);
  for (int r : w.report.active_clamps)
    if (r != skip && pinRow(model, w, static_cast<size_t>(r), path)) w.ineq_active[r] = 1;
}

double nextRowValue(const Workspace& w, size_t i) {
  double next = rowValue(w, i, w.q);
  for (int k = w.ineq_begin[i]; k < w.ineq_begin[i + 1]; ++k) next += w.ineq_coef[k] * w.dq(w.ineq_dof[k]);
  return next;
}

// Row i is violated by q + Δq but depends on the pinned rows: held at their bounds, they fix its
// value. A pinned row only has to hold as an inequality, so one of them may be the wrong one to
// hold at its bound (two regions' opposite limits pinned in one sweep leave the band between
// them no room; pinning the band instead leaves one of those limits inactive). Tries each pinned
// row, latest first, replaced by row i, and keeps the first exchange whose step satisfies the
// released row; otherwise restores the active set and step. Only rows that were dependent and
// violated pay for this (a rebuild and a pass per try).
bool exchangePinnedRow(const Model& model, Workspace& w, const SolveOptions& o, size_t i) {
  std::vector<int>& pinned = w.report.active_clamps;
  for (size_t k = pinned.size(); k-- > 0;) {
    const int released = pinned[k];
    rebuildActiveSet(model, w, o.path, released);
    if (!pinRow(model, w, i, o.path)) continue;
    computeDq0(w);
    runPass(model, w, o);
    if (nextRowValue(w, static_cast<size_t>(released)) > model.inequalities[released].rhs + o.inequality_tolerance)
      continue;
    pinned.erase(pinned.begin() + static_cast<std::ptrdiff_t>(k));  // capacity reserved: no allocation
    pinned.push_back(static_cast<int>(i));
    w.ineq_active[i] = 1;
    return true;
  }
  rebuildActiveSet(model, w, o.path, -1);
  computeDq0(w);
  runPass(model, w, o);
  return false;
}

// Pins every inequality violated by q + Δq (user couplings first: the model keeps that order).
// Returns whether a row was added.
bool pinViolations(const Model& model, Workspace& w, const SolveOptions& o) {
  bool added = false;
  for (size_t i = 0; i < model.inequalities.size(); ++i) {
    if (w.ineq_active[i]) continue;
    if (!(nextRowValue(w, i) > model.inequalities[i].rhs + o.inequality_tolerance)) continue;
    // A row dependent on the active set is first offered in exchange for a pinned row; if none
    // can give way it is skipped (first added wins), and reported only if it is still violated
    // once the loop settles (pinning its partner often satisfies it).
    if (pinRow(model, w, i, o.path)) {
      w.ineq_active[i] = 1;
      w.report.active_clamps.push_back(static_cast<int>(i));
      added = true;
    } else if (exchangePinnedRow(model, w, o, i)) {
      added = true;
    }
  }
  return added;
}

void reportRemainingViolations(const Model& model, Workspace& w, const SolveOptions& o) {
  for (size_t i = 0; i < model.inequalities.size(); ++i) {
    if (w.ineq_active[i] || w.ineq_reported[i]) continue;
    if (nextRowValue(w, i) > model.inequalities[i].rhs + o.inequality_tolerance) {
      w.ineq_reported[i] = 1;
      w.report.unsatisfiable.push_back(static_cast<int>(i));
    }
  }
}

void reparameterize(const Model& model, Workspace& w) {
  for (const Model::Joint& j : model.joints) {
    if (!j.reparameterize) continue;
    if (j.desc.type == JointType::Swing) {
      Eigen::Vector3d v = j.swing_basis * w.q.segment<2>(j.first_dof);
      if (reparameterizeExpMap(v)) w.q.segment<2>(j.first_dof) = j.swing_basis.transpose() * v;
      continue;
    }
    const int f = j.first_dof + (j.desc.type == JointType::Free ? 3 : 0);
    Eigen::Vector3d v = w.q.segment<3>(f);
    if (reparameterizeExpMap(v)) w.q.segment<3>(f) = v;
  }
}

// The oscillation guard's scaled step Δq0 + s (Δq - Δq0) moves each row's value linearly from
// its value at q + Δq0 to the one at q + Δq. Δq0 alone (the pinned rows at their bounds) may
// break a row the full step keeps (a limit pinned pushes a band past its slack), so the scale
// may not go below what keeps every row the clamping loop left satisfied.
double smallestScaleKeepingRows(const Model& model, const Workspace& w, const SolveOptions& o) {
  double smallest = 0.0;
  for (size_t i = 0; i < model.inequalities.size(); ++i) {
    const double bound = model.inequalities[i].rhs + o.inequality_tolerance;
    const double full = nextRowValue(w, i);
    if (full > bound) continue;  // violated anyway (reported): the scale cannot help
    double base = rowValue(w, i, w.q);
    for (int k = w.ineq_begin[i]; k < w.ineq_begin[i + 1]; ++k) base += w.ineq_coef[k] * w.dq0(w.ineq_dof[k]);
    if (base > bound) smallest = std::max(smallest, (base - bound) / (base - full));
  }
  return std::min(smallest, 1.0);
}

// The iteration after kinematics(): active-set reset, clamping loop, q += Δq.
// Returns false (q unchanged) if the step came out non-finite.
bool step(const Model& model, Workspace& w, const SolveOptions& o) {
  w.report.active_clamps.clear();
  w.report.unsatisfiable.clear();
  resetActiveSet(w, o.path);
  computeDq0(w);
  runPass(model, w, o);
  int passes = 1;
  while (o.clamping) {
    if (passes >= std::max(1, o.max_clamp_passes) || !pinViolations(model, w, o)) {
      reportRemainingViolations(model, w, o);
      break;
    }
    computeDq0(w);
    runPass(model, w, o);
    ++passes;
  }
  w.report.clamp_passes = passes;
  if (!w.dq.allFinite()) return false;
  if (o.oscillation_guard) {
    // The task part of the step (Δq - Δq0) lies in the null space of the active rows, so scaling
    // it keeps every pinned row and every priority relation exact. A step that reverses the
    // previous one (a period-2 cycle of the Gauss-Newton map near an unreachable or singular
    // target) halves the scale; consistent steps let it grow back to 1.
    Eigen::VectorXd& task = w.tmp_n;
    task = w.dq - w.dq0;
    const double norms = task.norm() * w.previous_task_step.norm();
    if (w.has_previous_step && norms > 0 && task.dot(w.previous_task_step) < -0.3 * norms)
      w.step_scale = std::max(w.step_scale * 0.5, 1.0 / 64);
    else
      w.step_scale = std::min(1.0, w.step_scale * 1.25);
    w.previous_task_step = task;
    w.has_previous_step = true;
    const double scale = w.step_scale < 1.0 ? std::max(w.step_scale, smallestScaleKeepingRows(model, w, o)) : 1.0;
    w.dq = w.dq0 + scale * task;
  }
  w.q += w.dq;
  reparameterize(model, w);
  return true;
}

bool validOptions(const SolveOptions& o) {
  return o.max_iterations >= 0 && std::isfinite(o.damping_max) && o.damping_max >= 0 &&
         std::isfinite(o.damping_eps) && o.damping_eps > 0 && std::isfinite(o.rank_tolerance) &&
         o.rank_tolerance > 0 && std::isfinite(o.inequality_tolerance) && o.inequality_tolerance >= 0 &&
         !(o.max_level_step < 0) && !std::isnan(o.max_level_step);
}

void fillResiduals(const Model& model, Workspace& w) {
  for (int t = 0; t < w.task_count; ++t) w.report.tasks[t] = w.residual[t];
  for (size_t k = 0; k < model.levels.size(); ++k) {
    double sum = 0.0;
    for (TaskId t : model.levels[k].tasks)
      if (w.enabled[t]) sum += w.residual[t].position * w.residual[t].position + w.residual[t].rotation * w.residual[t].rotation;
    w.report.levels[k] = std::sqrt(sum);
  }
}

bool allSatisfied(const Workspace& w) {
  for (const TaskResidual& r : w.residual)
    if (!r.satisfied) return false;
  return true;
}

}  // namespace

const Eigen::VectorXd& priorityPass(const Model& model, Data& data, const SolveOptions& options) {
  Workspace& w = data.workspace();
  if (!sameShape(model, w)) return w.dq;
  resetActiveSet(w, options.path);
  computeDq0(w);
  runPass(model, w, options);
  return w.dq;
}

void iterate(const Model& model, Data& data, const SolveOptions& options) {
  Workspace& w = data.workspace();
  if (!sameShape(model, w) || !validOptions(options)) return;
  kinematics(model, data, true);
  step(model, w, options);
}

const SolveReport& solve(const Model& model, Data& data, const SolveOptions& options) {
  Workspace& w = data.workspace();
  SolveReport& report = w.report;
  const Clock& clock = options.clock ? *options.clock : steadyClock();
  const Clock::time_point start = clock.now();
  report.iterations = 0;
  report.clamp_passes = 0;
  report.active_clamps.clear();
  report.unsatisfiable.clear();
  if (!sameShape(model, w) || !validOptions(options)) {
    report.stop = StopReason::InvalidState;
    report.elapsed = std::chrono::nanoseconds(0);
    return report;
  }
  report.stop = StopReason::IterationCap;
  kinematics(model, data, true);
  for (;;) {
    if (allSatisfied(w)) {
      report.stop = StopReason::Converged;
      break;
    }
    if (report.iterations >= options.max_iterations) break;
    if (options.deadline && clock.now() >= *options.deadline) {
      report.stop = StopReason::Deadline;
      break;
    }
    if (!step(model, w, options)) {
      report.stop = StopReason::InvalidState;
      break;
    }
    ++report.iterations;
    kinematics(model, data, true);
    if (w.dq.norm() < options.min_step) {
      report.stop = allSatisfied(w) ? StopReason::Converged : StopReason::Stalled;
      break;
    }
  }
  fillResiduals(model, w);
  report.elapsed = std::chrono::duration_cast<std::chrono::nanoseconds>(clock.now() - start);
  return report;
}

}  // namespace embody::ik
