// Forward kinematics, exact task Jacobians (exp-map left Jacobian, CoM by subtree sums) and the
// clamped, weighted task errors.
#include <cmath>

#include "ik/expmap.h"
#include "ik/solver.h"
#include "ik/solver_detail.h"
#include "ik/solver_internal.h"

namespace embody::ik {

using detail::sameShape;

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
        int axisRow[3] = {-1, -1, -1};  // the row of each constrained axis
        for (int k = 0; k < 3; ++k) {
          if (!(axes & (1 << k))) continue;
          w.error(r) = s * clamped(k);
          axisRow[k] = r++;
        }
        // One column per dof (its point velocity), written to the constrained axes' rows.
        for (int dof : w.task_dofs[t]) {
          const int j = w.dof_joint[dof];
          const Eigen::Vector3d col = w.dof_linear.col(dof) + w.dof_angular.col(dof).cross(p - w.frames[j].translation());
          for (int k = 0; k < 3; ++k)
            if (axisRow[k] >= 0) w.jacobian(axisRow[k], dof) = s * col(k);
        }
      }
      if (hasRot) {
        const Eigen::Quaterniond current(frame.linear());
        const Eigen::Quaterniond target = d.reference == kNoParent
                                              ? w.target_orientation[t]
                                              : Eigen::Quaterniond(w.frames[d.reference].linear()) * w.target_orientation[t];
        Eigen::Quaterniond err = target * current.conjugate();
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

}  // namespace embody::ik
