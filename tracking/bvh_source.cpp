#include "tracking/bvh_source.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include "tracking/body_dimensions.h"

namespace embody::tracking {

namespace {

using avatar::BvhClip;
using avatar::BvhGlobal;

// Lower case, namespace prefix ("mixamorig:") and rig prefixes dropped, separators removed:
// "mixamorig:LeftHand" -> "lefthand", "Hand_L" -> "handl", "Bip01 L Hand" -> "lhand".
std::string normalise(std::string_view name) {
  if (auto c = name.rfind(':'); c != std::string_view::npos) name.remove_prefix(c + 1);
  std::string s;
  for (char ch : name)
    if (std::isalnum(static_cast<unsigned char>(ch))) s += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  for (std::string_view prefix : {"mixamorig", "bip001", "bip01", "character1", "def"})
    if (s.rfind(prefix, 0) == 0 && s.size() > prefix.size()) {
      s.erase(0, prefix.size());
      break;
    }
  return s;
}

const std::array<std::vector<std::string_view>, kTrackerCount>& aliases() {
  static const std::array<std::vector<std::string_view>, kTrackerCount> a = {{
      {"head"},
      {"lefthand", "lhand", "handl", "leftwrist", "lwrist", "wristl"},
      {"righthand", "rhand", "handr", "rightwrist", "rwrist", "wristr"},
      {"hips", "hip", "pelvis"},
      {"leftfoot", "lfoot", "footl", "leftankle", "lankle", "anklel"},
      {"rightfoot", "rfoot", "footr", "rightankle", "rankle", "ankler"},
  }};
  return a;
}

int findJoint(const BvhClip& clip, TrackerId id) {
  const auto& names = aliases()[static_cast<size_t>(index(id))];
  for (std::string_view alias : names)
    for (size_t j = 0; j < clip.joints.size(); ++j)
      if (!clip.joints[j].endSite && normalise(clip.joints[j].name) == alias) return static_cast<int>(j);
  return -1;
}

std::string axisName(const glm::dvec3& v) {
  static const char* kAxes = "XYZ";
  for (int i = 0; i < 3; ++i)
    if (std::abs(v[i]) > 0.5) return std::string(v[i] > 0 ? "+" : "-") + kAxes[i];
  return "?";
}

// The signed coordinate axis nearest to v (v non-zero).
glm::dvec3 snap(const glm::dvec3& v) {
  int best = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(v[i]) > std::abs(v[best])) best = i;
  glm::dvec3 a(0.0);
  a[best] = v[best] > 0 ? 1.0 : -1.0;
  return a;
}

}  // namespace

Result<Trace> bvhToTrace(const BvhClip& clip, const BvhTrackerOptions& options, BvhMapping* mappingOut) {
  if (clip.joints.empty() || clip.frameCount == 0) return Error{"BVH clip has no joints or no frames"};
  if (!(options.userHeight >= 0.5f && options.userHeight <= 2.5f)) return Error{"user height outside 0.5 .. 2.5 m"};
  if (options.scale < 0.0 || !std::isfinite(options.scale)) return Error{"BVH scale must be positive"};
  BvhMapping m;
  for (auto id : kAllTrackers) {
    int& j = m.joint[static_cast<size_t>(index(id))];
    j = findJoint(clip, id);
    if (j >= 0) continue;
    std::string tried;
    for (auto a : aliases()[static_cast<size_t>(index(id))]) tried += (tried.empty() ? "" : ", ") + std::string(a);
    if (id == TrackerId::Hips) {  // the root is the pelvis in every common rig
      j = 0;
      m.notes.push_back("hips: no joint named like " + tried + "; using the root joint '" + clip.joints[0].name + "'");
    } else {
      m.notes.push_back(std::string(trackerKey(id)) + ": no joint named like " + tried + "; tracker absent");
    }
  }
  auto joint = [&](TrackerId id) { return m.joint[static_cast<size_t>(index(id))]; };

  std::vector<BvhGlobal> rest;
  avatar::bvhGlobals(clip, {}, rest);

  // File axes -> OpenXR. Up: hips to head; left: left limbs minus right limbs.
  glm::dvec3 up(0, 1, 0);
  if (joint(TrackerId::Head) >= 0) {
    const glm::dvec3 v = rest[static_cast<size_t>(joint(TrackerId::Head))].position -
                         rest[static_cast<size_t>(joint(TrackerId::Hips))].position;
    if (glm::length(v) > 1e-9) up = snap(v);
  }
  glm::dvec3 lateral(0.0);
  for (auto [l, r] : {std::pair{TrackerId::LeftHand, TrackerId::RightHand}, std::pair{TrackerId::LeftFoot, TrackerId::RightFoot}})
    if (joint(l) >= 0 && joint(r) >= 0)
      lateral += rest[static_cast<size_t>(joint(l))].position - rest[static_cast<size_t>(joint(r))].position;
  lateral -= up * glm::dot(lateral, up);
  glm::dvec3 left = glm::length(lateral) > 1e-9 ? snap(lateral) : glm::dvec3(0.0);
  if (glm::length(left) < 0.5 || std::abs(glm::dot(left, up)) > 0.5) {
    left = std::abs(up.x) < 0.5 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 0, 1);
    m.notes.push_back("facing: no left/right limbs to tell the facing; assuming the usual +Z");
  }
  const glm::dvec3 forward = glm::cross(left, up);  // OpenXR: (-X) x (+Y) = -Z
  m.upAxis = axisName(up);
  m.facingAxis = axisName(forward);
  // Rows of the file -> OpenXR rotation: world X = right = -left, Y = up, Z = back = -forward.
  const glm::dmat3 toXr = glm::transpose(glm::dmat3(-left, up, -forward));
  const glm::dquat qToXr = glm::quat_cast(toXr);

  // Standing height in file units from the rest skeleton, with the legs straightened: rest poses
  // often stand with the legs apart (CMU's does), which would underestimate the height.
  const double rootLevel = glm::dot(rest[0].position, up);
  double top = -1e300, lowest = 1e300;
  for (const auto& g : rest) {
    top = std::max(top, glm::dot(g.position, up) - rootLevel);
    lowest = std::min(lowest, glm::dot(g.position, up) - rootLevel);
  }
  double legHeight = -lowest;  // fallback without feet: the rest pose as it is
  for (auto foot : {TrackerId::LeftFoot, TrackerId::RightFoot}) {
    const int ankle = joint(foot);
    if (ankle < 0) continue;
    double straight = 0.0;
    for (int j = ankle; j > 0; j = clip.joints[static_cast<size_t>(j)].parent) {
      const glm::dvec3& o = clip.joints[static_cast<size_t>(j)].offset;
      const double len = glm::length(o), vertical = std::abs(glm::dot(o, up));
      straight += vertical > 0.8 * len ? len : vertical;  // leg bones count whole, hip offsets only vertically
    }
    double sole = glm::dot(rest[static_cast<size_t>(ankle)].position, up);
    for (size_t j = static_cast<size_t>(ankle) + 1; j < clip.joints.size(); ++j) {
      int a = clip.joints[j].parent;
      while (a > ankle) a = clip.joints[static_cast<size_t>(a)].parent;
      if (a == ankle) sole = std::min(sole, glm::dot(rest[j].position, up));
    }
    legHeight = std::max(legHeight, straight + glm::dot(rest[static_cast<size_t>(ankle)].position, up) - sole);
  }
  m.restHeightUnits = top + legHeight;
  if (!(m.restHeightUnits > 1e-9)) return Error{"BVH rest skeleton has no height (all joints at one level)"};
  m.scale = options.scale > 0.0 ? options.scale : options.userHeight / m.restHeightUnits;
  {
    char buf[200];
    std::snprintf(buf, sizeof buf, "standing height %.2f units (rest skeleton, legs straight), %s up, facing %s; "
                  "scale %.4f m/unit (%s)",
                  m.restHeightUnits, m.upAxis.c_str(), m.facingAxis.c_str(), m.scale,
                  options.scale > 0.0 ? "given" : "fitted to the user height");
    m.notes.insert(m.notes.begin(), buf);
  }
  const double performer = m.restHeightUnits * m.scale;
  const BodyDimensions body = BodyDimensions::fromHeight(static_cast<float>(std::clamp(performer, 0.5, 2.5)));

  // Reference orientations (tracker frame in the rest pose, OpenXR axes) and the eye offset.
  auto restXr = [&](int j) { return toXr * rest[static_cast<size_t>(j)].position * m.scale; };
  std::array<glm::dquat, kTrackerCount> reference;
  reference.fill(glm::dquat(1, 0, 0, 0));
  for (auto [id, side] : {std::pair{TrackerId::LeftHand, Side::Left}, std::pair{TrackerId::RightHand, Side::Right}}) {
    const int h = joint(id);
    if (h < 0) continue;
    // Fingers along the forearm (the first ancestor not on top of the wrist).
    int a = clip.joints[static_cast<size_t>(h)].parent;
    while (a >= 0 && glm::length(restXr(h) - restXr(a)) < 1e-4) a = clip.joints[static_cast<size_t>(a)].parent;
    const glm::dvec3 forearm = a >= 0 ? restXr(h) - restXr(a) : glm::dvec3(0.0);
    reference[static_cast<size_t>(index(id))] = glm::dquat(restGripOrientation(side, glm::vec3(forearm)));
  }
  glm::dvec3 eyeOffset(0.0);
  if (joint(TrackerId::Head) >= 0) {
    // Eyes at kEyeHeightRatio of the standing height, ahead of the head joint (OpenXR axes, rest pose).
    const double headAboveSole =
        (legHeight + glm::dot(rest[static_cast<size_t>(joint(TrackerId::Head))].position, up) - rootLevel) * m.scale;
    const double rise = std::clamp(kEyeHeightRatio * performer - headAboveSole, -0.05 * performer, 0.1 * performer);
    eyeOffset = glm::dvec3(0.0, rise, -static_cast<double>(body.eyeForward));
  }

  Trace trace;
  trace.source = "bvh";
  trace.userHeight = options.userHeight;
  trace.samples.resize(clip.frameCount);  // times from 0; TraceSource replays from the first sample
  std::vector<BvhGlobal> g;
  for (auto id : kAllTrackers)
    if (joint(id) >= 0) trace.trackers.set(id);
  double floorY = 1e300;
  for (size_t f = 0; f < clip.frameCount; ++f) {
    avatar::bvhGlobals(clip, clip.frame(f), g);
    for (const auto& x : g) floorY = std::min(floorY, (toXr * x.position).y * m.scale);
    PoseSample& s = trace.samples[f];
    s.time = static_cast<double>(f) * clip.frameTime;
    for (auto id : kAllTrackers) {
      const int j = joint(id);
      if (j < 0) continue;
      const auto ju = static_cast<size_t>(j);
      const glm::dquat delta = qToXr * g[ju].rotation * glm::inverse(rest[ju].rotation) * glm::inverse(qToXr);
      glm::dvec3 p = toXr * g[ju].position * m.scale;
      if (id == TrackerId::Head) p += delta * eyeOffset;
      TrackerPose& t = s[id];
      t.position = glm::vec3(p);
      t.orientation = glm::normalize(glm::quat(delta * reference[static_cast<size_t>(index(id))]));
      t.valid = true;
    }
  }
  // Many converted clips (CMU's among them) start with a reference pose (a T-pose) one frame
  // before the motion: a jump no person makes. Skip it rather than replay the jump.
  if (trace.samples.size() > 2) {
    auto fastest = [&](const PoseSample& a, const PoseSample& b) {
      float v = 0.0f;
      for (auto id : kAllTrackers)
        if (trace.trackers.has(id))
          v = std::max(v, glm::length(b[id].position - a[id].position) / static_cast<float>(clip.frameTime));
      return v;
    };
    const float first = fastest(trace.samples[0], trace.samples[1]);
    if (first > 10.0f && fastest(trace.samples[1], trace.samples[2]) < 10.0f) {
      trace.samples.erase(trace.samples.begin());
      m.firstFrame = 1;
      char buf[160];
      std::snprintf(buf, sizeof buf, "frame 0 is a reference pose (a tracker jumps at %.0f m/s to frame 1); skipped",
                    static_cast<double>(first));
      m.notes.push_back(buf);
    }
  }
  glm::vec3 shift(0.0f);
  if (options.alignGround) shift.y = -static_cast<float>(floorY);
  if (options.recentre) {
    const glm::vec3 h0 = trace.samples[0][TrackerId::Hips].position;
    shift.x = -h0.x;
    shift.z = -h0.z;
  }
  for (auto& s : trace.samples) {
    for (auto id : kAllTrackers)
      if (trace.trackers.has(id)) s[id].position += shift;
    sanitize(s);
  }
  m.toXr = toXr;
  m.shift = glm::dvec3(shift);
  m.eyeOffset = eyeOffset;
  m.reference = reference;
  for (const auto& w : clip.warnings) m.notes.push_back(w);
  trace.notes = m.notes;
  if (mappingOut) *mappingOut = std::move(m);
  return trace;
}

Result<std::unique_ptr<TraceSource>> openBvhSource(const std::string& path, const BvhTrackerOptions& options,
                                                   BvhMapping* mapping) {
  auto clip = avatar::loadBvh(path);
  if (!clip) return Error{clip.error()};
  auto trace = bvhToTrace(*clip, options, mapping);
  if (!trace) return Error{path + ": " + trace.error()};
  trace->source = path;
  return std::make_unique<TraceSource>(std::move(*trace), path);
}

}  // namespace embody::tracking
