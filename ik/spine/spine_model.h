#pragma once
// Turning a SpineDescription into IK joints and constraint rows (Raunhardt & Boulic 2008):
//
//   auto desc = spine::defaultFullSpine();                       // or withSites(...) for bones
//   auto rests = spine::restFramesFromPoints(pelvisWorld, sitePoints, headPoint, forward);
//   auto spine = spine::appendSpine(builder, desc, pelvisJoint, rests, {});
//   builder.addJoint("head", spine->top, ...);                    // the head hangs on `top`
//
// Coupled (the default): each site gets a Swing joint (2 dofs: flexion, bending; twist axis +Y)
// and/or a Revolute joint (torsion about +Y). Inside each region, equality rows with exactly two
// entries chain the same component of consecutive carriers, q_j - (r_j / r_i) q_i = 0 with r the
// ranges (so they reach their limits together): each region keeps 3 free dofs. Between
// neighbouring regions, the last carrier below and the first above are held in a band
// |q_j - (r_j / r_i) q_i| <= s. Joint limits are set on the first swing and the first revolute of
// each region only (the coupling keeps the others inside theirs), or on every joint.
// Uncoupled: one Ball joint per site (exp-map [flexion, torsion, -bending]) with its own limits.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <span>
#include <string>
#include <vector>

#include "ik/model.h"
#include "ik/spine/spine_description.h"
#include "core/result.h"

namespace embody::ik::spine {

struct SpineOptions {
  bool coupled = true;            // false: the uncoupled ball-joint variant (no rows at all)
  bool axis_coupling = false;     // add the description's cross-axis rows (coupled only)
  bool check_all_limits = false;  // limits on every joint, not only the first of each region
};

// What appendSpine added to the builder, per site, and the row counts.
struct SpineJoints {
  struct SiteJoints {
    ik::JointId swing = -1;     // coupled: the swing joint, or -1
    ik::JointId revolute = -1;  // coupled: the revolute joint, or -1
    ik::JointId ball = -1;      // uncoupled: the ball joint
    ik::JointId last() const { return ball >= 0 ? ball : revolute >= 0 ? revolute : swing; }
  };
  std::vector<SiteJoints> sites;  // description.sites order
  ik::JointId top = -1;           // the last joint added: the head (or skullbase) hangs on it
  std::vector<Eigen::Vector3d> ranges;  // per site, radians (siteRanges with distribute = coupled)
  bool coupled = true;
  int equalities = 0;          // chain rows + axis-coupling rows
  int axis_equalities = 0;     // of which cross-axis rows
  int band_inequalities = 0;   // inter-region band rows (two per band)
  // The bands' rows by name (ik::Model::findInequality), so a caller can move a band's slack per
  // frame (ik::Data::setInequalityBound): both rows have rhs = the description's band_slack.
  struct Band {
    Region below = Region::Lumbar;  // the band joins this region to the next one up
    Component component = Component::Flexion;
    std::string upper, lower;       // q_j - r q_i <= s and -(q_j - r q_i) <= s
  };
  std::vector<Band> bands;
  int limit_inequalities = 0;  // joint-limit rows the builder will generate (one per finite bound)
};

// Appends the spine's joints and rows to `builder` under `parent` (kNoParent for a root).
// `rests` has one transform per site: the site's joint frame in the frame of the previous site
// (of `parent` for the first), +Y along the spine towards the next site, +Z forward, +X to the
// character's left; q = 0 is then that pose. Joint names: the site name; a site with both
// joints names its revolute "<site>_torsion". Masses are left to the caller (setSegment).
Result<SpineJoints> appendSpine(ik::ModelBuilder& builder, const SpineDescription& description,
                                ik::JointId parent, std::span<const Eigen::Isometry3d> rests,
                                const SpineOptions& options = {});

// Rest transforms for appendSpine from world-space points: one per site (its joint centre), plus
// the point the last site aims at (the head joint). Each frame's +Y points at the next point, +X is
// +Y × forward (the character's left when forward is its facing direction). `parentWorld` is the
// parent joint's world frame at rest. Points must be distinct and not along `forward`.
Result<std::vector<Eigen::Isometry3d>> restFramesFromPoints(const Eigen::Isometry3d& parentWorld,
                                                            std::span<const Eigen::Vector3d> sitePoints,
                                                            const Eigen::Vector3d& topPoint,
                                                            const Eigen::Vector3d& forward = Eigen::Vector3d::UnitZ());

// The joint centre of each site (its first vertebra's centre) at the natural standing curvature,
// pelvis frame, scaled to `height`; plus the head joint last.
std::vector<Eigen::Vector3d> neutralSitePoints(const SpineDescription& description, double height);

// The spine alone on a fixed pelvis (the paper's §5.1 set-up): "pelvis" (Fixed, at the origin),
// the spine, and "skullbase" (Fixed, world-aligned at rest) at the top. Tasks:
//   level 0 "head_orientation": keep the skullbase orientation (the gaze is stabilised first);
//   level 1 "neck_position":    move the top of the neck (skullbase centre).
struct IsolatedSpine {
  ik::Model model;
  SpineJoints joints;
  ik::JointId pelvis = -1;
  ik::JointId skullbase = -1;
  ik::TaskId head_orientation = -1;
  ik::TaskId neck_position = -1;
};
Result<IsolatedSpine> buildIsolatedSpine(const SpineDescription& description, const SpineOptions& options = {},
                                         double height = 1.75);

// What `embody spine describe` reports.
struct SpineSummary {
  int vertebrae = 0;
  int sites = 0;
  int swing_joints = 0;
  int revolute_joints = 0;
  int ball_joints = 0;
  int dof_total = 0;
  int dof_free = 0;  // dof_total minus the rank of the equality rows
  int equalities = 0;
  int axis_equalities = 0;
  int inequalities = 0;  // bands + joint limits
  int band_inequalities = 0;
  int limit_inequalities = 0;
};
SpineSummary summarize(const SpineDescription& description, const IsolatedSpine& spine);

}  // namespace embody::ik::spine
