#include "runtime/residuals_job.h"

namespace embody::runtime {

using tracking::TrackerId;

bool ResidualsJob::Validate() const {
  if (!rig || !data || !targets || !result) return false;
  if (data->q().size() != rig->body.model.dofs) return false;
  for (const Eigen::Vector3d& p : targets->point)
    if (!p.allFinite()) return false;
  return true;
}

bool ResidualsJob::Run() const {
  if (!Validate()) return false;
  const BodyRig& r = *rig;
  const ik::Data& d = *data;
  auto jointPosition = [&](ik::JointId j) { return d.jointFrame(j).translation(); };
  // Residuals in avatar metres: the tracked point against the body part it drives.
  for (auto id : tracking::kAllTrackers) {
    const size_t i = size_t(tracking::index(id));
    if (r.tasks.position[i] < 0 || !d.enabled(r.tasks.position[i])) continue;
    const Eigen::Vector3d actual = id == TrackerId::Head ? Eigen::Vector3d(d.jointFrame(r.body.head) * r.eyeInHead)
                                                         : Eigen::Vector3d(jointPosition(r.joint[i]));
    result->residual[i] = float((actual - targets->point[i]).norm());
    if (targets->weight[i] > 0.0)
      result->turnResidual[i] = float(targets->rotation[i].angularDistance(Eigen::Quaterniond(d.jointFrame(r.joint[i]).rotation())));
    if (id == TrackerId::LeftHand || id == TrackerId::RightHand) {
      const ik::JointId shoulder = r.shoulder(id == TrackerId::LeftHand ? tracking::Side::Left : tracking::Side::Right);
      result->reachable[i] = (targets->point[i] - jointPosition(shoulder)).norm() <= r.armReach;
    }
  }
  return true;
}

}  // namespace embody::runtime
