// The embedded default spine description (schema: docs/spine.md). Sources for every number:
// ../shared/reference/spine.md; the choices made where it leaves one open are in docs/spine.md.
#include "ik/spine/spine_default_data.h"

namespace embody::ik::spine::detail {

// White & Panjabi's representative ranges (where the two transcriptions disagree, the values of
// White & Panjabi's own table: L5-S1 FE 17 / AR 1, L4-L5 FE 16, T2-T5 AR 8, T8-T9 AR 7).
// Lengths: distances between the H-Anim LOA-3 default joint centres (height 1.7504 m).
// Standing curvature: lumbar lordosis 43 deg (+ the 22 deg forward tilt of L5 on the vertical
// pelvis), thoracic kyphosis 45 deg, cervical lordosis 40 deg; the head ends above L5.
const char* const kFullSpineJson = R"json(
{
  "format": "embody-spine",
  "version": 1,
  "name": "full",
  "reference_height_m": 1.7504,
  "origin_m": [0.0, 0.2328, -0.1053],
  "flexion_share": 0.6,
  "band_slack_deg": 2.0,
  "vertebrae": [
    {"name": "vl5", "level": "L5-S1", "region": "lumbar", "range_deg": [17, 3, 1], "neutral_extension_deg": -22, "length_m": 0.0357},
    {"name": "vl4", "level": "L4-L5", "region": "lumbar", "range_deg": [16, 6, 2], "neutral_extension_deg": 18, "length_m": 0.0351},
    {"name": "vl3", "level": "L3-L4", "region": "lumbar", "range_deg": [15, 8, 2], "neutral_extension_deg": 12, "length_m": 0.0270},
    {"name": "vl2", "level": "L2-L3", "region": "lumbar", "range_deg": [14, 6, 2], "neutral_extension_deg": 7, "length_m": 0.0366},
    {"name": "vl1", "level": "L1-L2", "region": "lumbar", "range_deg": [12, 6, 2], "neutral_extension_deg": 6, "length_m": 0.0366},
    {"name": "vt12", "level": "T12-L1", "region": "thoracic", "range_deg": [12, 8, 2], "neutral_extension_deg": -2, "length_m": 0.0401},
    {"name": "vt11", "level": "T11-T12", "region": "thoracic", "range_deg": [12, 9, 2], "neutral_extension_deg": -4, "length_m": 0.0169},
    {"name": "vt10", "level": "T10-T11", "region": "thoracic", "range_deg": [9, 7, 2], "neutral_extension_deg": -4, "length_m": 0.0278},
    {"name": "vt9", "level": "T9-T10", "region": "thoracic", "range_deg": [6, 6, 4], "neutral_extension_deg": -4, "length_m": 0.0256},
    {"name": "vt8", "level": "T8-T9", "region": "thoracic", "range_deg": [6, 6, 7], "neutral_extension_deg": -5, "length_m": 0.0243},
    {"name": "vt7", "level": "T7-T8", "region": "thoracic", "range_deg": [6, 6, 8], "neutral_extension_deg": -5, "length_m": 0.0243},
    {"name": "vt6", "level": "T6-T7", "region": "thoracic", "range_deg": [5, 6, 8], "neutral_extension_deg": -5, "length_m": 0.0242},
    {"name": "vt5", "level": "T5-T6", "region": "thoracic", "range_deg": [4, 6, 8], "neutral_extension_deg": -4, "length_m": 0.0229},
    {"name": "vt4", "level": "T4-T5", "region": "thoracic", "range_deg": [4, 6, 8], "neutral_extension_deg": -4, "length_m": 0.0283},
    {"name": "vt3", "level": "T3-T4", "region": "thoracic", "range_deg": [4, 6, 8], "neutral_extension_deg": -4, "length_m": 0.0198},
    {"name": "vt2", "level": "T2-T3", "region": "thoracic", "range_deg": [4, 6, 8], "neutral_extension_deg": -3, "length_m": 0.0213},
    {"name": "vt1", "level": "T1-T2", "region": "thoracic", "range_deg": [4, 6, 9], "neutral_extension_deg": -1, "length_m": 0.0200},
    {"name": "vc7", "level": "C7-T1", "region": "cervical", "range_deg": [9, 4, 2], "neutral_extension_deg": 4, "length_m": 0.0275},
    {"name": "vc6", "level": "C6-C7", "region": "cervical", "range_deg": [17, 7, 6], "neutral_extension_deg": 6, "length_m": 0.0174},
    {"name": "vc5", "level": "C5-C6", "region": "cervical", "range_deg": [20, 8, 7], "neutral_extension_deg": 7, "length_m": 0.0142},
    {"name": "vc4", "level": "C4-C5", "region": "cervical", "range_deg": [20, 11, 7], "neutral_extension_deg": 7, "length_m": 0.0139},
    {"name": "vc3", "level": "C3-C4", "region": "cervical", "range_deg": [15, 11, 7], "neutral_extension_deg": 6, "length_m": 0.0128},
    {"name": "vc2", "level": "C2-C3", "region": "cervical", "range_deg": [10, 10, 3], "neutral_extension_deg": 5, "length_m": 0.0227},
    {"name": "vc1", "level": "C1-C2", "region": "cervical", "range_deg": [20, 5, 40], "neutral_extension_deg": 5, "length_m": 0.0278}
  ],
  "sites": [
    {"first": "vl5", "joints": "swing"},
    {"first": "vl4", "joints": "swing"},
    {"first": "vl3", "joints": "swing"},
    {"first": "vl2", "joints": "revolute"},
    {"first": "vl1", "joints": "swing"},
    {"first": "vt12", "joints": "swing"},
    {"first": "vt11", "joints": "swing"},
    {"first": "vt10", "joints": "swing"},
    {"first": "vt9", "joints": "swing"},
    {"first": "vt8", "joints": "revolute"},
    {"first": "vt7", "joints": "swing"},
    {"first": "vt6", "joints": "swing"},
    {"first": "vt5", "joints": "swing"},
    {"first": "vt4", "joints": "revolute"},
    {"first": "vt3", "joints": "swing"},
    {"first": "vt2", "joints": "swing"},
    {"first": "vt1", "joints": "swing"},
    {"first": "vc7", "joints": "swing"},
    {"first": "vc6", "joints": "revolute"},
    {"first": "vc5", "joints": "swing"},
    {"first": "vc4", "joints": "swing"},
    {"first": "vc3", "joints": "revolute"},
    {"first": "vc2", "joints": "swing"},
    {"first": "vc1", "joints": "revolute"}
  ],
  "axis_coupling": [
    {"region": "cervical", "torsion_per_bending": 0.4, "side": "same"},
    {"region": "lumbar", "torsion_per_bending": 0.25, "side": "opposite"}
  ]
})json";

// The 8-site spine for full bodies: the same vertebrae, other sites.
const char* const kSimplifiedSitesJson = R"json([
  {"name": "lumbar_lower", "first": "vl5", "last": "vl4", "joints": "swing"},
  {"name": "lumbar_middle", "first": "vl3", "last": "vl2", "joints": "swing+revolute"},
  {"name": "lumbar_upper", "first": "vl1", "last": "vl1", "joints": "swing"},
  {"name": "thoracic_lower", "first": "vt12", "last": "vt9", "joints": "swing"},
  {"name": "thoracic_middle", "first": "vt8", "last": "vt5", "joints": "swing+revolute"},
  {"name": "thoracic_upper", "first": "vt4", "last": "vt1", "joints": "swing+revolute"},
  {"name": "cervical_lower", "first": "vc7", "last": "vc4", "joints": "swing+revolute"},
  {"name": "cervical_upper", "first": "vc3", "last": "vc1", "joints": "swing+revolute"}
])json";

}  // namespace embody::ik::spine::detail
