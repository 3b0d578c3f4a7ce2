#include "ik/spine/spine_model.h"

#include <cmath>

namespace embody::ik::spine {
namespace {

constexpr int kFlexion = static_cast<int>(Component::Flexion);
constexpr int kBending = static_cast<int>(Component::Bending);
constexpr int kTorsion = static_cast<int>(Component::Torsion);

// The joint dof that carries a component of a coupled site, or {-1, 0}.
ik::DofRef carrier(const SpineJoints::SiteJoints& s, int component) {
  if (component == kTorsion) return {s.revolute, 0};
  return {s.swing, component};  // swing: [0] flexion, [1] bending
}

// Sites of a region that carry a component, caudal first.
std::vector<int> carriers(const SpineDescription& d, const SpineJoints& j, Region region, int component) {
  std::vector<int> out;
  for (size_t s = 0; s < d.sites.size(); ++s)
    if (d.sites[s].region == region && carrier(j.sites[s], component).joint >= 0) out.push_back(static_cast<int>(s));
  return out;
}

std::string rowName(const SpineDescription& d, int component, int from, int to) {
  return std::string(toString(Component(component))) + " " + d.sites[to].name + " = r * " + d.sites[from].name;
}

// Limits of the uncoupled ball joints, as JointDesc limits (one row per bound).
void limitBall(ik::ModelBuilder& b, const SpineDescription& d, ik::JointId j, const Eigen::Vector3d& r, SpineJoints& out) {
  auto limit = [&](int dof, Component c, double range) {
    b.setLimits({j, dof}, lowerLimit(d, c, range), upperLimit(d, c, range));
    out.limit_inequalities += 2;
  };
  limit(0, Component::Flexion, r[kFlexion]);  // exp-map x: flexion
  limit(1, Component::Torsion, r[kTorsion]);  // exp-map y: torsion (the spine axis)
  limit(2, Component::Bending, r[kBending]);  // exp-map z: minus bending (symmetric)
}

// The uncoupled variant: one ball joint per site with its own limits, no rows.
void appendBallJoints(ik::ModelBuilder& b, const SpineDescription& d, ik::JointId parent,
                      std::span<const Eigen::Isometry3d> rests, SpineJoints& out) {
  ik::JointId prev = parent;
  for (size_t s = 0; s < d.sites.size(); ++s) {
    const ik::JointId j = b.addJoint(d.sites[s].name, prev, ik::JointType::Ball, rests[s], Eigen::Vector3d::UnitY());
    limitBall(b, d, j, out.ranges[s], out);
    out.sites[s].ball = prev = j;
  }
  out.top = prev;
}

// Coupled joints: per site a swing and/or a revolute (the revolute on the swing at the same
// place). Limits on the first carrier of each region (or every joint) go in as explicit rows
// ahead of the bands rather than as JointDesc limits: the solver pins violated rows user
// couplings first, then limits, first added wins. A band pinned at its slack before the
// neighbouring region's limit makes that limit row linearly dependent (band + the other region's
// limit fix it), so the joint would end up past its limit by s. Checked first, the anatomical
// limit wins and the band yields.
void appendCoupledJoints(ik::ModelBuilder& b, const SpineDescription& d, ik::JointId parent,
                         std::span<const Eigen::Isometry3d> rests, const SpineOptions& options, SpineJoints& out) {
  std::vector<ik::InequalityRow> limitRows;
  auto limitRow = [&](ik::DofRef dof, Component c, double range) {
    limitRows.push_back({"", {{dof, 1.0}}, upperLimit(d, c, range), ik::InequalityKind::UserCoupling});
    limitRows.push_back({"", {{dof, -1.0}}, -lowerLimit(d, c, range), ik::InequalityKind::UserCoupling});
    out.limit_inequalities += 2;
  };
  const Eigen::Vector3d axis = Eigen::Vector3d::UnitY();
  ik::JointId prev = parent;
  bool swingLimited[kRegionCount] = {}, torsionLimited[kRegionCount] = {};
  for (size_t s = 0; s < d.sites.size(); ++s) {
    const Site& site = d.sites[s];
    const Eigen::Vector3d& r = out.ranges[s];
    const int region = static_cast<int>(site.region);
    Eigen::Isometry3d rest = rests[s];
    if (site.swing) {
      const ik::JointId j = b.addJoint(site.name, prev, ik::JointType::Swing, rest, axis);
      if (options.check_all_limits || !swingLimited[region]) {
        limitRow({j, 0}, Component::Flexion, r[kFlexion]);
        limitRow({j, 1}, Component::Bending, r[kBending]);
        swingLimited[region] = true;
      }
      out.sites[s].swing = prev = j;
      rest = Eigen::Isometry3d::Identity();  // a revolute at the same site sits on the swing joint
    }
    if (site.revolute) {
      const ik::JointId j =
          b.addJoint(site.swing ? site.name + "_torsion" : site.name, prev, ik::JointType::Revolute, rest, axis);
      if (options.check_all_limits || !torsionLimited[region]) {
        limitRow({j, 0}, Component::Torsion, r[kTorsion]);
        torsionLimited[region] = true;
      }
      out.sites[s].revolute = prev = j;
    }
  }
  out.top = prev;
  for (ik::InequalityRow& row : limitRows) {
    const ik::DofRef dof = row.terms[0].dof;
    const bool upper = row.terms[0].coefficient > 0;
    row.name = b.joints()[dof.joint].name + "[" + std::to_string(dof.component) + "] " + (upper ? "<= upper" : ">= lower");
    b.addInequality(std::move(row));
  }
}

// Inside each region: chain consecutive carriers of a component, exactly two entries per row.
void appendRegionChains(ik::ModelBuilder& b, const SpineDescription& d, SpineJoints& out) {
  for (int region = 0; region < kRegionCount; ++region)
    for (int c = 0; c < kComponentCount; ++c) {
      const std::vector<int> chain = carriers(d, out, Region(region), c);
      for (size_t k = 1; k < chain.size(); ++k) {
        const int i = chain[k - 1], j = chain[k];
        b.addEquality(rowName(d, c, i, j), carrier(out.sites[j], c), 1.0, carrier(out.sites[i], c),
                      -out.ranges[j][c] / out.ranges[i][c]);
        ++out.equalities;
      }
    }
}

// Between neighbouring regions: a band on the same component (relaxed coupling).
void appendRegionBands(ik::ModelBuilder& b, const SpineDescription& d, SpineJoints& out) {
  for (int region = 0; region + 1 < kRegionCount; ++region)
    for (int c = 0; c < kComponentCount; ++c) {
      const int i = carriers(d, out, Region(region), c).back();
      const int j = carriers(d, out, Region(region + 1), c).front();
      const double ratio = out.ranges[j][c] / out.ranges[i][c];
      const ik::DofRef qi = carrier(out.sites[i], c), qj = carrier(out.sites[j], c);
      const std::string name = "band " + rowName(d, c, i, j);
      SpineJoints::Band band{Region(region), Component(c), name + " (upper)", name + " (lower)"};
      b.addInequality({band.upper, {{qj, 1.0}, {qi, -ratio}}, d.band_slack, ik::InequalityKind::UserCoupling});
      b.addInequality({band.lower, {{qj, -1.0}, {qi, ratio}}, d.band_slack, ik::InequalityKind::UserCoupling});
      out.bands.push_back(std::move(band));
      out.band_inequalities += 2;
    }
}

// Cross-axis: the region's torsion follows its bending. The first revolute and the first swing
// stand for their region through the chains: region total = own value * (region range / own
// range), so q_t = sign * k * (r_t / T) * (B / r_b) * q_b.
void appendAxisCouplings(ik::ModelBuilder& b, const SpineDescription& d, SpineJoints& out) {
  for (const AxisCoupling& a : d.axis_couplings) {
    const std::vector<int> twist = carriers(d, out, a.region, kTorsion);
    const std::vector<int> bend = carriers(d, out, a.region, kBending);
    double totalTwist = 0, totalBend = 0;
    for (int s : twist) totalTwist += out.ranges[s][kTorsion];
    for (int s : bend) totalBend += out.ranges[s][kBending];
    const int t = twist.front(), s = bend.front();
    const double k = (a.same_side ? 1.0 : -1.0) * a.torsion_per_bending * (out.ranges[t][kTorsion] / totalTwist) *
                     (totalBend / out.ranges[s][kBending]);
    b.addEquality(std::string(toString(a.region)) + " torsion follows bending", carrier(out.sites[t], kTorsion), 1.0,
                  carrier(out.sites[s], kBending), -k);
    ++out.equalities;
    ++out.axis_equalities;
  }
}

}  // namespace

Result<SpineJoints> appendSpine(ik::ModelBuilder& b, const SpineDescription& d, ik::JointId parent,
                                std::span<const Eigen::Isometry3d> rests, const SpineOptions& options) {
  if (rests.size() != d.sites.size())
    return Error{"appendSpine: " + std::to_string(rests.size()) + " rest frames for " + std::to_string(d.sites.size()) +
                 " sites"};
  for (const Eigen::Isometry3d& r : rests)
    if (!r.matrix().allFinite()) return Error{"appendSpine: a rest frame is not finite"};
  SpineJoints out;
  out.coupled = options.coupled;
  out.ranges = siteRanges(d, options.coupled);
  out.sites.resize(d.sites.size());
  if (!options.coupled) {
    appendBallJoints(b, d, parent, rests, out);
    return out;
  }
  appendCoupledJoints(b, d, parent, rests, options, out);
  appendRegionChains(b, d, out);
  appendRegionBands(b, d, out);
  if (options.axis_coupling) appendAxisCouplings(b, d, out);
  return out;
}

Result<std::vector<Eigen::Isometry3d>> restFramesFromPoints(const Eigen::Isometry3d& parentWorld,
                                                            std::span<const Eigen::Vector3d> points,
                                                            const Eigen::Vector3d& topPoint,
                                                            const Eigen::Vector3d& forward) {
  if (!parentWorld.matrix().allFinite() || !topPoint.allFinite() || !forward.allFinite())
    return Error{"restFramesFromPoints: input is not finite"};
  std::vector<Eigen::Isometry3d> rests;
  rests.reserve(points.size());
  Eigen::Isometry3d previous = parentWorld;
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d next = i + 1 < points.size() ? points[i + 1] : topPoint;
    if (!points[i].allFinite()) return Error{"restFramesFromPoints: point " + std::to_string(i) + " is not finite"};
    const Eigen::Vector3d y = next - points[i];
    const Eigen::Vector3d x = y.cross(forward);
    if (y.norm() < 1e-9 || x.norm() < 1e-9 * y.norm() * forward.norm())
      return Error{"restFramesFromPoints: point " + std::to_string(i) +
                   " coincides with the next or the segment runs along `forward`"};
    Eigen::Matrix3d r;
    r.col(1) = y.normalized();
    r.col(0) = x.normalized();
    r.col(2) = r.col(0).cross(r.col(1));
    Eigen::Isometry3d world = Eigen::Isometry3d::Identity();
    world.linear() = r;
    world.translation() = points[i];
    rests.push_back(previous.inverse() * world);
    previous = world;
  }
  return rests;
}

std::vector<Eigen::Vector3d> neutralSitePoints(const SpineDescription& d, double height) {
  const std::vector<Eigen::Vector3d> centres = neutralCentres(d, height);
  std::vector<Eigen::Vector3d> points;
  for (const Site& s : d.sites) points.push_back(centres[s.first]);
  points.push_back(centres.back());
  return points;
}

Result<IsolatedSpine> buildIsolatedSpine(const SpineDescription& d, const SpineOptions& options, double height) {
  if (!(height > 0.3 && height < 3.0)) return Error{"buildIsolatedSpine: height must be in (0.3, 3) m"};
  ik::ModelBuilder b;
  IsolatedSpine out;
  out.pelvis = b.addJoint("pelvis", ik::kNoParent, ik::JointType::Fixed);
  const std::vector<Eigen::Vector3d> points = neutralSitePoints(d, height);
  const std::span<const Eigen::Vector3d> sitePoints(points.data(), points.size() - 1);
  auto rests = restFramesFromPoints(Eigen::Isometry3d::Identity(), sitePoints, points.back());
  if (!rests) return Error{rests.error()};
  auto joints = appendSpine(b, d, out.pelvis, *rests, options);
  if (!joints) return Error{joints.error()};
  out.joints = std::move(*joints);
  Eigen::Isometry3d topWorld = Eigen::Isometry3d::Identity();
  for (const Eigen::Isometry3d& r : *rests) topWorld = topWorld * r;
  out.skullbase = b.addJoint("skullbase", out.joints.top, ik::JointType::Fixed,
                             topWorld.inverse() * Eigen::Translation3d(points.back()));
  // Nominal segment masses so the model also has a centre of mass (not used by the tasks here).
  for (const SpineJoints::SiteJoints& s : out.joints.sites) b.setSegment(s.last(), 1.0, Eigen::Vector3d::Zero());
  b.setSegment(out.skullbase, 5.0, Eigen::Vector3d(0, 0.08, 0));

  ik::TaskDesc t;
  // Small per-iteration error clamps: with 9 free dofs and the head orientation held, the neck's
  // sideways direction is close to singular, and a large clamped error gives steps far outside
  // the linearisation (the spine curls up). A few more iterations are cheaper than that.
  t.max_position_error = 0.02;
  t.max_rotation_error = 0.1;
  t.name = "head_orientation";
  t.type = ik::TaskType::Orientation;
  t.joint = out.skullbase;
  t.level = 0;
  out.head_orientation = b.addTask(t);
  t.name = "neck_position";
  t.type = ik::TaskType::Position;
  t.level = 1;
  out.neck_position = b.addTask(t);
  auto model = b.build();
  if (!model) return Error{"spine model '" + d.name + "': " + model.error()};
  out.model = std::move(*model);
  return out;
}

SpineSummary summarize(const SpineDescription& d, const IsolatedSpine& spine) {
  SpineSummary s;
  s.vertebrae = static_cast<int>(d.vertebrae.size());
  s.sites = static_cast<int>(d.sites.size());
  for (const auto& j : spine.model.joints) {
    s.swing_joints += j.desc.type == ik::JointType::Swing ? 1 : 0;
    s.revolute_joints += j.desc.type == ik::JointType::Revolute ? 1 : 0;
    s.ball_joints += j.desc.type == ik::JointType::Ball ? 1 : 0;
  }
  s.dof_total = spine.model.dofs;
  s.equalities = static_cast<int>(spine.model.equalities.size());
  s.dof_free = s.dof_total - (s.equalities - static_cast<int>(spine.model.dependent_equalities.size()));
  s.axis_equalities = spine.joints.axis_equalities;
  s.band_inequalities = spine.joints.band_inequalities;
  s.limit_inequalities = spine.joints.limit_inequalities;
  s.inequalities = static_cast<int>(spine.model.inequalities.size());
  return s;
}

}  // namespace embody::ik::spine
