#include "ik/spine/spine_analysis.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "ik/expmap.h"

namespace embody::ik::spine {

std::vector<SiteMotion> siteMotion(const ik::Model& model, const Eigen::VectorXd& q, const SpineJoints& joints) {
  std::vector<SiteMotion> out(joints.sites.size());
  for (size_t s = 0; s < joints.sites.size(); ++s) {
    const SpineJoints::SiteJoints& j = joints.sites[s];
    SiteMotion& m = out[s];
    if (j.ball >= 0) {
      const Eigen::Vector3d v = q.segment<3>(model.joints[j.ball].first_dof);
      const Eigen::Quaterniond r(ik::expMapRotation(v));
      // Twist about +Y: the quaternion's y part; the swing is what remains, R = S T.
      const double twist = 2.0 * std::atan2(r.y(), r.w());
      const Eigen::Matrix3d swing = r.toRotationMatrix() * Eigen::AngleAxisd(-twist, Eigen::Vector3d::UnitY()).toRotationMatrix();
      const Eigen::Vector3d sv = ik::rotationLog(swing);
      m.s_x = sv.x();
      m.s_y = -sv.z();
      m.torsion = std::remainder(twist, 2.0 * std::numbers::pi);
      continue;
    }
    if (j.swing >= 0) {
      const int first = model.joints[j.swing].first_dof;
      m.s_x = q[first];
      m.s_y = q[first + 1];
    }
    if (j.revolute >= 0) m.torsion = q[model.joints[j.revolute].first_dof];
  }
  return out;
}

double swingSpread(const SpineDescription& d, const SpineJoints& joints, const std::vector<SiteMotion>& motion) {
  double worst = 0.0;
  for (int region = 0; region < kRegionCount; ++region)
    for (Component c : {Component::Flexion, Component::Bending}) {
      std::vector<double> normalized;
      for (size_t s = 0; s < d.sites.size(); ++s) {
        const bool carries = joints.sites[s].ball >= 0 || joints.sites[s].swing >= 0;
        if (d.sites[s].region != Region(region) || !carries) continue;
        const double value = c == Component::Flexion ? motion[s].s_x : motion[s].s_y;
        const double range = joints.ranges[s][static_cast<int>(c)];
        const double bound = value >= 0 ? upperLimit(d, c, range) : -lowerLimit(d, c, range);
        normalized.push_back(value / bound);
      }
      if (normalized.size() < 2) continue;
      double mean = 0.0;
      for (double x : normalized) mean += x;
      mean /= static_cast<double>(normalized.size());
      double var = 0.0;
      for (double x : normalized) var += (x - mean) * (x - mean);
      worst = std::max(worst, std::sqrt(var / static_cast<double>(normalized.size())));
    }
  return worst;
}

int torsionSignChangesWithinRegions(const SpineDescription& d, const SpineJoints& joints,
                                    const std::vector<SiteMotion>& motion, double epsilon) {
  int changes = 0;
  for (int region = 0; region < kRegionCount; ++region) {
    int previousSign = 0;
    for (size_t s = 0; s < d.sites.size(); ++s) {
      const bool carries = joints.sites[s].ball >= 0 || joints.sites[s].revolute >= 0;
      if (d.sites[s].region != Region(region) || !carries) continue;
      const double t = motion[s].torsion;
      const int sign = t > epsilon ? 1 : t < -epsilon ? -1 : 0;
      if (sign == 0) continue;
      if (previousSign != 0 && sign != previousSign) ++changes;
      previousSign = sign;
    }
  }
  return changes;
}

}  // namespace embody::ik::spine

namespace embody::ik::spine {

int torsionSignChangesBetweenRegions(const SpineDescription& d, const SpineJoints& joints,
                                     const std::vector<SiteMotion>& motion, double epsilon) {
  // Per region the torsion sign of its last and its first torsion-carrying site (0: none / below epsilon).
  int first[kRegionCount] = {}, last[kRegionCount] = {};
  for (size_t s = 0; s < d.sites.size(); ++s) {
    const bool carries = joints.sites[s].ball >= 0 || joints.sites[s].revolute >= 0;
    if (!carries) continue;
    const double t = motion[s].torsion;
    const int sign = t > epsilon ? 1 : t < -epsilon ? -1 : 0;
    const int region = static_cast<int>(d.sites[s].region);
    if (first[region] == 0) first[region] = sign;
    if (sign != 0) last[region] = sign;
  }
  int changes = 0;
  for (int region = 0; region + 1 < kRegionCount; ++region)
    if (last[region] != 0 && first[region + 1] != 0 && last[region] != first[region + 1]) ++changes;
  return changes;
}

double maxNormalisedSwing(const SpineDescription& d, const SpineJoints& joints, const std::vector<SiteMotion>& motion) {
  double worst = 0.0;
  for (size_t s = 0; s < d.sites.size(); ++s) {
    if (joints.sites[s].ball < 0 && joints.sites[s].swing < 0) continue;
    for (Component c : {Component::Flexion, Component::Bending}) {
      const double value = c == Component::Flexion ? motion[s].s_x : motion[s].s_y;
      const double range = joints.ranges[s][static_cast<int>(c)];
      if (range <= 0) continue;
      const double bound = value >= 0 ? upperLimit(d, c, range) : -lowerLimit(d, c, range);
      worst = std::max(worst, std::abs(value) / bound);
    }
  }
  return worst;
}

}  // namespace embody::ik::spine

namespace embody::ik::spine {

std::vector<double> vertebraTorsion(const SpineDescription& d, const SpineJoints& joints,
                                    const std::vector<SiteMotion>& motion) {
  constexpr int kTorsion = static_cast<int>(Component::Torsion);
  std::vector<double> out(d.vertebrae.size(), 0.0);
  for (size_t v = 0; v < d.vertebrae.size(); ++v) {
    const int s = carrierSite(d, static_cast<int>(v), Component::Torsion, joints.coupled);
    if (s < 0 || joints.ranges[static_cast<size_t>(s)][kTorsion] <= 0) continue;
    out[v] = motion[static_cast<size_t>(s)].torsion * d.vertebrae[v].range[kTorsion] /
             joints.ranges[static_cast<size_t>(s)][kTorsion];
  }
  return out;
}

}  // namespace embody::ik::spine
