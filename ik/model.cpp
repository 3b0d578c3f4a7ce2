#include "ik/model.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>
#include <sstream>

#include "core/enum_names.h"
#include "ik/projector.h"

namespace embody::ik {
namespace {

bool finite(const Eigen::Isometry3d& t) { return t.matrix().allFinite(); }

// A unit vector orthogonal to `axis`: the projection of `hint` (or of a fallback when `hint` is
// nearly parallel).
Eigen::Vector3d orthogonalUnit(const Eigen::Vector3d& axis, const Eigen::Vector3d& hint,
                               const Eigen::Vector3d& fallback) {
  Eigen::Vector3d u = hint - hint.dot(axis) * axis;
  if (u.norm() < 1e-6) u = fallback - fallback.dot(axis) * axis;
  return u.normalized();
}

Error modelError(const std::string& what) { return Error{"ik model: " + what}; }

std::string levelName(const Model& model, TaskId t) {
  return "'" + model.tasks[t].desc.name + "' (level " + std::to_string(model.tasks[t].desc.level) +
         ")";
}

}  // namespace

int dofCount(JointType type) {
  switch (type) {
    case JointType::Free: return 6;
    case JointType::Ball: return 3;
    case JointType::Swing: return 2;
    case JointType::Revolute: return 1;
    case JointType::Fixed: return 0;
  }
  return 0;
}

constexpr EnumName<JointType> kJointTypeNames[] = {{JointType::Free, "free"},
                                                   {JointType::Ball, "ball"},
                                                   {JointType::Swing, "swing"},
                                                   {JointType::Revolute, "revolute"},
                                                   {JointType::Fixed, "fixed"}};

const char* toString(JointType type) {
  return enumName(kJointTypeNames, type);
}

constexpr EnumName<TaskType> kTaskTypeNames[] = {{TaskType::Position, "position"},
                                                 {TaskType::Orientation, "orientation"},
                                                 {TaskType::Pose, "pose"},
                                                 {TaskType::CenterOfMass, "center-of-mass"}};

const char* toString(TaskType type) {
  return enumName(kTaskTypeNames, type);
}

JointId Model::findJoint(const std::string& name) const {
  for (size_t i = 0; i < joints.size(); ++i)
    if (joints[i].desc.name == name) return static_cast<JointId>(i);
  return -1;
}

TaskId Model::findTask(const std::string& name) const {
  for (size_t i = 0; i < tasks.size(); ++i)
    if (tasks[i].desc.name == name) return static_cast<TaskId>(i);
  return -1;
}

int Model::findInequality(const std::string& name) const {
  for (size_t i = 0; i < inequalities.size(); ++i)
    if (inequalities[i].name == name) return static_cast<int>(i);
  return -1;
}

std::string Model::dofName(int dof) const {
  for (const Joint& j : joints)
    if (dof >= j.first_dof && dof < j.first_dof + j.dof_count)
      return j.desc.name + "[" + std::to_string(dof - j.first_dof) + "]";
  return "dof " + std::to_string(dof);
}

JointId ModelBuilder::addJoint(JointDesc joint) {
  joints_.push_back(std::move(joint));
  return static_cast<JointId>(joints_.size() - 1);
}

JointId ModelBuilder::addJoint(std::string name, JointId parent, JointType type,
                               const Eigen::Isometry3d& rest, const Eigen::Vector3d& axis) {
  JointDesc d;
  d.name = std::move(name);
  d.parent = parent;
  d.type = type;
  d.rest = rest;
  d.axis = axis;
  return addJoint(std::move(d));
}

void ModelBuilder::setLimits(DofRef dof, double lower, double upper) {
  if (dof.joint < 0 || dof.joint >= static_cast<JointId>(joints_.size())) return;  // build() fails
  JointDesc& j = joints_[dof.joint];
  const size_t n = static_cast<size_t>(dofCount(j.type));
  if (j.lower.size() != n) j.lower.assign(n, -kUnbounded);
  if (j.upper.size() != n) j.upper.assign(n, kUnbounded);
  if (dof.component < 0 || dof.component >= static_cast<int>(n)) {
    // Remember the bad reference so build() reports it instead of silently ignoring it.
    j.lower.push_back(lower);
    return;
  }
  j.lower[dof.component] = lower;
  j.upper[dof.component] = upper;
}

void ModelBuilder::setSegment(JointId joint, double mass, const Eigen::Vector3d& com) {
  if (joint < 0 || joint >= static_cast<JointId>(joints_.size())) return;
  joints_[joint].mass = mass;
  joints_[joint].com = com;
}

void ModelBuilder::setNeutral(DofRef dof, double value) {
  if (dof.joint < 0 || dof.joint >= static_cast<JointId>(joints_.size())) return;
  JointDesc& j = joints_[dof.joint];
  const size_t n = static_cast<size_t>(dofCount(j.type));
  if (j.neutral.size() != n) j.neutral.assign(n, 0.0);
  if (dof.component < 0 || dof.component >= static_cast<int>(n)) {
    j.neutral.push_back(value);  // build() reports the bad size
    return;
  }
  j.neutral[dof.component] = value;
}

void ModelBuilder::addEquality(EqualityRow row) { equalities_.push_back(std::move(row)); }

void ModelBuilder::addEquality(std::string name, DofRef a, double ca, DofRef b, double cb,
                               double rhs) {
  EqualityRow row;
  row.name = std::move(name);
  row.terms = {{a, ca}, {b, cb}};
  row.rhs = rhs;
  addEquality(std::move(row));
}

void ModelBuilder::addInequality(InequalityRow row) { inequalities_.push_back(std::move(row)); }

TaskId ModelBuilder::addTask(TaskDesc task) {
  tasks_.push_back(std::move(task));
  return static_cast<TaskId>(tasks_.size() - 1);
}

void ModelBuilder::setUp(const Eigen::Vector3d& up) { up_ = up; }

namespace {

// One joint: validated, its dof range assigned, limits and neutral filled in.
Status buildJoint(const JointDesc& desc, size_t i, std::set<std::string>& names, Model& m) {
  Model::Joint j;
  j.desc = desc;
  JointDesc& d = j.desc;
  const std::string who = "joint " + std::to_string(i) + " '" + d.name + "'";
  if (d.name.empty()) return modelError(who + ": empty name");
  if (!names.insert(d.name).second) return modelError(who + ": duplicate name");
  if (d.parent != kNoParent && (d.parent < 0 || d.parent >= static_cast<JointId>(i)))
    return modelError(who + ": parent " + std::to_string(d.parent) + " must be an earlier joint");
  if (!finite(d.rest)) return modelError(who + ": rest transform is not finite");
  const Eigen::Matrix3d r = d.rest.linear();
  if (!(r.transpose() * r).isApprox(Eigen::Matrix3d::Identity(), 1e-6) || r.determinant() < 0)
    return modelError(who + ": rest transform's linear part is not a rotation");
  if (d.type == JointType::Revolute || d.type == JointType::Swing) {
    if (!d.axis.allFinite() || d.axis.norm() < 1e-9) return modelError(who + ": axis must be finite and non-zero");
    d.axis.normalize();
  }
  j.dof_count = dofCount(d.type);
  j.first_dof = m.dofs;
  m.dofs += j.dof_count;
  const size_t n = static_cast<size_t>(j.dof_count);
  if (d.lower.empty()) d.lower.assign(n, -kUnbounded);
  if (d.upper.empty()) d.upper.assign(n, kUnbounded);
  if (d.lower.size() != n || d.upper.size() != n)
    return modelError(who + ": limits need " + std::to_string(n) + " entries (a limit names a missing dof?)");
  for (size_t k = 0; k < n; ++k) {
    if (std::isnan(d.lower[k]) || std::isnan(d.upper[k]) || d.lower[k] > d.upper[k])
      return modelError(who + ": limits of dof " + std::to_string(k) + " are not an interval");
  }
  if (d.neutral.empty()) d.neutral.assign(n, 0.0);
  if (d.neutral.size() != n) return modelError(who + ": neutral needs " + std::to_string(n) + " entries");
  for (size_t k = 0; k < n; ++k)
    if (!std::isfinite(d.neutral[k])) return modelError(who + ": neutral value of dof " + std::to_string(k) + " is not finite");
  if (!std::isfinite(d.mass) || d.mass < 0) return modelError(who + ": mass must be finite and >= 0");
  if (!d.com.allFinite()) return modelError(who + ": centre of mass is not finite");
  if (d.type == JointType::Swing) {
    j.swing_basis.col(0) = orthogonalUnit(d.axis, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ());
    j.swing_basis.col(1) = d.axis.cross(j.swing_basis.col(0));
  }
  m.total_mass += d.mass;
  m.joints.push_back(std::move(j));
  return Status::success();
}

// A row's terms: joints and dofs exist, coefficients finite and not all zero; written densely.
Status checkTerms(const Model& m, const std::vector<LinearTerm>& terms, const std::string& who,
                  Eigen::Ref<Eigen::RowVectorXd, 0, Eigen::InnerStride<>> dense) {
  if (terms.empty()) return modelError(who + ": no terms");
  dense.setZero();
  for (const LinearTerm& t : terms) {
    if (t.dof.joint < 0 || t.dof.joint >= static_cast<JointId>(m.joints.size()))
      return modelError(who + ": joint " + std::to_string(t.dof.joint) + " does not exist");
    const Model::Joint& j = m.joints[t.dof.joint];
    if (t.dof.component < 0 || t.dof.component >= j.dof_count)
      return modelError(who + ": joint '" + j.desc.name + "' (" + toString(j.desc.type) + ") has no dof " +
                  std::to_string(t.dof.component));
    if (!std::isfinite(t.coefficient)) return modelError(who + ": coefficient is not finite");
    dense(m.dofIndex(t.dof)) += t.coefficient;
  }
  if (dense.norm() == 0) return modelError(who + ": all coefficients are zero");
  return Status::success();
}

// Equalities, with the corrected Algorithm 1 to find dependent rows (first added wins).
Status addEqualities(const std::vector<EqualityRow>& equalities, Model& m) {
  const int g = static_cast<int>(equalities.size());
  m.equality_matrix.setZero(g, m.dofs);
  m.equality_rhs.setZero(g);
  for (int i = 0; i < g; ++i) {
    const EqualityRow& row = equalities[i];
    const std::string who = "equality " + std::to_string(i) + " '" + row.name + "'";
    if (Status s = checkTerms(m, row.terms, who, m.equality_matrix.row(i)); !s) return Error{s.error()};
    if (!std::isfinite(row.rhs)) return modelError(who + ": rhs is not finite");
    m.equality_rhs(i) = row.rhs;
    m.equalities.push_back(row);
  }
  (void)incrementalNullspaceProjector(m.equality_matrix, 1e-9, &m.dependent_equalities);

  return Status::success();
}

// Inequalities: user couplings, then joint-limit rows (given, then generated from limits).
Status addInequalities(const std::vector<InequalityRow>& inequalities, Model& m) {
  Eigen::RowVectorXd scratch(m.dofs);
  for (InequalityKind kind : {InequalityKind::UserCoupling, InequalityKind::JointLimit}) {
    for (size_t i = 0; i < inequalities.size(); ++i) {
      const InequalityRow& row = inequalities[i];
      if (row.kind != kind) continue;
      const std::string who = "inequality " + std::to_string(i) + " '" + row.name + "'";
      if (Status s = checkTerms(m, row.terms, who, scratch); !s) return Error{s.error()};
      if (!std::isfinite(row.rhs)) return modelError(who + ": rhs is not finite");
      m.inequalities.push_back(row);
    }
  }
  for (size_t ji = 0; ji < m.joints.size(); ++ji) {
    const JointDesc& d = m.joints[ji].desc;
    for (int k = 0; k < m.joints[ji].dof_count; ++k) {
      const DofRef ref{static_cast<JointId>(ji), k};
      if (std::isfinite(d.upper[k]))
        m.inequalities.push_back({d.name + "[" + std::to_string(k) + "] <= upper", {{ref, 1.0}}, d.upper[k],
                                  InequalityKind::JointLimit});
      if (std::isfinite(d.lower[k]))
        m.inequalities.push_back({d.name + "[" + std::to_string(k) + "] >= lower", {{ref, -1.0}}, -d.lower[k],
                                  InequalityKind::JointLimit});
    }
  }

  return Status::success();
}

// Exp-map joints whose dofs appear in no constraint row and carry no limits may be
// re-parameterised near |v| = π (that changes q, which would break a linear row).
void markReparameterizable(Model& m) {
  std::vector<char> constrained(m.dofs, 0);
  for (const EqualityRow& r : m.equalities)
    for (const LinearTerm& t : r.terms) constrained[m.dofIndex(t.dof)] = 1;
  for (const InequalityRow& r : m.inequalities)
    for (const LinearTerm& t : r.terms) constrained[m.dofIndex(t.dof)] = 1;
  for (Model::Joint& j : m.joints) {
    const JointType t = j.desc.type;
    if (t != JointType::Free && t != JointType::Ball && t != JointType::Swing) continue;
    const int first = j.first_dof + (t == JointType::Free ? 3 : 0);
    bool free = true;
    for (int k = first; k < j.first_dof + j.dof_count; ++k) free = free && !constrained[k];
    j.reparameterize = free;
  }

}

// Which joints a task recruits (ToRoot, Depth, Explicit), from its ancestor chain.
Status recruitJoints(const TaskDesc& d, const std::string& who, bool com, const std::vector<JointId>& chain,
                     const Model& m, Model::Task& t) {
  t.recruited.assign(m.joints.size(), 0);
  switch (d.recruit) {
    case Recruit::ToRoot: t.recruited = t.ancestors; break;
    case Recruit::Depth:
      if (d.depth <= 0) return modelError(who + ": recruit depth must be > 0");
      if (com) return modelError(who + ": a centre-of-mass task recruits to the root or an explicit list");
      for (size_t k = 0; k < chain.size() && static_cast<int>(k) < d.depth; ++k) t.recruited[chain[k]] = 1;
      break;
    case Recruit::Explicit:
      for (JointId j : d.joints) {
        if (j < 0 || j >= static_cast<JointId>(m.joints.size())) return modelError(who + ": recruited joint " + std::to_string(j) + " does not exist");
        if (!t.ancestors[j])
          return modelError(who + ": recruits joint '" + m.joints[j].desc.name + "', which is not an ancestor of '" +
                      m.joints[d.joint].desc.name + "'");
        t.recruited[j] = 1;
      }
      break;
  }
  return Status::success();
}

// One task: validated, its rows counted, its ancestors and recruited joints set.
Status buildTask(const std::vector<TaskDesc>& tasks, size_t i, Model& m) {
  const TaskDesc& d = tasks[i];
  const std::string who = "task " + std::to_string(i) + " '" + d.name + "'";
  if (d.name.empty()) return modelError(who + ": empty name");
  for (size_t k = 0; k < i; ++k)
    if (tasks[k].name == d.name) return modelError(who + ": duplicate name");
  Model::Task t;
  t.desc = d;
  const bool com = d.type == TaskType::CenterOfMass;
  if (!com && (d.joint < 0 || d.joint >= static_cast<JointId>(m.joints.size())))
    return modelError(who + ": joint " + std::to_string(d.joint) + " does not exist");
  if (!d.offset.allFinite()) return modelError(who + ": offset is not finite");
  if (!(std::isfinite(d.weight) && d.weight > 0)) return modelError(who + ": weight must be finite and > 0");
  if (!(d.max_position_error > 0 && d.max_rotation_error > 0))
    return modelError(who + ": error clamps must be > 0");
  if (!(d.position_tolerance >= 0 && d.rotation_tolerance >= 0))
    return modelError(who + ": tolerances must be >= 0");
  switch (d.type) {
    case TaskType::Position:
      if ((d.axes & kAxesXYZ) == 0 || (d.axes & ~kAxesXYZ) != 0) return modelError(who + ": axes must be a non-empty subset of xyz");
      t.rows = ((d.axes & kAxisX) ? 1 : 0) + ((d.axes & kAxisY) ? 1 : 0) + ((d.axes & kAxisZ) ? 1 : 0);
      break;
    case TaskType::Orientation: t.rows = 3; break;
    case TaskType::Pose: t.rows = 6; break;
    case TaskType::CenterOfMass:
      t.rows = 2;
      if (!(m.total_mass > 0)) return modelError(who + ": a centre-of-mass task needs segment masses");
      break;
  }
  const size_t nj = m.joints.size();
  t.ancestors.assign(nj, com ? 1 : 0);
  std::vector<JointId> chain;  // task joint first, root last
  if (!com) {
    for (JointId j = d.joint; j != kNoParent; j = m.joints[j].desc.parent) {
      t.ancestors[j] = 1;
      chain.push_back(j);
    }
  }
  if (Status s = recruitJoints(d, who, com, chain, m, t); !s) return s;
  if (d.reference != kNoParent) {
    if (d.type != TaskType::Orientation) return modelError(who + ": only an orientation task takes a reference joint");
    if (d.reference < 0 || d.reference >= static_cast<JointId>(nj) || d.reference == d.joint || !t.ancestors[d.reference])
      return modelError(who + ": reference joint " + std::to_string(d.reference) + " is not an ancestor of its joint");
  }
  m.tasks.push_back(std::move(t));
  return Status::success();
}

// Tasks grouped into strict priority levels (smaller level = more important), rows stacked.
void buildLevels(Model& m) {
  std::vector<int> priorities;
  for (const Model::Task& t : m.tasks) priorities.push_back(t.desc.level);
  std::sort(priorities.begin(), priorities.end());
  priorities.erase(std::unique(priorities.begin(), priorities.end()), priorities.end());
  for (int p : priorities) {
    Model::Level level;
    level.priority = p;
    level.first_row = m.task_rows;
    for (size_t i = 0; i < m.tasks.size(); ++i) {
      Model::Task& t = m.tasks[i];
      if (t.desc.level != p) continue;
      t.level_index = static_cast<int>(m.levels.size());
      t.first_row = m.task_rows;
      m.task_rows += t.rows;
      level.tasks.push_back(static_cast<TaskId>(i));
    }
    level.rows = m.task_rows - level.first_row;
    m.levels.push_back(std::move(level));
  }

}

}  // namespace

Result<Model> ModelBuilder::build() const {
  Model m;
  if (joints_.empty()) return modelError("no joints");
  if (!up_.allFinite() || up_.norm() < 1e-9) return modelError("the up axis must be a finite non-zero vector");
  m.up = up_.normalized();
  m.ground_axes.col(0) = orthogonalUnit(m.up, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ());
  m.ground_axes.col(1) = m.up.cross(m.ground_axes.col(0)).normalized();
  std::set<std::string> names;
  for (size_t i = 0; i < joints_.size(); ++i)
    if (Status s = buildJoint(joints_[i], i, names, m); !s) return Error{s.error()};
  if (m.dofs == 0) return modelError("the model has no dofs");
  m.neutral.setZero(m.dofs);
  for (const Model::Joint& j : m.joints)
    for (int k = 0; k < j.dof_count; ++k) m.neutral(j.first_dof + k) = j.desc.neutral[k];
  if (Status s = addEqualities(equalities_, m); !s) return Error{s.error()};
  if (Status s = addInequalities(inequalities_, m); !s) return Error{s.error()};
  markReparameterizable(m);
  for (size_t i = 0; i < tasks_.size(); ++i)
    if (Status s = buildTask(tasks_, i, m); !s) return Error{s.error()};
  buildLevels(m);
  if (Status s = checkRecruiting(m); !s) return Error{s.error()};
  return m;
}

Status checkRecruiting(const Model& model) {
  const size_t nj = model.joints.size();
  // Coup: joints connected through equality rows (transitively), as union-find components.
  std::vector<size_t> parent(nj);
  std::iota(parent.begin(), parent.end(), size_t{0});
  auto find = [&](size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::vector<char> coupled(nj, 0);
  for (const EqualityRow& row : model.equalities) {
    for (const LinearTerm& t : row.terms) {
      if (t.dof.joint != row.terms.front().dof.joint) {
        coupled[t.dof.joint] = coupled[row.terms.front().dof.joint] = 1;
        parent[find(t.dof.joint)] = find(row.terms.front().dof.joint);
      }
    }
  }
  auto withCoupled = [&](const std::vector<char>& rec) {
    std::vector<char> roots(nj, 0), out = rec;
    for (size_t j = 0; j < nj; ++j)
      if (rec[j] && coupled[j]) roots[find(j)] = 1;
    for (size_t j = 0; j < nj; ++j)
      if (coupled[j] && roots[find(j)]) out[j] = 1;
    return out;
  };
  const auto& tasks = model.tasks;
  for (size_t a = 0; a < tasks.size(); ++a) {
    for (size_t b = 0; b < tasks.size(); ++b) {
      if (tasks[a].level_index >= tasks[b].level_index) continue;  // a strictly higher than b
      const std::vector<char> implicit = withCoupled(tasks[b].recruited);
      for (size_t j = 0; j < nj; ++j) {
        if (!tasks[a].ancestors[j] || tasks[a].recruited[j]) continue;
        if (tasks[b].recruited[j])
          return Error{"ik recruiting rule (eq. 3): task " + levelName(model, static_cast<TaskId>(b)) +
                       " recruits joint '" + model.joints[j].desc.name +
                       "', an ancestor of higher-priority task " + levelName(model, static_cast<TaskId>(a)) +
                       " that it does not recruit"};
        if (implicit[j])
          return Error{"ik recruiting rule (eq. 4): task " + levelName(model, static_cast<TaskId>(b)) +
                       " implicitly recruits joint '" + model.joints[j].desc.name +
                       "' through a coupling; it is an ancestor of higher-priority task " +
                       levelName(model, static_cast<TaskId>(a)) + " that does not recruit it"};
      }
    }
  }
  // A target relative to a reference joint: nothing the task moves may move the reference.
  for (const Model::Task& t : tasks) {
    if (t.desc.reference == kNoParent) continue;
    const std::vector<char> moved = withCoupled(t.recruited);
    for (JointId j = t.desc.reference; j != kNoParent; j = model.joints[j].desc.parent)
      if (moved[j])
        return Error{"ik task '" + t.desc.name + "': its target is relative to joint '" +
                     model.joints[t.desc.reference].desc.name + "', which its recruited joint '" +
                     model.joints[j].desc.name + "' moves"};
  }
  std::vector<char> any(nj, 0), anyImplicit(nj, 0);
  for (const Model::Task& t : tasks) {
    const std::vector<char> implicit = withCoupled(t.recruited);
    for (size_t j = 0; j < nj; ++j) {
      any[j] = any[j] || t.recruited[j];
      anyImplicit[j] = anyImplicit[j] || implicit[j];
    }
  }
  for (size_t j = 0; j < nj; ++j) {
    if (anyImplicit[j] && !any[j]) {
      std::string by;
      for (const Model::Task& t : tasks)
        if (withCoupled(t.recruited)[j]) by += (by.empty() ? "'" : ", '") + t.desc.name + "'";
      return Error{"ik recruiting rule (eq. 5): joint '" + model.joints[j].desc.name +
                   "' is coupled to joints recruited by task(s) " + by + " but no task recruits it"};
    }
  }
  return Status::success();
}

}  // namespace embody::ik
