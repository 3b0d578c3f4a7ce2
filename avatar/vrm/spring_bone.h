#pragma once
// VRM spring bones: hair, skirts and accessories that swing after the body moves.
//
// Data: VRM 1.0 `VRMC_springBone` (springs of joints, sphere and capsule colliders, collider
// groups, a centre node) and VRM 0.x `VRM.secondaryAnimation` (bone groups whose every root
// subtree sways, sphere colliders) are both read into one SpringBoneSetup of joint chains.
//
// Simulation: the reference algorithm of the VRMC_springBone specification (as UniVRM and
// three-vrm implement it): per joint, the tail's verlet step
//   next = cur + (cur - prev) * (1 - drag) + dt * stiffness * restDirection + dt * gravityPower * gravityDir
// held at the bone's length from the joint, pushed out of colliders, then the joint is turned so
// that its rest axis points at the tail. Inertia lives in the centre node's space when a chain
// has one. SpringBoneJob runs it at a fixed sub-step (default 120 Hz) after IK and before
// skinning, allocation-free once its SpringBoneState is sized.
#include <span>
#include <string>
#include <vector>

#include "avatar/skeleton.h"

namespace embody::avatar {

struct SpringCollider {
  enum class Shape { Sphere, Capsule };
  int joint = -1;  // the joint the collider rides on
  Shape shape = Shape::Sphere;
  glm::vec3 offset{0.0f};  // centre (sphere) or start (capsule), in the joint's frame
  glm::vec3 tail{0.0f};    // capsule end, in the joint's frame
  float radius = 0.0f;
};

struct SpringJointSettings {
  float stiffness = 1.0f;     // VRM 1.0 default
  float dragForce = 0.5f;     // 0..1
  float gravityPower = 0.0f;
  glm::vec3 gravityDir{0.0f, -1.0f, 0.0f};  // world (model) space, unit length
  float hitRadius = 0.0f;
};

// One swinging joint: it turns so that its rest axis (towards `child`, or a virtual tail when
// child < 0) follows the simulated tail.
struct SpringJoint {
  int joint = -1;
  int child = -1;         // the tail joint (a child or a deeper descendant), -1 for a virtual tail
  glm::vec3 tail{0.0f};   // the tail in the joint's rest frame (VRM 0.x leaves: 7 cm along its own offset)
  SpringJointSettings settings;
};

struct SpringChain {
  std::string name;
  std::vector<SpringJoint> joints;  // parents before children
  std::vector<int> colliders;       // indices into SpringBoneSetup::colliders
  int center = -1;                  // joint whose space holds the inertia, -1: world
};

struct SpringBoneSetup {
  std::vector<SpringCollider> colliders;
  std::vector<SpringChain> chains;
  size_t jointCount() const;
  bool empty() const { return chains.empty(); }
};

// Per-joint simulation state (world or centre space), sized once for a setup.
struct SpringBoneState {
  std::vector<glm::vec3> prevTail, currentTail;  // per joint of every chain, chain after chain
  std::vector<glm::vec3> restAxis;               // unit tail direction in the joint's rest frame
  std::vector<float> boneLength;                 // rest tail distance (world units at rest)
  std::vector<glm::mat4> globals;                // scratch: the pose's globals as the job updates them
  std::vector<int> springOfJoint;                // skeleton joint -> flat spring joint index, -1
  std::vector<int> chainOfSpring, indexInChain;  // flat spring joint -> chain, index in it
  glm::mat4 lastRoot{1.0f};
  double accumulator = 0.0;
  bool initialized = false;
  void resize(const SpringBoneSetup& setup, size_t skeletonJoints);
};

// ozz-style job: the pose after IK in, the pose with the spring joints' local rotations replaced
// out (in place). Run() performs as many fixed sub-steps as `deltaTime` holds (the remainder
// carries over) and re-initialises the state (tails at rest, no velocity) on the first run, on
// `reset`, when the root joint jumps more than `teleportDistance` or turns more than
// `teleportAngle` in one frame, or when the state would become non-finite.
struct SpringBoneJob {
  const SpringBoneSetup* setup = nullptr;
  const Skeleton* skeleton = nullptr;
  SkeletonPose* pose = nullptr;                       // in/out
  std::span<const glm::mat4> globals;                 // the pose's globals before the job
  SpringBoneState* state = nullptr;
  double deltaTime = 0.0;                             // seconds since the last Run
  double stepSeconds = 1.0 / 120.0;                   // fixed sub-step
  int maxStepsPerRun = 12;                            // a longer frame is simulated as this many steps
  int rootJoint = 0;                                  // watched for teleports (the hips)
  float teleportDistance = 1.0f;                      // metres per frame of the root joint
  float teleportAngle = 1.0f;                         // radians per frame of the root joint
  bool reset = false;
  // Outputs.
  int stepsRun = 0;
  bool wasReset = false;

  bool Validate() const;
  bool Run();
};

}  // namespace embody::avatar
