#pragma once
// The data side of the coupled spine (Raunhardt & Boulic 2008): which vertebrae exist, their
// ranges of motion and standing curvature, and how they are grouped into joint sites. A
// `SpineDescription` is plain data, read from JSON (schema in docs/spine.md) and validated; the
// embedded defaults are the 24-vertebra "full" model and the 8-site "simplified" one.
// Building IK joints from it is spine_model.h.
//
// Conventions (the same as ik): y up, z forward, x to the character's left; angles in the
// JSON are degrees, everything in C++ is radians and metres. Per joint, component 0 is flexion
// (+ forward), component 1 lateral bending (+ to the left), component 2 torsion about the spine
// axis (+ turning the front to the left).
#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/result.h"

namespace embody::ik::spine {

enum class Region : std::uint8_t { Lumbar, Thoracic, Cervical };
inline constexpr int kRegionCount = 3;
const char* toString(Region region);  // "lumbar", "thoracic", "cervical"

enum class Component : std::uint8_t { Flexion, Bending, Torsion };
inline constexpr int kComponentCount = 3;
const char* toString(Component component);  // "flexion", "bending", "torsion"

// One intervertebral level, named after the H-Anim joint below the movable vertebra.
struct Vertebra {
  std::string name;   // H-Anim joint, e.g. "vl5"
  std::string level;  // anatomical level, e.g. "L5-S1"
  Region region = Region::Lumbar;
  // Range of motion in radians: [0] flexion + extension combined, [1] lateral bending to one
  // side, [2] axial rotation to one side (White & Panjabi's table, ../shared/reference/spine.md).
  Eigen::Vector3d range = Eigen::Vector3d::Zero();
  // Standing sagittal angle of the segment above this joint relative to the segment below, in
  // radians, + = extension (lordotic). For the first vertebra, relative to the vertical.
  double neutral_extension = 0.0;
  double length = 0.0;  // metres to the next joint centre (the last: to the head joint), reference height
};

// A joint site: consecutive vertebrae of one region moved by one swing joint, one revolute
// (torsion) joint, or both (swing, then the revolute as its child at the same place).
struct Site {
  std::string name;
  int first = 0;  // index of its first (most caudal) vertebra
  int count = 1;  // number of vertebrae it stands for
  bool swing = false;
  bool revolute = false;
  Region region = Region::Lumbar;
};

// Optional cross-axis coupling: the region's torsion tied to its lateral bending (spine.md §3).
struct AxisCoupling {
  Region region = Region::Cervical;
  double torsion_per_bending = 0.0;  // region torsion / region bending, > 0
  bool same_side = true;             // cervical: same side; lumbar: opposite side
};

struct SpineDescription {
  std::string name;
  double reference_height = 1.7504;  // body height the lengths and origin are given for (m)
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // first joint centre in the pelvis frame (m)
  double flexion_share = 0.6;    // share of the FE range that is flexion (the rest is extension)
  double band_slack = 0.0;       // s of the inter-region bands |q_j - r q_i| <= s (radians)
  std::vector<Vertebra> vertebrae;  // caudal to cranial; regions in order lumbar, thoracic, cervical
  std::vector<Site> sites;          // caudal to cranial, covering every vertebra exactly once
  std::vector<AxisCoupling> axis_couplings;

  int swingCount() const;
  int revoluteCount() const;
  int findVertebra(std::string_view name) const;  // -1 when absent
};

// Parses and validates (every field, finite and positive numbers, contiguous region-pure sites
// covering every vertebra once, at least one swing and one revolute site per region). Errors
// name the offending entry, e.g. "vertebrae[3] (vl2): range_deg must have 3 entries".
Result<SpineDescription> parseSpineDescription(const nlohmann::json& json);
Result<SpineDescription> parseSpineDescriptionText(std::string_view text);
Result<SpineDescription> loadSpineDescription(const std::string& path);
nlohmann::json toJson(const SpineDescription& description);

// The embedded defaults: "full" (24 sites: revolute at vl2; vt8, vt4; vc6, vc3, vc1, swing
// elsewhere) and "simplified" (8 sites: 3 lumbar, 3 thoracic, 2 cervical; 8 swing + 5 revolute).
const SpineDescription& defaultFullSpine();
const SpineDescription& defaultSimplifiedSpine();
// "paper": the full model with the revolute count of the paper's §5.1 (17 swing + 7 revolute,
// 32 equality rows: a fourth cervical revolute at vc4); the default has 18 + 6 and 33 rows.
const SpineDescription& paperSpine();
// "full", "simplified", "paper", or a path to a JSON file.
Result<SpineDescription> loadSpineModel(const std::string& nameOrPath);

// One entry of a custom grouping: vertebrae `first` … `last` (H-Anim names, caudal first).
struct SiteSpec {
  std::string name;
  std::string first;
  std::string last;
  bool swing = true;
  bool revolute = false;
};
// The same vertebrae grouped into other sites (e.g. one site per avatar spine bone); validated
// like a parsed file.
Result<SpineDescription> withSites(const SpineDescription& base, const std::vector<SiteSpec>& sites);

// The range each site's joints carry, per component (radians: FE combined, LB, AR).
// distribute = true (coupled joints): each vertebra's range of a component goes to the nearest
// site of its region that carries the component (ties to the caudal one), so a region's total
// range is kept however the joints are placed; components a site does not carry are 0.
// distribute = false (ball joints): each site carries the sum of its own vertebrae's ranges.
std::vector<Eigen::Vector3d> siteRanges(const SpineDescription& description, bool distribute);
// The site whose joint carries a vertebra's component under the same rule (distribute = false:
// the site the vertebra belongs to); -1 when none does (a description validate() refuses).
int carrierSite(const SpineDescription& description, int vertebra, Component component, bool distribute);

// Lower / upper joint limit of a component for a range (flexion split by flexion_share).
double lowerLimit(const SpineDescription& description, Component component, double range);
double upperLimit(const SpineDescription& description, Component component, double range);

// Joint centres at the natural standing curvature, scaled to `height` (metres), in the pelvis
// frame: one per vertebra plus the head joint (skullbase) last.
std::vector<Eigen::Vector3d> neutralCentres(const SpineDescription& description, double height);

}  // namespace embody::ik::spine
