#include "eval/metrics.h"

#include <algorithm>
#include <cmath>

#include "core/percentile.h"

namespace embody::eval {

namespace {

constexpr double kContactHeight = 0.05, kContactSpeed = 0.20, kBendDegrees = 15.0, kTwistDegrees = 1.0;

double angleDegrees(const glm::dquat& a, const glm::dquat& b) {
  const double d = std::min(1.0, std::abs(glm::dot(glm::normalize(a), glm::normalize(b))));
  return glm::degrees(2.0 * std::acos(d));
}

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / double(v.size());
}

// Mean norm of the k-th backward difference of every scored joint's position, × fps^k.
double differenceNorm(const JointTrack& t, const std::vector<int>& joints, double fps, int order) {
  static const double kCoeff[4][4] = {{1, 0, 0, 0}, {1, -1, 0, 0}, {1, -2, 1, 0}, {1, -3, 3, -1}};
  double sum = 0.0;
  size_t n = 0;
  for (int f = order; f < t.frames(); ++f)
    for (int j : joints) {
      glm::dvec3 d(0.0);
      for (int k = 0; k <= order; ++k) d += kCoeff[order][k] * t.p(f - k, j);
      sum += glm::length(d) * std::pow(fps, order);
      ++n;
    }
  return n ? sum / double(n) : 0.0;
}

// The bend of a three-joint limb: angle (degrees) and the bend normal.
std::pair<double, glm::dvec3> bend(const JointTrack& t, int f, const std::array<int, 3>& limb) {
  const glm::dvec3 a = t.p(f, limb[1]) - t.p(f, limb[0]), b = t.p(f, limb[2]) - t.p(f, limb[1]);
  const glm::dvec3 n = glm::cross(a, b);
  return {glm::degrees(std::atan2(glm::length(n), glm::dot(a, b))), n};
}

bool reversed(const JointTrack& s, const JointTrack& c, int f, const std::array<int, 3>& limb) {
  if (limb[0] < 0 || limb[1] < 0 || limb[2] < 0) return false;
  const auto [sa, sn] = bend(s, f, limb);
  const auto [ca, cn] = bend(c, f, limb);
  return sa > kBendDegrees && ca > kBendDegrees && glm::dot(sn, cn) < 0.0;
}

bool torsionSignChange(const JointTrack& t, int f, const ScoredSkeleton::SpineRegion& region) {
  int sign = 0;
  for (size_t k = 1; k < region.chain.size(); ++k) {
    const glm::dquat local = glm::conjugate(t.q(f, region.chain[k - 1])) * t.q(f, region.chain[k]);
    const glm::dvec3 axis = region.axis[k];
    const double twist = glm::degrees(2.0 * std::atan2(glm::dot(glm::dvec3(local.x, local.y, local.z), axis), local.w));
    const double wrapped = std::remainder(twist, 360.0);
    if (std::abs(wrapped) < kTwistDegrees) continue;
    const int s = wrapped > 0 ? 1 : -1;
    if (sign != 0 && s != sign) return true;
    sign = s;
  }
  return false;
}

double soleHeight(const JointTrack& t, int f, const std::vector<int>& sole) {
  double y = 1e300;
  for (int j : sole) y = std::min(y, t.p(f, j).y);
  return y;
}

// The clip's body frame at frame f as (forward, left) on the ground: left from the right hip to
// the left one. False when the hips are not scored or coincide on the ground.
bool bodyFrame(const JointTrack& clip, const ScoredSkeleton& sk, int f, glm::dvec3& forward, glm::dvec3& left) {
  const int l = sk.legs[0][0], r = sk.legs[1][0];
  if (l < 0 || r < 0) return false;
  left = clip.p(f, l) - clip.p(f, r);
  left.y = 0.0;
  const double n = glm::length(left);
  if (n < 1e-9) return false;
  left /= n;
  forward = glm::cross(left, glm::dvec3(0.0, 1.0, 0.0));
  return true;
}

double horizontalSpeed(const JointTrack& t, int f, int j, double fps) {
  glm::dvec3 d = t.p(f, j) - t.p(f - 1, j);
  d.y = 0.0;
  return glm::length(d) * fps;
}

}  // namespace

const char* groupName(Group g) {
  static const char* kNames[] = {"all", "hands", "feet", "head", "upper", "lower", "root"};
  return kNames[int(g)];
}

double percentile95(std::vector<double> values) { return percentileNearestRank(values, 95.0); }

Metrics score(const JointTrack& solved, const JointTrack& clip, const ScoredSkeleton& sk, double fps) {
  Metrics m;
  const int frames = std::min(solved.frames(), clip.frames());
  m.frames = frames;
  m.perJointError.assign(size_t(clip.joints), 0.0);
  if (sk.legs[0][0] >= 0 && sk.legs[1][0] >= 0) m.perJointBias.assign(size_t(clip.joints), glm::dvec3(0.0));
  int biasFrames = 0;
  std::vector<double> error(size_t(clip.joints));
  double rotation = 0.0;
  size_t rotationCount = 0;
  for (int f = 0; f < frames; ++f) {
    for (int j = 0; j < clip.joints; ++j) {
      error[size_t(j)] = glm::length(solved.p(f, j) - clip.p(f, j));
      m.perJointError[size_t(j)] += error[size_t(j)] / double(frames);
    }
    glm::dvec3 forward, left;
    if (!m.perJointBias.empty() && bodyFrame(clip, sk, f, forward, left)) {
      for (int j = 0; j < clip.joints; ++j) {
        const glm::dvec3 d = solved.p(f, j) - clip.p(f, j);
        m.perJointBias[size_t(j)] += glm::dvec3(glm::dot(d, forward), glm::dot(d, left), d.y);
      }
      ++biasFrames;
    }
    for (int g = 0; g < kGroupCount; ++g) {
      if (sk.groups[size_t(g)].empty()) continue;
      double sum = 0.0;
      for (int j : sk.groups[size_t(g)]) sum += error[size_t(j)];
      m.perFrame[size_t(g)].push_back(sum / double(sk.groups[size_t(g)].size()));
    }
    for (int j : sk.groups[kAll]) rotation += angleDegrees(solved.q(f, j), clip.q(f, j)), ++rotationCount;
    unsigned char flags = 0;
    if (reversed(solved, clip, f, sk.legs[0]) || reversed(solved, clip, f, sk.legs[1])) ++m.kneeReverseFrames, flags |= kKneeReversed;
    if (reversed(solved, clip, f, sk.arms[0]) || reversed(solved, clip, f, sk.arms[1])) ++m.elbowReverseFrames, flags |= kElbowReversed;
    bool solvedChange = false, clipChange = false;
    for (const auto& region : sk.spineRegions) {
      solvedChange = solvedChange || torsionSignChange(solved, f, region);
      clipChange = clipChange || torsionSignChange(clip, f, region);
    }
    m.torsionSignChangeFrames += solvedChange;
    m.clipTorsionSignChangeFrames += clipChange;
    if (sk.pelvis >= 0 && sk.standingPelvisHeight > 0.0) {
      const double half = 0.5 * sk.standingPelvisHeight;
      if (solved.p(f, sk.pelvis).y < half && clip.p(f, sk.pelvis).y >= half) ++m.collapsedFrames, flags |= kCollapsed;
    }
    m.perFrameFlags.push_back(flags);
  }
  for (int g = 0; g < kGroupCount; ++g) {
    m.mpjpe[size_t(g)].mean = mean(m.perFrame[size_t(g)]);
    m.mpjpe[size_t(g)].p95 = percentile95(m.perFrame[size_t(g)]);
  }
  m.mpjreDegrees = rotationCount ? rotation / double(rotationCount) : 0.0;
  for (auto& b : m.perJointBias) b = biasFrames ? b / double(biasFrames) : glm::dvec3(0.0);

  // Velocities: backward differences.
  double velocity = 0.0;
  size_t velocityCount = 0;
  for (int f = 1; f < frames; ++f)
    for (int j : sk.groups[kAll]) {
      const glm::dvec3 vs = (solved.p(f, j) - solved.p(f - 1, j)) * fps, vc = (clip.p(f, j) - clip.p(f - 1, j)) * fps;
      velocity += glm::length(vs - vc), ++velocityCount;
    }
  m.mpjve = velocityCount ? velocity / double(velocityCount) : 0.0;
  for (int g = 0; g < kGroupCount; ++g) {
    m.groupJitter[size_t(g)] = differenceNorm(solved, sk.groups[size_t(g)], fps, 3);
    m.clipGroupJitter[size_t(g)] = differenceNorm(clip, sk.groups[size_t(g)], fps, 3);
  }
  m.jitter = m.groupJitter[kAll];
  m.clipJitter = m.clipGroupJitter[kAll];

  double skate = 0.0, clipSkate = 0.0;
  for (int f = 1; f < frames; ++f)
    for (size_t s = 0; s < 2; ++s) {
      if (sk.soles[s].empty()) continue;
      const int ankle = sk.soles[s][0];
      if (soleHeight(clip, f, sk.soles[s]) - sk.soleBelowAnkle[s] > kContactHeight || horizontalSpeed(clip, f, ankle, fps) > kContactSpeed) continue;
      skate += horizontalSpeed(solved, f, ankle, fps);
      clipSkate += horizontalSpeed(clip, f, ankle, fps);
      ++m.contactFrames;
    }
  m.footSkating = m.contactFrames ? skate / m.contactFrames : 0.0;
  m.clipFootSkating = m.contactFrames ? clipSkate / m.contactFrames : 0.0;
  return m;
}

}  // namespace embody::eval
