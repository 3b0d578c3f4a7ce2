#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "tracking/bvh_source.h"

namespace embody::tracking {

namespace {

using avatar::BvhChannel;
using avatar::BvhClip;

// Speeds in the skeleton's reach (its farthest joint from the root in the rest pose, about 0.55
// of the standing height) per second: 50 is about 27 heights a second, 48 m/s for a 1.75 m
// performer, four times a sprint. A jump under a tenth of the reach is never one (the 1000 Hz
// noise floor).
constexpr double kGlitchReachesPerSecond = 50.0;
constexpr double kGlitchMinReaches = 0.1;
// A glitch comes back within a second; a root that stays away is a cut in the clip (left alone),
// unless it went beyond any capture volume (kGlitchFarReaches, about 100 m): a broken clip.
constexpr double kGlitchMaxSeconds = 1.0;
constexpr double kGlitchFarReaches = 100.0;

// The joints with position channels (the root, a root under a static one), and where their
// X/Y/Z values sit in a frame (-1: no such channel).
struct PositionJoint {
  int channel[3] = {-1, -1, -1};
};

std::vector<PositionJoint> positionJoints(const BvhClip& clip) {
  std::vector<PositionJoint> out;
  for (const auto& j : clip.joints) {
    PositionJoint p;
    bool any = false;
    for (size_t c = 0; c < j.channels.size(); ++c) {
      const int k = static_cast<int>(j.channels[c]);
      if (k < 3) p.channel[k] = j.firstChannel + static_cast<int>(c), any = true;
    }
    if (any) out.push_back(p);
  }
  return out;
}

// The rest pose's farthest joint from the root: the skeleton's size in file units, whatever its
// pose or axes (0 when the offsets are all zero).
double skeletonReach(const BvhClip& clip) {
  std::vector<avatar::BvhGlobal> g;
  avatar::bvhGlobals(clip, {}, g);
  double reach = 0.0;
  for (const auto& x : g) reach = std::max(reach, glm::length(x.position - g[0].position));
  return std::isfinite(reach) ? reach : 0.0;
}

struct GlitchScan {
  const BvhClip& clip;
  std::vector<PositionJoint> joints;
  double reach = 0.0;

  // The largest move of a position joint between two frames, in file units.
  double distance(size_t a, size_t b) const {
    const auto fa = clip.frame(a), fb = clip.frame(b);
    double worst = 0.0;
    for (const auto& j : joints) {
      double d2 = 0.0;
      for (int k : j.channel)
        if (k >= 0) {
          const double d = double(fb[size_t(k)]) - double(fa[size_t(k)]);
          d2 += d * d;
        }
      worst = std::max(worst, std::sqrt(d2));
    }
    return worst;
  }
  // The farthest a position joint is from the file's origin in a frame.
  double magnitude(size_t f) const {
    const auto v = clip.frame(f);
    double worst = 0.0;
    for (const auto& j : joints) {
      double d2 = 0.0;
      for (int k : j.channel)
        if (k >= 0) d2 += double(v[size_t(k)]) * double(v[size_t(k)]);
      worst = std::max(worst, std::sqrt(d2));
    }
    return worst;
  }
  // The farthest a body moves in `frames` frames.
  double limit(size_t frames) const {
    return reach * std::max(kGlitchReachesPerSecond * clip.frameTime * double(frames), kGlitchMinReaches);
  }
};

std::string frameList(const std::vector<BvhGlitch>& spans) {
  std::string s;
  for (size_t i = 0; i < spans.size(); ++i) {
    if (i == 5) return s + " and " + std::to_string(spans.size() - 5) + " more spans";
    s += (i ? ", " : "") + std::to_string(spans[i].first);
    if (spans[i].last > spans[i].first) s += "-" + std::to_string(spans[i].last);
  }
  return s;
}

}  // namespace

Result<std::vector<BvhGlitch>> findBvhGlitches(const BvhClip& clip) {
  GlitchScan scan{clip, positionJoints(clip), skeletonReach(clip)};
  std::vector<BvhGlitch> spans;
  const size_t n = clip.frameCount;
  if (scan.joints.empty() || !(scan.reach > 0.0) || n < 2 || !(clip.frameTime > 0.0)) return spans;
  const size_t window = std::max<size_t>(1, static_cast<size_t>(kGlitchMaxSeconds / clip.frameTime));
  const size_t none = std::numeric_limits<size_t>::max();
  size_t good = 0;  // the last frame whose root is where a body can be
  for (size_t f = 1; f < n; ++f) {
    const double jump = scan.distance(good, f);
    if (jump <= scan.limit(f - good)) {
      good = f;
      continue;
    }
    // f jumped away from `good`: the glitch ends with a jump back to within reach of it (a jump:
    // frames inside a long glitch can be within the growing reach of `good` yet stay glitched).
    size_t back = none;
    for (size_t g = f + 1; g < n && g - good <= window; ++g)
      if (scan.distance(g - 1, g) > scan.limit(1) && scan.distance(good, g) <= scan.limit(g - good)) {
        back = g;
        break;
      }
    const bool far = jump > kGlitchFarReaches * scan.reach;
    if (back != none) {
      spans.push_back({f, back - 1, good, back, jump});
      good = back;
      f = back;
    } else if (far && spans.empty() && f <= window && scan.magnitude(0) > scan.magnitude(f)) {
      // Frames 0..f-1 were the glitch: beyond any capture volume from where the clip goes on, and
      // farther from the origin than it.
      spans.push_back({0, f - 1, none, f, jump});
      good = f;
    } else if (n - 1 - good <= window && n - f < f) {
      // The clip ends within the glitch (and the glitch is not most of it): held at the last good frame.
      spans.push_back({f, n - 1, good, none, jump});
      break;
    } else if (far) {
      char text[240];
      std::snprintf(text, sizeof text,
                    "frame %zu: the root jumps %.3g units (the skeleton reaches %.3g units from its root) and does not "
                    "come back within %g s: the clip is broken from there",
                    f, jump, scan.reach, kGlitchMaxSeconds);
      return Error{text};
    } else {
      good = f;  // a cut in the clip: the motion goes on from there
    }
  }
  return spans;
}

Result<size_t> repairBvhGlitches(BvhClip& clip) {
  auto spans = findBvhGlitches(clip);
  if (!spans) return Error{spans.error()};
  if (spans->empty()) return size_t{0};
  const std::vector<PositionJoint> joints = positionJoints(clip);
  const size_t none = std::numeric_limits<size_t>::max();
  const size_t channels = static_cast<size_t>(clip.channelCount);
  size_t repaired = 0;
  double worst = 0.0;
  for (const BvhGlitch& s : *spans) {
    worst = std::max(worst, s.jump);
    for (size_t f = s.first; f <= s.last; ++f) {
      // Linear between the good frames either side; held at the one there is at the clip's ends.
      const size_t a = s.before != none ? s.before : s.after, b = s.after != none ? s.after : s.before;
      const double t = a == b ? 0.0 : double(f - a) / double(b - a);
      for (const auto& j : joints)
        for (int k : j.channel)
          if (k >= 0) {
            const size_t c = size_t(k);
            const double va = clip.values[a * channels + c], vb = clip.values[b * channels + c];
            clip.values[f * channels + c] = static_cast<float>(va + (vb - va) * t);
          }
      ++repaired;
    }
  }
  char text[320];
  std::snprintf(text, sizeof text,
                " (%zu of %zu): the root jumps up to %.3g units away and back (the skeleton reaches %.3g units from its "
                "root), faster than any body moves; their root positions were interpolated from the frames either "
                "side (held at the clip's ends)",
                repaired, clip.frameCount, worst, skeletonReach(clip));
  clip.warnings.push_back("root glitch in frame" + std::string(repaired > 1 ? "s " : " ") + frameList(*spans) + text);
  return repaired;
}

}  // namespace embody::tracking
