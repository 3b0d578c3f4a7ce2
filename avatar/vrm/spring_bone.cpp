// SpringBoneJob: the VRMC_springBone reference algorithm at a fixed sub-step.
#include "avatar/vrm/spring_bone.h"

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

namespace embody::avatar {

namespace {

bool finite(const glm::vec3& v) { return std::isfinite(v.x + v.y + v.z); }

glm::mat4 localMatrix(const glm::vec3& t, const glm::quat& r, const glm::vec3& s) {
  return glm::scale(glm::translate(glm::mat4(1.0f), t) * glm::mat4_cast(r), s);
}

// Rotation turning unit vector a onto unit vector b (the shortest arc; any half turn when opposite).
glm::quat fromTo(const glm::vec3& a, const glm::vec3& b) {
  const float d = glm::dot(a, b);
  if (d < -0.999999f) {
    glm::vec3 axis = glm::cross(glm::vec3(1.0f, 0.0f, 0.0f), a);
    if (glm::dot(axis, axis) < 1e-8f) axis = glm::cross(glm::vec3(0.0f, 1.0f, 0.0f), a);
    return glm::angleAxis(glm::pi<float>(), glm::normalize(axis));
  }
  const glm::vec3 c = glm::cross(a, b);
  return glm::normalize(glm::quat(1.0f + d, c.x, c.y, c.z));
}

// Moves `tail` out of one collider (and back to the bone's length from `origin`).
glm::vec3 collide(const SpringCollider& c, const glm::mat4& g, glm::vec3 tail, glm::vec3 origin, float length,
                  float hitRadius) {
  const glm::vec3 a(g * glm::vec4(c.offset, 1.0f));
  glm::vec3 centre = a;
  if (c.shape == SpringCollider::Shape::Capsule) {
    const glm::vec3 b(g * glm::vec4(c.tail, 1.0f));
    const glm::vec3 ab = b - a;
    const float len2 = glm::dot(ab, ab);
    const float t = len2 > 1e-12f ? glm::clamp(glm::dot(tail - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
    centre = a + t * ab;
  }
  const float scale = glm::length(glm::vec3(g[0]));  // collider radii follow their node's scale
  const glm::vec3 d = tail - centre;
  const float dl = glm::length(d);
  const float dist = dl - c.radius * scale - hitRadius;
  if (dist >= 0.0f || dl < 1e-9f) return tail;
  tail -= (d / dl) * dist;
  const glm::vec3 dir = tail - origin;
  const float l = glm::length(dir);
  return l > 1e-9f ? origin + dir * (length / l) : tail;
}

}  // namespace

void SpringBoneState::resize(const SpringBoneSetup& setup, size_t skeletonJoints) {
  const size_t n = setup.jointCount();
  prevTail.assign(n, glm::vec3(0.0f));
  currentTail.assign(n, glm::vec3(0.0f));
  restAxis.assign(n, glm::vec3(0.0f, 1.0f, 0.0f));
  boneLength.assign(n, 0.0f);
  globals.assign(skeletonJoints, glm::mat4(1.0f));
  springOfJoint.assign(skeletonJoints, -1);
  chainOfSpring.assign(n, 0);
  indexInChain.assign(n, 0);
  size_t k = 0;
  for (size_t c = 0; c < setup.chains.size(); ++c)
    for (size_t i = 0; i < setup.chains[c].joints.size(); ++i, ++k) {
      const int j = setup.chains[c].joints[i].joint;
      if (j >= 0 && static_cast<size_t>(j) < skeletonJoints) springOfJoint[static_cast<size_t>(j)] = static_cast<int>(k);
      chainOfSpring[k] = static_cast<int>(c);
      indexInChain[k] = static_cast<int>(i);
    }
  accumulator = 0.0;
  initialized = false;
}

bool SpringBoneJob::Validate() const {
  if (!setup || !skeleton || !pose || !state) return false;
  const size_t n = skeleton->joints.size();
  if (pose->local.size() != n || globals.size() != n || state->globals.size() != n || state->springOfJoint.size() != n ||
      state->currentTail.size() != setup->jointCount())
    return false;
  if (!(deltaTime >= 0.0) || !std::isfinite(deltaTime) || !(stepSeconds > 0.0) || maxStepsPerRun < 0) return false;
  if (rootJoint < 0 || static_cast<size_t>(rootJoint) >= n) return false;
  for (const SpringChain& c : setup->chains) {
    for (const SpringJoint& j : c.joints)
      if (j.joint < 0 || static_cast<size_t>(j.joint) >= n || j.child >= static_cast<int>(n)) return false;
    for (int k : c.colliders)
      if (k < 0 || static_cast<size_t>(k) >= setup->colliders.size()) return false;
    if (c.center >= static_cast<int>(n)) return false;
  }
  for (const SpringCollider& c : setup->colliders)
    if (c.joint < 0 || static_cast<size_t>(c.joint) >= n) return false;
  return true;
}

namespace {

// What one Run needs while walking the skeleton.
struct Walk {
  const SpringBoneJob& job;
  SpringBoneState& s;

  glm::mat4 parentGlobal(int j) const {
    const int p = job.skeleton->joints[static_cast<size_t>(j)].parent;
    return p < 0 ? glm::mat4(1.0f) : s.globals[static_cast<size_t>(p)];
  }
  // The joint's global with its rest rotation (its pose translation and scale).
  glm::mat4 restRotated(int j) const {
    const Transform& t = job.pose->local[static_cast<size_t>(j)];
    return parentGlobal(j) * localMatrix(t.translation, job.skeleton->joints[static_cast<size_t>(j)].rest.rotation, t.scale);
  }
  glm::mat4 centre(int chain) const {
    const int c = job.setup->chains[static_cast<size_t>(chain)].center;
    return c < 0 ? glm::mat4(1.0f) : s.globals[static_cast<size_t>(c)];
  }

  // Tails at rest, no velocity (globals must hold the frame's pose with rest spring rotations).
  void initialise() {
    for (size_t j = 0; j < s.globals.size(); ++j) {
      const int k = s.springOfJoint[j];
      s.globals[j] = k < 0 ? parentGlobal(static_cast<int>(j)) * job.pose->local[j].matrix() : restRotated(static_cast<int>(j));
      if (k < 0) continue;
      const SpringJoint& sj = jointOf(k);
      const glm::vec3 tl = sj.tail;
      const float len = glm::length(tl);
      s.restAxis[static_cast<size_t>(k)] = len > 1e-9f ? tl / len : glm::vec3(0.0f, 1.0f, 0.0f);
      const glm::vec3 origin(s.globals[j][3]);
      const glm::vec3 tail(s.globals[j] * glm::vec4(len > 1e-9f ? tl : s.restAxis[static_cast<size_t>(k)] * 1e-3f, 1.0f));
      s.boneLength[static_cast<size_t>(k)] = glm::length(tail - origin);
      const glm::vec3 inCentre(glm::inverse(centre(s.chainOfSpring[static_cast<size_t>(k)])) * glm::vec4(tail, 1.0f));
      s.prevTail[static_cast<size_t>(k)] = s.currentTail[static_cast<size_t>(k)] = inCentre;
    }
    s.initialized = true;
  }

  const SpringJoint& jointOf(int k) const {
    const SpringChain& c = job.setup->chains[static_cast<size_t>(s.chainOfSpring[static_cast<size_t>(k)])];
    return c.joints[static_cast<size_t>(s.indexInChain[static_cast<size_t>(k)])];
  }

  // One joint: integrate (dt > 0) or only re-aim at the current tail (dt == 0); writes globals.
  // Returns false on a non-finite result.
  bool updateJoint(int j, int k, float dt) {
    const SpringJoint& sj = jointOf(k);
    const size_t ks = static_cast<size_t>(k);
    const int chainIndex = s.chainOfSpring[ks];
    const glm::mat4 g = restRotated(j);
    const glm::vec3 origin(g[3]);
    const glm::mat4 c = centre(chainIndex);
    glm::vec3 tail(c * glm::vec4(s.currentTail[ks], 1.0f));
    if (dt > 0.0f) {
      const SpringJointSettings& p = sj.settings;
      const glm::vec3 prev(c * glm::vec4(s.prevTail[ks], 1.0f));
      const glm::vec3 restDir = glm::normalize(glm::mat3(g) * s.restAxis[ks]);
      glm::vec3 next = tail + (tail - prev) * (1.0f - p.dragForce) + dt * p.stiffness * restDir +
                       dt * p.gravityPower * p.gravityDir;
      const glm::vec3 dir = next - origin;
      const float l = glm::length(dir);
      next = origin + (l > 1e-9f ? dir / l : restDir) * s.boneLength[ks];
      for (int ci : job.setup->chains[static_cast<size_t>(chainIndex)].colliders) {
        const SpringCollider& col = job.setup->colliders[static_cast<size_t>(ci)];
        next = collide(col, s.globals[static_cast<size_t>(col.joint)], next, origin, s.boneLength[ks], p.hitRadius);
      }
      if (!finite(next)) return false;
      const glm::mat4 inv = glm::inverse(c);
      s.prevTail[ks] = glm::vec3(inv * glm::vec4(tail, 1.0f));
      s.currentTail[ks] = glm::vec3(inv * glm::vec4(next, 1.0f));
      tail = next;
    }
    const glm::vec3 to(glm::inverse(g) * glm::vec4(tail, 1.0f));
    const float tl = glm::length(to);
    const glm::quat rest = job.skeleton->joints[static_cast<size_t>(j)].rest.rotation;
    const glm::quat r = tl > 1e-9f ? glm::normalize(rest * fromTo(s.restAxis[ks], to / tl)) : rest;
    if (!std::isfinite(r.w + r.x + r.y + r.z)) return false;
    Transform& t = job.pose->local[static_cast<size_t>(j)];
    t.rotation = r;
    s.globals[static_cast<size_t>(j)] = parentGlobal(j) * t.matrix();
    return true;
  }

  // One pass over the skeleton in order (parents first): spring joints step, others follow.
  bool pass(float dt) {
    for (size_t j = 0; j < s.globals.size(); ++j) {
      const int k = s.springOfJoint[j];
      if (k < 0) {
        s.globals[j] = parentGlobal(static_cast<int>(j)) * job.pose->local[j].matrix();
      } else if (!updateJoint(static_cast<int>(j), k, dt)) {
        return false;
      }
    }
    return true;
  }
};

bool jumped(const glm::mat4& a, const glm::mat4& b, float distance, float angle) {
  if (glm::length(glm::vec3(a[3]) - glm::vec3(b[3])) > distance) return true;
  const glm::vec3 za = glm::normalize(glm::vec3(a[2])), zb = glm::normalize(glm::vec3(b[2]));
  const glm::vec3 ya = glm::normalize(glm::vec3(a[1])), yb = glm::normalize(glm::vec3(b[1]));
  const float cosLimit = std::cos(angle);
  return glm::dot(za, zb) < cosLimit || glm::dot(ya, yb) < cosLimit;
}

}  // namespace

bool SpringBoneJob::Run() {
  stepsRun = 0;
  wasReset = false;
  if (!Validate()) return false;
  SpringBoneState& s = *state;
  if (setup->chains.empty()) return true;
  std::copy(globals.begin(), globals.end(), s.globals.begin());
  Walk walk{*this, s};
  const glm::mat4& root = globals[static_cast<size_t>(rootJoint)];
  if (!s.initialized || reset || jumped(root, s.lastRoot, teleportDistance, teleportAngle)) {
    walk.initialise();
    s.accumulator = 0.0;
    wasReset = true;
  }
  s.lastRoot = root;
  s.accumulator += deltaTime;
  int steps = static_cast<int>(s.accumulator / stepSeconds);
  if (steps > maxStepsPerRun) {  // a long stall: simulate the cap, drop the rest of the backlog
    steps = maxStepsPerRun;
    s.accumulator = 0.0;
  } else {
    s.accumulator -= steps * stepSeconds;
  }
  bool ok = true;
  for (int i = 0; i < steps && ok; ++i) {
    ok = walk.pass(static_cast<float>(stepSeconds));
    ++stepsRun;
  }
  if (steps == 0) ok = walk.pass(0.0f);  // no step due: aim at the tails under this frame's pose
  if (!ok) {  // never publish NaN: back to rest, start over next frame
    std::copy(globals.begin(), globals.end(), s.globals.begin());
    walk.initialise();
    walk.pass(0.0f);
    wasReset = true;
  }
  return true;
}

}  // namespace embody::avatar
