#include "tracking/tracker.h"

#include <cmath>

namespace embody::tracking {

namespace {
constexpr std::array<std::string_view, kTrackerCount> kKeys = {"head", "left", "right", "hips", "left_foot",
                                                                "right_foot"};

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool finite(const glm::quat& q) {
  return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w);
}
}  // namespace

std::string_view trackerKey(TrackerId id) { return kKeys[static_cast<size_t>(index(id))]; }

std::optional<TrackerId> trackerFromKey(std::string_view key) {
  for (auto id : kAllTrackers)
    if (trackerKey(id) == key) return id;
  return std::nullopt;
}

TrackerMask PoseSample::validMask() const {
  TrackerMask m;
  for (auto id : kAllTrackers) m.set(id, (*this)[id].valid);
  return m;
}

bool isUsable(const TrackerPose& pose) {
  if (!finite(pose.position) || !finite(pose.orientation)) return false;
  const float n2 = glm::dot(pose.orientation, pose.orientation);
  // A unit quaternion written with a few digits has a norm near 1; anything far off is garbage.
  return n2 > 0.25f && n2 < 4.0f;
}

void sanitize(PoseSample& sample) {
  for (auto& t : sample.trackers) {
    if (!t.valid) continue;
    if (!isUsable(t)) {
      t.valid = false;
      continue;
    }
    t.orientation = glm::normalize(t.orientation);
  }
}

glm::quat gripOrientation(Side side, const glm::vec3& fingers, const glm::vec3& palmFacing) {
  const glm::vec3 d = glm::normalize(fingers);
  glm::vec3 p = palmFacing - d * glm::dot(palmFacing, d);
  if (glm::length(p) < 1e-6f) {  // palm direction along the fingers: pick any perpendicular
    p = std::abs(d.y) < 0.9f ? glm::cross(d, glm::vec3(0, 1, 0)) : glm::cross(d, glm::vec3(1, 0, 0));
  }
  p = glm::normalize(p);
  // Left: X = -palm, Y = fingers, Z = fingers x palm. Right: X = palm, Y = fingers, Z = palm x fingers.
  const glm::vec3 x = side == Side::Left ? -p : p;
  const glm::vec3 y = d;
  const glm::vec3 z = glm::cross(x, y);
  return glm::normalize(glm::quat_cast(glm::mat3(x, y, z)));
}

glm::quat restGripOrientation(Side side, const glm::vec3& forearm) {
  const glm::vec3 fingers = glm::length(forearm) > 1e-9f ? glm::normalize(forearm)
                                                        : glm::vec3(side == Side::Left ? -1.0f : 1.0f, 0.0f, 0.0f);
  const glm::vec3 palm = std::abs(fingers.y) < 0.7f ? glm::vec3(0, -1, 0)
                                                     : glm::vec3(side == Side::Left ? 1.0f : -1.0f, 0.0f, 0.0f);
  return gripOrientation(side, fingers, palm);
}

glm::quat headingOf(const glm::quat& orientation) {
  const glm::vec3 fwd = orientation * glm::vec3(0, 0, -1);
  const glm::vec3 up = orientation * glm::vec3(0, 1, 0);
  // Looking down, the head's up vector points forward: blend it in so the heading stays defined.
  glm::vec3 f(fwd.x - fwd.y * up.x, 0.0f, fwd.z - fwd.y * up.z);
  if (glm::dot(f, f) < 1e-12f) return glm::quat(1, 0, 0, 0);
  const float yaw = std::atan2(-f.x, -f.z);
  return glm::angleAxis(yaw, glm::vec3(0, 1, 0));
}

glm::mat4 Pose::matrix() const {
  glm::mat4 m = glm::mat4_cast(orientation);
  m[3] = glm::vec4(position, 1.0f);
  return m;
}

Pose Pose::operator*(const Pose& b) const {
  return {position + orientation * b.position, glm::normalize(orientation * b.orientation)};
}

Pose Pose::inverse() const {
  const glm::quat qi = glm::conjugate(orientation);
  return {qi * -position, qi};
}

TrackerPose interpolate(const TrackerPose& a, const TrackerPose& b, float t) {
  TrackerPose r;
  r.position = glm::mix(a.position, b.position, t);
  glm::quat qb = b.orientation;
  if (glm::dot(a.orientation, qb) < 0.0f) qb = -qb;
  r.orientation = glm::normalize(glm::slerp(a.orientation, qb, t));
  r.valid = a.valid;
  return r;
}

}  // namespace embody::tracking
