// A BVH clip's axes, height and reference frame, measured on the motion (bvh_body.h).
#include "avatar/bvh/bvh_body.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include "avatar/body/anthropometry.h"
#include "avatar/bvh/bvh_body_internal.h"

namespace embody::avatar {
namespace {

constexpr double kSnapUpDegrees = 25.0, kSnapForwardDegrees = 30.0;
// A body whose head stands over its feet along no axis of the file, by more than this, is not a
// person standing in a tilted capture volume (those lean 5-30 degrees) but a quadruped with human
// names (Truebones' animals: 43 degrees) or a performer lying down for much of the clip (35
// degrees, 60 % of the frames within 40 degrees of it).
constexpr double kMaxObliqueUpDegrees = 40.0;
constexpr double kObliqueUpAgreement = 0.8;  // ... or more than kSnapUpDegrees with fewer frames agreeing
constexpr double kHeadJointRatio = 0.91;        // skull base over the height, without a head-top joint
constexpr double kReferenceJumpHeightsPerS = 5.7;  // 10 m/s for a 1.75 m performer
// Leading reference frames (a T-pose held for a few frames, then the take): at most this many,
// each the same pose to within this share of the body's size.
constexpr size_t kMaxReferenceFrames = 10;
constexpr double kStillReferenceShare = 1e-4;
constexpr double kBareFootShare = 0.02;             // of the bone-length size (~3 cm at 1.75 m)
constexpr size_t kMaxStatFrames = 4096;           // frames read for the statistics (evenly spaced)

std::string fmt(const char* f, double a, double b = 0.0, double c = 0.0) {
  char buf[160];
  std::snprintf(buf, sizeof buf, f, a, b, c);
  return buf;
}

// The signed coordinate axis within `degrees` of v, else v itself (v unit).
glm::dvec3 snapAxis(const glm::dvec3& v, double degrees) {
  int best = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(v[i]) > std::abs(v[best])) best = i;
  if (std::abs(v[best]) < std::cos(glm::radians(degrees))) return v;
  glm::dvec3 a(0.0);
  a[best] = v[best] > 0 ? 1.0 : -1.0;
  return a;
}

// Joint j and every joint below it (parents come first in a clip).
std::vector<bool> subtree(const BvhClip& clip, int root) {
  std::vector<bool> in(clip.joints.size(), false);
  if (root < 0) return in;
  in[static_cast<size_t>(root)] = true;
  for (size_t j = static_cast<size_t>(root) + 1; j < clip.joints.size(); ++j)
    if (clip.joints[j].parent >= 0) in[j] = in[static_cast<size_t>(clip.joints[j].parent)];
  return in;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

// Runs fn(frame, globals) over frames [from, to), at most kMaxStatFrames evenly spaced.
template <class Fn>
void forFrames(const BvhClip& clip, size_t from, size_t to, Fn fn) {
  if (to <= from) return;
  const size_t stride = (to - from + kMaxStatFrames - 1) / kMaxStatFrames;
  std::vector<BvhGlobal> g;
  for (size_t f = from; f < to; f += stride) {
    bvhGlobals(clip, clip.frame(f), g);
    fn(f, g);
  }
}

struct BodyJoints {
  int hips, head, feet[2], hands[2];
  std::vector<std::pair<int, int>> lateralPairs;  // (left, right): upper legs, upper arms, ...
  explicit BodyJoints(const HumanoidMap& m)
      : hips(m.joint(HumanBone::hips)),
        head(m.joint(HumanBone::head)),
        feet{m.joint(HumanBone::leftFoot), m.joint(HumanBone::rightFoot)},
        hands{m.joint(HumanBone::leftHand), m.joint(HumanBone::rightHand)} {
    for (auto [l, r] : {std::pair{HumanBone::leftUpperLeg, HumanBone::rightUpperLeg},
                        std::pair{HumanBone::leftUpperArm, HumanBone::rightUpperArm},
                        std::pair{HumanBone::leftShoulder, HumanBone::rightShoulder},
                        std::pair{HumanBone::leftFoot, HumanBone::rightFoot}})
      if (m.has(l) && m.has(r)) lateralPairs.emplace_back(m.joint(l), m.joint(r));
    if (lateralPairs.empty() && m.has(HumanBone::leftHand) && m.has(HumanBone::rightHand))
      lateralPairs.emplace_back(m.joint(HumanBone::leftHand), m.joint(HumanBone::rightHand));
  }
  // The point under the head: between the feet, else the hips.
  int base() const { return feet[0] >= 0 ? feet[0] : (feet[1] >= 0 ? feet[1] : hips); }
  glm::dvec3 basePoint(const std::vector<BvhGlobal>& g) const {
    if (feet[0] >= 0 && feet[1] >= 0)
      return 0.5 * (g[static_cast<size_t>(feet[0])].position + g[static_cast<size_t>(feet[1])].position);
    return g[static_cast<size_t>(base())].position;
  }
};

// Straight-limb length hips -> head plus hips -> foot from the offsets: a frame-free size for
// thresholds before the height is measured.
double boneLengthSize(const BvhClip& clip, const BodyJoints& b) {
  auto chain = [&](int from, int to) {
    double len = 0.0;
    for (int j = to; j > from && j >= 0; j = clip.joints[static_cast<size_t>(j)].parent)
      len += glm::length(clip.joints[static_cast<size_t>(j)].offset);
    return len;
  };
  double size = (b.head >= 0 ? chain(b.hips, b.head) : 0.0) + (b.base() != b.hips ? chain(b.hips, b.base()) : 0.0);
  if (size <= 1e-9)
    for (const auto& j : clip.joints) size += glm::length(j.offset);
  return size;
}

// The first frame of the take: 0, or k + 1 when frames 0..k hold one reference pose (a T-pose)
// and a body joint jumps from it into frame k + 1 faster than any body moves, then moves at a
// body's speed. Two held T-pose frames were once played as motion (the hands 65 cm off at t = 0).
size_t referenceFrame(const BvhClip& clip, const BodyJoints& b, double size) {
  if (clip.frameCount < 3) return 0;
  const size_t span = std::min(clip.frameCount, kMaxReferenceFrames + 2);  // frames read
  const std::vector<int> joints{b.hips, b.head, b.feet[0], b.feet[1], b.hands[0], b.hands[1]};
  std::vector<std::vector<BvhGlobal>> g(span);
  for (size_t f = 0; f < span; ++f) bvhGlobals(clip, clip.frame(f), g[f]);
  auto moved = [&](size_t a) {  // the farthest a body joint moves from frame a to a + 1
    double d = 0.0;
    for (int j : joints)
      if (j >= 0) d = std::max(d, glm::length(g[a + 1][static_cast<size_t>(j)].position - g[a][static_cast<size_t>(j)].position));
    return d;
  };
  const double jump = kReferenceJumpHeightsPerS * size / 0.88 * clip.frameTime;  // the bone size is ~0.88 of the height
  for (size_t k = 0; k + 2 < span; ++k) {
    if (moved(k) > jump) return moved(k + 1) < jump ? k + 1 : 0;
    if (moved(k) > kStillReferenceShare * size) return 0;  // moving before any jump: frame 0 is the take's
  }
  return 0;
}

struct UpEstimate {
  glm::dvec3 up{0, 1, 0};
  double resultant = 0.0, agreement = 0.0;
};

UpEstimate measureUp(const BvhClip& clip, const BodyJoints& b, size_t first) {
  std::vector<glm::dvec3> dirs;
  forFrames(clip, first, clip.frameCount, [&](size_t, const std::vector<BvhGlobal>& g) {
    const glm::dvec3 v = g[static_cast<size_t>(b.head)].position - b.basePoint(g);
    if (glm::length(v) > 1e-12) dirs.push_back(glm::normalize(v));
  });
  UpEstimate e;
  glm::dvec3 sum(0.0);
  for (const auto& d : dirs) sum += d;
  if (dirs.empty() || glm::length(sum) < 1e-12) return e;
  e.resultant = glm::length(sum) / static_cast<double>(dirs.size());
  e.up = glm::normalize(sum);
  size_t agree = 0;
  for (const auto& d : dirs) agree += glm::dot(d, e.up) > std::cos(glm::radians(40.0)) ? 1 : 0;
  e.agreement = static_cast<double>(agree) / static_cast<double>(dirs.size());
  return e;
}

// The body's left in one frame: left minus right limbs, across `up` (not normalised).
glm::dvec3 leftAcross(const std::vector<BvhGlobal>& g, const BodyJoints& b, const glm::dvec3& up) {
  glm::dvec3 left(0.0);
  for (auto [l, r] : b.lateralPairs) left += g[static_cast<size_t>(l)].position - g[static_cast<size_t>(r)].position;
  return left - up * glm::dot(left, up);
}

// The left direction (left minus right limbs) across `up`, summed over frames [from, to).
glm::dvec3 lateralSum(const BvhClip& clip, const BodyJoints& b, const glm::dvec3& up, size_t from, size_t to,
                      double* resultant) {
  glm::dvec3 sum(0.0);
  size_t n = 0;
  forFrames(clip, from, to, [&](size_t, const std::vector<BvhGlobal>& g) {
    const glm::dvec3 left = leftAcross(g, b, up);
    if (glm::length(left) < 1e-12) return;
    sum += glm::normalize(left);
    ++n;
  });
  if (resultant) *resultant = n ? glm::length(sum) / static_cast<double>(n) : 0.0;
  return sum;
}

Status chooseUp(const BvhClip& clip, const BodyJoints& b, const BvhBodyOptions& o, BvhBody& body) {
  if (!o.up.empty()) {
    auto a = parseBvhAxis(o.up);
    if (!a) return Error{"--bvh-up: " + a.error()};
    body.up = *a;
    body.upFrom = "--bvh-up";
    body.upConfidence = 1.0;
    return {};
  }
  if (b.head < 0 || b.base() < 0 || b.base() == b.head)
    return Error{"cannot tell which way is up: no head joint, or no feet and hips below it; give --bvh-up +Y (or +Z, ...)"};
  const UpEstimate e = measureUp(clip, b, body.firstFrame);
  if (e.resultant < 0.5 || e.agreement < 0.5)
    return Error{fmt("axes ambiguous: the head is above the feet in only %.0f%% of the frames along any direction; "
                     "give --bvh-up (+Y, +Z, ...) and --bvh-forward",
                     100.0 * e.agreement)};
  body.up = snapAxis(e.up, kSnapUpDegrees);
  double offAxis = 90.0;
  for (int a = 0; a < 3; ++a) offAxis = std::min(offAxis, glm::degrees(std::acos(std::min(1.0, std::abs(e.up[a])))));
  // Off every axis and the frames disagreeing too: the body lies down for a good part of the clip.
  if (offAxis > kMaxObliqueUpDegrees || (offAxis > kSnapUpDegrees && e.agreement < kObliqueUpAgreement))
    return Error{fmt("not a standing humanoid: its head stands over its feet %.0f deg from every axis of the file", offAxis) +
                 " (a quadruped with human joint names, or a performer lying down for most of the clip?); give --bvh-up "
                 "(+Y, +Z, ...) to read it anyway"};
  body.upFrom = "motion";
  body.upConfidence = e.agreement;
  const double off = glm::degrees(std::acos(std::clamp(glm::dot(body.up, e.up), -1.0, 1.0)));
  if (off > 3.0) body.notes.push_back(fmt("up: the head leans %.0f deg from the axis used, on average", off));
  return {};
}

Status chooseForward(const BvhClip& clip, const BodyJoints& b, const BvhBodyOptions& o, BvhBody& body) {
  if (!o.forward.empty()) {
    auto a = parseBvhAxis(o.forward);
    if (!a) return Error{"--bvh-forward: " + a.error()};
    if (std::abs(glm::dot(*a, body.up)) > 0.1)
      return Error{"--bvh-forward " + o.forward + " is not perpendicular to the up axis " + bvhAxisName(body.up)};
    body.forward = glm::normalize(*a - body.up * glm::dot(*a, body.up));
    body.forwardFrom = "--bvh-forward";
    body.forwardConfidence = 1.0;
    return {};
  }
  if (b.lateralPairs.empty())
    return Error{"cannot tell which way the performer faces: no left/right limbs mapped; give --bvh-forward (+Z, -X, ...)"};
  const size_t window = std::max<size_t>(2, static_cast<size_t>(std::lround(0.5 / clip.frameTime)));
  double resultant = 0.0;
  const glm::dvec3 left = lateralSum(clip, b, body.up, body.firstFrame, std::min(clip.frameCount, body.firstFrame + window), &resultant);
  if (glm::length(left) < 1e-12 || resultant < 0.5)
    return Error{"axes ambiguous: left and right limbs do not tell a facing at the start of the clip; give --bvh-forward"};
  const glm::dvec3 facing = glm::normalize(glm::cross(glm::normalize(left), body.up));
  glm::dvec3 snapped = snapAxis(facing, kSnapForwardDegrees);
  if (std::abs(glm::dot(snapped, body.up)) > 1e-6) snapped = facing;  // up not axis-aligned
  body.forward = snapped;
  body.forwardFrom = "motion";
  body.forwardConfidence = resultant;
  return {};
}

// The joint of a foot's subtree (toes, End Sites) farthest from the foot joint at rest, and how
// far (-1 and 0 without a foot).
struct FootTip {
  int joint = -1;
  double reach = 0.0;
};

FootTip footTip(const BvhClip& clip, int foot, const std::vector<BvhGlobal>& rest) {
  FootTip t;
  if (foot < 0) return t;
  const std::vector<bool> part = subtree(clip, foot);
  for (size_t j = 0; j < part.size(); ++j) {
    const double d = part[j] ? glm::length(rest[j].position - rest[static_cast<size_t>(foot)].position) : 0.0;
    if (d > t.reach) t = {static_cast<int>(j), d};
  }
  return t;
}

// Left and right against the toes: the facing from the names (left minus right limbs, across up)
// and the way the feet point (ankle to the farthest toe or End Site, on the ground), frame by
// frame over the take. A body whose toes point behind its hips and shoulders is no human pose:
// the file is mirrored (left-handed axes) or its Left/Right names are swapped. Both read as "walks
// backwards" and played the performer walking backwards, toes behind him (eval 4.2 cm for 0.84).
// Refused only on strong evidence: the toes behind (more than 60 deg off the back) in at least 80%
// of at least 10 frames where a foot points within 45 deg of level. Feet without toes or End Sites cannot
// be checked and pass.
Status checkSides(const BvhClip& clip, const BodyJoints& b, const BvhBody& body) {
  if (b.lateralPairs.empty()) return {};
  std::vector<BvhGlobal> rest;
  bvhGlobals(clip, {}, rest);
  const double size = boneLengthSize(clip, b);
  std::array<int, 2> tip{-1, -1};  // the farthest joint of each foot's subtree at rest
  std::array<double, 2> reach{0.0, 0.0};
  for (size_t i = 0; i < 2; ++i) {
    const FootTip t = footTip(clip, b.feet[i], rest);
    reach[i] = t.reach;
    tip[i] = t.reach < kBareFootShare * size ? -1 : t.joint;
  }
  if (tip[0] < 0 && tip[1] < 0) return {};
  size_t counted = 0, behind = 0;
  forFrames(clip, body.firstFrame, clip.frameCount, [&](size_t, const std::vector<BvhGlobal>& g) {
    const glm::dvec3 left = leftAcross(g, b, body.up);
    glm::dvec3 toes(0.0);
    for (size_t i = 0; i < 2; ++i) {
      if (tip[i] < 0) continue;
      glm::dvec3 t = g[static_cast<size_t>(tip[i])].position - g[static_cast<size_t>(b.feet[i])].position;
      t -= body.up * glm::dot(t, body.up);
      if (glm::length(t) > 0.7 * reach[i]) toes += glm::normalize(t);  // within 45 deg of level, not pointing down
    }
    if (glm::length(left) < 1e-12 || glm::length(toes) < 1e-12) return;
    const glm::dvec3 facing = glm::normalize(glm::cross(glm::normalize(left), body.up));
    ++counted;
    if (glm::dot(glm::normalize(toes), facing) < -0.5) ++behind;
  });
  if (counted < 10 || static_cast<double>(behind) < 0.8 * static_cast<double>(counted)) return {};
  return Error{fmt("left and right are mirrored: the toes point behind the way the hips and shoulders face in %.0f%% "
                   "of the frames",
                   100.0 * static_cast<double>(behind) / static_cast<double>(counted)) +
               " (a left-handed file, or its Left/Right joint names swapped); give --bvh-mirror to read a left-handed "
               "file mirrored back, or a --bvh-bone-map that exchanges the sides for swapped names"};
}

// Where the hips travel over the clip, against the facing (a check, not a decision).
void describeWalking(const BvhClip& clip, const BodyJoints& b, BvhBody& body) {
  std::vector<BvhGlobal> g;
  bvhGlobals(clip, clip.frame(body.firstFrame), g);
  const glm::dvec3 start = g[static_cast<size_t>(b.hips)].position;
  bvhGlobals(clip, clip.frame(clip.frameCount - 1), g);
  glm::dvec3 travel = g[static_cast<size_t>(b.hips)].position - start;
  travel -= body.up * glm::dot(travel, body.up);
  if (glm::length(travel) < 0.3 * body.heightUnits) {
    body.walking = "stays in place";
    return;
  }
  double r = 0.0;
  const glm::dvec3 left = lateralSum(clip, b, body.up, body.firstFrame, clip.frameCount, &r);
  const double c = glm::dot(glm::normalize(travel), glm::normalize(glm::cross(left, body.up)));
  body.walking = c > 0.5 ? "walks forward" : (c < -0.5 ? "walks backwards" : "moves sideways or turns");
}

// A foot with nothing to stand on below its joint: no descendant (toe joint, End Site) farther
// than kBareFootShare of the body's size from it at rest. s_no_toes (the CMU walk without its toes)
// and s_minimal (no End Sites either) stood on their ankles: the feet trackers 4 cm low and the
// performer measured 3 % short, so scaled 3 % up.
bool bareFoot(const BvhClip& clip, int foot, const std::vector<BvhGlobal>& rest, double size) {
  return foot >= 0 && footTip(clip, foot, rest).reach < kBareFootShare * size;
}

void measureHeight(const BvhClip& clip, const BodyJoints& b, BvhBody& body) {
  const std::vector<bool> headPart = subtree(clip, b.head);
  std::vector<BvhGlobal> rest;
  bvhGlobals(clip, {}, rest);
  const double size = boneLengthSize(clip, b);
  // Joints of a foot with toes (their lowest is the sole) and of a bare foot (the sole is under them).
  std::vector<bool> footPart(clip.joints.size(), false), barePart(clip.joints.size(), false);
  std::array<bool, 2> bare{false, false};
  for (int i = 0; i < 2; ++i) {
    bare[static_cast<size_t>(i)] = bareFoot(clip, b.feet[i], rest, size);
    const auto s = subtree(clip, b.feet[i]);
    std::vector<bool>& into = bare[static_cast<size_t>(i)] ? barePart : footPart;
    for (size_t j = 0; j < s.size(); ++j) into[j] = into[j] || s[j];
  }
  const bool anyFoot = b.feet[0] >= 0 || b.feet[1] >= 0;
  // Per frame: the top of the head, the head joint, the lowest toe, the lowest bare ankle.
  std::vector<double> hi, headJointAt, sole, ankle;
  forFrames(clip, body.firstFrame, clip.frameCount, [&](size_t, const std::vector<BvhGlobal>& g) {
    double top = -1e300, toes = 1e300, bareAnkle = 1e300;
    for (size_t j = 0; j < g.size(); ++j) {
      const double h = glm::dot(g[j].position, body.up);
      if (headPart[j]) top = std::max(top, h);
      if (barePart[j]) bareAnkle = std::min(bareAnkle, h);
      else if (!anyFoot || footPart[j]) toes = std::min(toes, h);
    }
    hi.push_back(top);
    headJointAt.push_back(glm::dot(g[static_cast<size_t>(b.head)].position, body.up));
    sole.push_back(toes);
    ankle.push_back(bareAnkle);
  });
  // The height with the bare soles `drop` under their ankles; the drop is a share of the height,
  // so the two are solved together (each step shrinks the change 20-fold).
  bool noHeadTop = false;
  auto measure = [&](double drop) {
    std::vector<double> top, headJoint;
    for (size_t f = 0; f < hi.size(); ++f) {
      const double s = std::min(sole[f], ankle[f] - drop);
      top.push_back(hi[f] - s);
      headJoint.push_back(headJointAt[f] - s);
    }
    body.headJointUnits = percentile(headJoint, 0.95);
    body.heightUnits = percentile(top, 0.95);
    noHeadTop = body.heightUnits - body.headJointUnits < 0.05 * body.heightUnits;
    if (noHeadTop) body.heightUnits = body.headJointUnits / kHeadJointRatio;
  };
  measure(0.0);
  if (bare[0] || bare[1]) {
    double drop = 0.0;
    for (int k = 0; k < 50 && std::abs(kAnkleHeightRatio * body.heightUnits - drop) > 1e-9 * body.heightUnits; ++k) {
      drop = kAnkleHeightRatio * body.heightUnits;
      measure(drop);
    }
    for (size_t i = 0; i < 2; ++i) body.soleBelowFoot[i] = bare[i] ? drop : 0.0;
    const std::string feet = bare[0] && bare[1] ? "feet" : (bare[0] ? "left foot" : "right foot");
    body.notes.push_back("no toes or End Site below the " + feet +
                         fmt(": the sole taken %.3g of the height (%.3g units) under the ankle joint", kAnkleHeightRatio, drop));
  }
  if (noHeadTop) body.notes.push_back("no joint at the top of the head: the head joint taken at 0.91 of the height");
}

}  // namespace

Result<glm::dvec3> parseBvhAxis(std::string_view text) {
  std::string_view t = text;
  double sign = 1.0;
  if (!t.empty() && (t[0] == '+' || t[0] == '-')) {
    sign = t[0] == '-' ? -1.0 : 1.0;
    t.remove_prefix(1);
  }
  if (t.size() == 1) {
    const char c = static_cast<char>(std::toupper(static_cast<unsigned char>(t[0])));
    if (c >= 'X' && c <= 'Z') {
      glm::dvec3 a(0.0);
      a[c - 'X'] = sign;
      return a;
    }
  }
  return Error{"'" + std::string(text) + "' is not an axis (+X, -X, +Y, -Y, +Z, -Z)"};
}

BvhBodyOptions mirroredBvhOptions(BvhBodyOptions options) {
  options.mirror = false;
  for (std::string* axis : {&options.up, &options.forward}) {
    const auto a = parseBvhAxis(*axis);
    if (a && std::abs(a->x) > 0.5) *axis = a->x > 0 ? "-X" : "+X";
  }
  return options;
}

std::string bvhAxisName(const glm::dvec3& v) {
  for (int i = 0; i < 3; ++i)
    if (std::abs(std::abs(v[i]) - 1.0) < 1e-9) return std::string(v[i] > 0 ? "+" : "-") + "XYZ"[i];
  return fmt("(%.2f, %.2f, %.2f)", v.x, v.y, v.z);
}

Result<BvhBody> analyseBvhBody(const BvhClip& clip, const BvhBodyOptions& options) {
  if (clip.joints.empty() || clip.frameCount == 0) return Error{"BVH clip has no joints or no frames"};
  BvhBody body;
  body.skeleton = bvhSkeleton(clip);
  auto mapped = mapBvhJoints(clip, body.skeleton, 0, options.boneMapJson);
  if (!mapped) return Error{mapped.error()};
  body.humanoid = std::move(*mapped);
  if (!body.humanoid.has(HumanBone::hips)) {
    body.humanoid.bones[static_cast<int>(HumanBone::hips)] = 0;  // the root is the pelvis in every common rig
    body.notes.push_back("hips: no joint named or shaped like the hips; using the root joint '" + clip.joints[0].name + "'");
  }
  const BodyJoints b(body.humanoid);
  body.firstFrame = referenceFrame(clip, b, boneLengthSize(clip, b));
  if (body.firstFrame == 1) body.notes.push_back("frame 0 is a reference pose (a body joint jumps into frame 1); skipped");
  if (body.firstFrame > 1)
    body.notes.push_back("frames 0-" + std::to_string(body.firstFrame - 1) + " hold a reference pose (a body joint jumps into frame " +
                         std::to_string(body.firstFrame) + "); skipped");
  if (auto s = chooseUp(clip, b, options, body); !s.ok()) return Error{s.error()};
  if (auto s = chooseForward(clip, b, options, body); !s.ok()) return Error{s.error()};
  body.upAxis = bvhAxisName(body.up);
  body.forwardAxis = bvhAxisName(body.forward);
  const glm::dvec3 left = glm::cross(body.up, body.forward);
  body.toXr = glm::transpose(glm::dmat3(-left, body.up, -body.forward));  // rows: right, up, back
  if (b.head >= 0)
    measureHeight(clip, b, body);
  if (!(body.heightUnits > 1e-9)) {
    body.heightUnits = boneLengthSize(clip, b) / 0.88;
    body.notes.push_back("height from the bone lengths (no head or no standing frame)");
  }
  if (auto s = checkSides(clip, b, body); !s.ok()) return Error{s.error()};
  describeWalking(clip, b, body);
  return body;
}

}  // namespace embody::avatar
