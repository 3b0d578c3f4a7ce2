#include "tracking/bvh_source.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "avatar/body/calibration.h"
#include "core/percentile.h"
#include "tracking/body_dimensions.h"

namespace embody::tracking {

namespace {

using avatar::BvhBody;
using avatar::BvhClip;
using avatar::BvhGlobal;
using avatar::HumanBone;

constexpr HumanBone kTrackerBone[kTrackerCount] = {HumanBone::head,     HumanBone::leftHand, HumanBone::rightHand,
                                                   HumanBone::hips,     HumanBone::leftFoot, HumanBone::rightFoot};

// The user's height, in the range every CLI option takes (avatar/body/calibration.h).
Status checkUserHeight(float userHeight) {
  if (avatar::plausibleBodyHeight(userHeight)) return {};
  char text[48];
  std::snprintf(text, sizeof text, "%g", double(userHeight));
  return Error{std::string("--user-height ") + text + " m is outside " + avatar::bodyHeightRange()};
}

Status checkOptions(const BvhClip& clip, const BvhTrackerOptions& options) {
  if (clip.joints.empty() || clip.frameCount == 0) return Error{"BVH clip has no joints or no frames"};
  if (auto s = checkUserHeight(options.userHeight); !s) return s;
  if (options.scale < 0.0 || !std::isfinite(options.scale)) return Error{"--bvh-scale must be positive"};
  return {};
}

// A given --bvh-scale must make the performer a body height the project takes (the range of
// --user-height): 1e30 or 1e-30 reached the body solver as "a rest frame is not finite", 1e6 an
// eval of 2.4e9 cm at exit 0. The message gives the scales that would do for this clip.
Status checkScale(const BvhTrackerOptions& options, double heightUnits) {
  if (options.scale <= 0.0 || !(heightUnits > 0.0)) return {};  // fitted to the user's height
  const double performer = heightUnits * options.scale;
  if (avatar::plausibleBodyHeight(performer)) return {};
  char text[320];
  std::snprintf(text, sizeof text,
                "--bvh-scale %g m/unit makes the performer %.3g m tall (%.4g units standing), not %s; for this clip "
                "give %.3g .. %.3g m/unit, or leave --bvh-scale out to fit the user's height",
                options.scale, performer, heightUnits, avatar::bodyHeightRange().c_str(),
                avatar::kMinBodyHeight / heightUnits, avatar::kMaxBodyHeight / heightUnits);
  return Error{text};
}

// A required tracker without a joint stops the run (one line: what is missing, how to map it);
// an optional one is absent with a note.
Status checkTrackers(const BvhClip& clip, const BvhTrackerOptions& options, BvhMapping& m) {
  std::string missing;
  for (auto id : kAllTrackers) {
    if (m.joint[static_cast<size_t>(index(id))] >= 0) continue;
    const std::string bone(avatar::humanBoneName(kTrackerBone[static_cast<size_t>(index(id))]));
    if (options.required.has(id)) {
      missing += (missing.empty() ? "" : ", ") + bone;
    } else {
      m.notes.push_back(std::string(trackerKey(id)) + ": no joint named or shaped like the " + bone + "; tracker absent");
    }
  }
  if (missing.empty()) return {};
  std::string example = "JOINT";
  for (const auto& j : clip.joints)
    if (!j.endSite) example = j.name;  // a real name from the file, for the example
  return Error{"no joint for " + missing + " (by names or skeleton shape); map it with --bvh-bone-map FILE, "
               "e.g. {\"" + missing.substr(0, missing.find(',')) + "\": \"" + example + "\"}"};
}

std::string mappingNote(const BvhClip& clip, const BvhMapping& m, const BvhTrackerOptions& options) {
  const BvhBody& b = m.body;
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "standing height %.2f units; scale %.4f m/unit (%s); %s up (%s, %.0f%% sure), facing %s (%s, %.0f%% "
                "sure), %s; joints by %s",
                m.heightUnits, m.scale, options.scale > 0.0 ? "given" : "fitted to the user height", m.upAxis.c_str(),
                b.upFrom.c_str(), 100.0 * b.upConfidence, m.facingAxis.c_str(), b.forwardFrom.c_str(),
                100.0 * b.forwardConfidence, b.walking.c_str(), std::string(avatar::mappingMethodName(b.humanoid.method)).c_str());
  std::string note = buf;
  note += ":";
  for (auto id : kAllTrackers) {
    const int j = m.joint[static_cast<size_t>(index(id))];
    note += std::string(" ") + std::string(trackerKey(id)) + "=" + (j >= 0 ? clip.joints[static_cast<size_t>(j)].name : "-");
  }
  return note;
}

// Tracker frames in the reference (first motion) frame, in OpenXR axes: identity for the head,
// hips and feet (the clip is turned so the performer faces -Z there); for hands the grip of a
// hand along its forearm.
struct References {
  std::array<glm::dquat, kTrackerCount> orientation;
  std::vector<BvhGlobal> pose;  // the reference frame's globals
  glm::dvec3 eyeOffset{0.0};    // from the head joint to the eyes, OpenXR axes, metres
};

References references(const BvhClip& clip, const BvhMapping& m) {
  References r;
  r.orientation.fill(glm::dquat(1, 0, 0, 0));
  avatar::bvhGlobals(clip, clip.frame(m.body.firstFrame), r.pose);
  auto xr = [&](int j) { return m.body.toXr * r.pose[static_cast<size_t>(j)].position * m.scale; };
  for (auto [id, side] : {std::pair{TrackerId::LeftHand, Side::Left}, std::pair{TrackerId::RightHand, Side::Right}}) {
    const int h = m.joint[static_cast<size_t>(index(id))];
    if (h < 0) continue;
    // Fingers along the forearm (the first ancestor not on top of the wrist).
    int a = clip.joints[static_cast<size_t>(h)].parent;
    while (a >= 0 && glm::length(xr(h) - xr(a)) < 1e-4) a = clip.joints[static_cast<size_t>(a)].parent;
    const glm::dvec3 forearm = a >= 0 ? xr(h) - xr(a) : glm::dvec3(0.0);
    r.orientation[static_cast<size_t>(index(id))] = glm::dquat(restGripOrientation(side, glm::vec3(forearm)));
  }
  // Eyes at kEyeHeightRatio of the standing height, ahead of the head joint.
  const double performer = m.heightUnits * m.scale;
  const BodyDimensions body =
      BodyDimensions::fromHeight(static_cast<float>(std::clamp(performer, avatar::kMinBodyHeight, avatar::kMaxBodyHeight)));
  const double rise = std::clamp(kEyeHeightRatio * performer - m.body.headJointUnits * m.scale, -0.05 * performer,
                                 0.1 * performer);
  r.eyeOffset = glm::dvec3(0.0, rise, -static_cast<double>(body.eyeForward));
  return r;
}

// The floor under a clip: the 5th percentile of each frame's lowest point. Not the lowest point
// of the whole clip: extrapolated end sites dip below the floor in a few frames (cgspeed's
// `LeftToe_End` 7.5 cm under where the feet stand in 95 % of `cmu_131_02`), and taking that as the
// floor stood the performer 7-10 cm above it, out of reach of a body whose feet are on the floor.
// Robust to outliers in up to 1 frame in 20; a clip standing on the floor in fewer frames (a jump
// sequence) is still placed on the lowest of the frames it stands in. A foot without toes or End
// Site counts with its sole under the ankle (BvhBody::soleBelowFoot), not the ankle itself.
double floorHeight(std::vector<double>& lowestPerFrame) {
  return lowestPerFrame.empty() ? 0.0 : percentileByRank(lowestPerFrame, kFloorPercentile);
}

// Every motion frame's trackers (times from 0 at frame 0), and the floor (floorHeight).
Trace sampleFrames(const BvhClip& clip, const BvhMapping& m, const References& ref, double& floorY) {
  const glm::dquat qToXr = glm::quat_cast(m.body.toXr);
  Trace trace;
  trace.source = "bvh";
  for (auto id : kAllTrackers)
    if (m.joint[static_cast<size_t>(index(id))] >= 0) trace.trackers.set(id);
  trace.samples.resize(clip.frameCount - m.body.firstFrame);
  std::vector<BvhGlobal> g;
  std::vector<double> lowest;
  lowest.reserve(clip.frameCount);
  for (size_t f = m.body.firstFrame; f < clip.frameCount; ++f) {
    avatar::bvhGlobals(clip, clip.frame(f), g);
    double low = 1e300;
    for (const auto& x : g) low = std::min(low, (m.body.toXr * x.position).y * m.scale);
    low = m.body.lowestWithBareSoles(low, m.scale, [&](size_t, int foot) {
      return (m.body.toXr * g[static_cast<size_t>(foot)].position).y * m.scale;
    });
    lowest.push_back(low);
    PoseSample& s = trace.samples[f - m.body.firstFrame];
    s.time = static_cast<double>(f) * clip.frameTime;
    for (auto id : kAllTrackers) {
      const int j = m.joint[static_cast<size_t>(index(id))];
      if (j < 0) continue;
      const auto ju = static_cast<size_t>(j);
      const glm::dquat delta = qToXr * g[ju].rotation * glm::inverse(ref.pose[ju].rotation) * glm::inverse(qToXr);
      glm::dvec3 p = m.body.toXr * g[ju].position * m.scale;
      if (id == TrackerId::Head) p += delta * ref.eyeOffset;
      TrackerPose& t = s[id];
      t.position = glm::vec3(p);
      t.orientation = glm::normalize(glm::quat(delta * ref.orientation[static_cast<size_t>(index(id))]));
      t.valid = true;
    }
  }
  floorY = floorHeight(lowest);
  return trace;
}

// The floor (floorHeight) at y = 0, the first frame's hips over the origin.
glm::vec3 placeOnFloor(Trace& trace, double floorY, const BvhTrackerOptions& options) {
  glm::vec3 shift(0.0f);
  if (options.alignGround) shift.y = -static_cast<float>(floorY);
  if (options.recentre && trace.trackers.has(TrackerId::Hips)) {
    const glm::vec3 h0 = trace.samples[0][TrackerId::Hips].position;
    shift.x = -h0.x;
    shift.z = -h0.z;
  }
  for (auto& s : trace.samples) {
    for (auto id : kAllTrackers)
      if (trace.trackers.has(id)) s[id].position += shift;
    sanitize(s);
  }
  return shift;
}

// The eyes at most at eye height (kEyeHeightRatio of the standing height) in 99% of the frames:
// the floor is the clip's lowest point and the head's reference is the first motion frame, both
// of which can lift the eye point above what a body of that height reaches standing. The excess
// comes off the eye offset, along the head's up.
float capEyeHeight(Trace& trace, double performer) {
  if (!trace.trackers.has(TrackerId::Head) || trace.samples.empty()) return 0.0f;
  std::vector<float> y;
  for (const auto& s : trace.samples) y.push_back(s[TrackerId::Head].position.y);
  const size_t k = (y.size() - 1) * 99 / 100;
  std::nth_element(y.begin(), y.begin() + static_cast<std::ptrdiff_t>(k), y.end());
  const float excess = y[k] - static_cast<float>(kEyeHeightRatio * performer);
  if (excess <= 0.0f) return 0.0f;
  for (auto& s : trace.samples) {
    TrackerPose& h = s[TrackerId::Head];
    h.position -= h.orientation * glm::vec3(0.0f, excess, 0.0f);
  }
  return excess;
}

// The references at the clip's rest pose (every channel zero), for code that sets the clip's own
// skeleton beside the trace (tracking/bvh_avatar.h, embody eval): at the rest pose a tracker reads
// restTurn * ref.orientation and the eyes sit restTurn * eyeOffset from the head joint, where
// restTurn is the joint's turn from the reference frame to the rest pose (tracking axes).
void restReferences(const BvhClip& clip, const References& ref, float eyeDrop, BvhMapping& m) {
  const glm::dquat qToXr = glm::quat_cast(m.body.toXr);
  std::vector<BvhGlobal> rest;
  avatar::bvhGlobals(clip, {}, rest);
  for (auto id : kAllTrackers) {
    const size_t i = static_cast<size_t>(index(id));
    const int j = m.joint[i];
    if (j < 0) continue;
    const auto ju = static_cast<size_t>(j);
    const glm::dquat restTurn = qToXr * rest[ju].rotation * glm::inverse(ref.pose[ju].rotation) * glm::inverse(qToXr);
    m.reference[i] = restTurn * ref.orientation[i];
    if (id == TrackerId::Head)  // capEyeHeight lowered the eyes along the head's up
      m.eyeOffset = restTurn * (ref.eyeOffset - ref.orientation[i] * glm::dvec3(0.0, double(eyeDrop), 0.0));
  }
}

}  // namespace

std::array<int, kTrackerCount> bvhTrackerJoints(const avatar::HumanoidMap& humanoid) {
  std::array<int, kTrackerCount> j{};
  for (auto id : kAllTrackers) j[static_cast<size_t>(index(id))] = humanoid.joint(kTrackerBone[static_cast<size_t>(index(id))]);
  return j;
}

Result<Trace> bvhToTrace(const BvhClip& clip, const BvhTrackerOptions& options, BvhMapping* mappingOut) {
  if (auto s = checkOptions(clip, options); !s.ok()) return Error{s.error()};
  if (options.body.mirror) {  // --bvh-mirror: a left-handed file, read mirrored back (on a copy)
    BvhClip mirrored = clip;
    avatar::mirrorBvhClip(mirrored);
    BvhTrackerOptions o = options;
    o.body = avatar::mirroredBvhOptions(options.body);
    auto trace = bvhToTrace(mirrored, o, mappingOut);
    if (trace && mappingOut) mappingOut->notes.push_back("--bvh-mirror: the clip read mirrored across its X axis");
    if (trace) trace->notes.push_back("--bvh-mirror: the clip read mirrored across its X axis");
    return trace;
  }
  // A glitch frame (a root 99999 units up for one frame) ruined every measurement after it: the
  // trace and whatever is compared with the clip. Repaired on a copy here.
  auto glitches = findBvhGlitches(clip);
  if (!glitches) return Error{glitches.error()};
  if (!glitches->empty()) {
    BvhClip repaired = clip;
    if (auto r = repairBvhGlitches(repaired); !r) return Error{r.error()};
    return bvhToTrace(repaired, options, mappingOut);
  }
  auto body = avatar::analyseBvhBody(clip, options.body);
  if (!body) return Error{body.error()};
  BvhMapping m;
  m.body = std::move(*body);
  m.joint = bvhTrackerJoints(m.body.humanoid);
  if (auto s = checkTrackers(clip, options, m); !s.ok()) return Error{s.error()};
  m.heightUnits = m.body.heightUnits;
  if (auto s = checkScale(options, m.heightUnits); !s.ok()) return Error{s.error()};
  m.scale = options.scale > 0.0 ? options.scale : options.userHeight / m.heightUnits;
  m.upAxis = m.body.upAxis;
  m.facingAxis = m.body.forwardAxis;
  m.notes.insert(m.notes.begin(), mappingNote(clip, m, options));
  for (const auto& n : m.body.notes) m.notes.push_back(n);
  for (const auto& n : m.body.humanoid.notes) m.notes.push_back(n);
  const References ref = references(clip, m);
  double floorY = 0.0;
  Trace trace = sampleFrames(clip, m, ref, floorY);
  trace.userHeight = options.userHeight;
  const glm::vec3 shift = placeOnFloor(trace, floorY, options);
  m.toXr = m.body.toXr;
  m.shift = glm::dvec3(shift);
  m.firstFrame = m.body.firstFrame;
  restReferences(clip, ref, capEyeHeight(trace, m.heightUnits * m.scale), m);
  for (const auto& w : clip.warnings) m.notes.push_back(w);
  trace.notes = m.notes;
  if (mappingOut) *mappingOut = std::move(m);
  return trace;
}

Result<std::unique_ptr<TraceSource>> openBvhSource(const std::string& path, const BvhTrackerOptions& options,
                                                   BvhMapping* mapping) {
  // Before the file: a bad --user-height is not the clip's fault.
  if (auto s = checkUserHeight(options.userHeight); !s.ok()) return Error{s.error()};
  auto clip = avatar::loadBvh(path);
  if (!clip) return Error{clip.error()};
  auto trace = bvhToTrace(*clip, options, mapping);
  if (!trace) return Error{path + ": " + trace.error()};
  trace->source = path;
  return std::make_unique<TraceSource>(std::move(*trace), path);
}

}  // namespace embody::tracking
