#include "tests/support/sample_models.h"

#include <cmath>
#include <string>

#include "core/angles.h"

namespace embody::test {
using namespace embody::ik;  // a fixture of the IK library: its vocabulary throughout
namespace {

Eigen::Isometry3d at(double x, double y, double z) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(x, y, z);
  return t;
}

void limits(ModelBuilder& b, JointId j, std::initializer_list<std::pair<double, double>> degrees) {
  int k = 0;
  for (const auto& [lo, hi] : degrees) b.setLimits({j, k++}, lo * kDeg, hi * kDeg);
}

TaskDesc poseTask(const std::string& name, JointId joint, int level, const Eigen::Vector3d& offset) {
  return {.name = name, .type = TaskType::Pose, .joint = joint, .offset = offset, .level = level};
}

}  // namespace

Result<Model> sampleHumanoid() {
  ModelBuilder b;
  const JointId hips = b.addJoint("hips", kNoParent, JointType::Free, at(0, 0.95, 0));
  b.setSegment(hips, 11.0, {0, 0.05, 0});
  // Spine and head.
  JointId parent = hips;
  const char* spine[] = {"lumbar1", "lumbar2", "thorax1", "thorax2", "chest", "neck", "head"};
  const double rise[] = {0.08, 0.08, 0.09, 0.09, 0.10, 0.18, 0.10};
  const double mass[] = {4.0, 4.0, 5.0, 5.0, 8.0, 1.5, 5.0};
  JointId chest = 0, head = 0;
  for (int i = 0; i < 7; ++i) {
    const JointId j = b.addJoint(spine[i], parent, JointType::Ball, at(0, rise[i], 0));
    if (i < 5) limits(b, j, {{-20, 20}, {-20, 20}, {-15, 15}});
    else limits(b, j, {{-40, 40}, {-50, 50}, {-35, 35}});
    b.setSegment(j, mass[i], {0, 0.05, 0});
    parent = j;
    if (i == 4) chest = j;
    if (i == 6) head = j;
  }
  const JointId headEnd = b.addJoint("head_end", head, JointType::Fixed, at(0, 0.12, 0.02));
  // Arms: side = +1 left (x > 0), -1 right.
  JointId hands[2] = {0, 0};
  for (int s = 0; s < 2; ++s) {
    const double side = s == 0 ? 1.0 : -1.0;
    const std::string p = s == 0 ? "left_" : "right_";
    const JointId clav = b.addJoint(p + "clavicle", chest, JointType::Swing, at(side * 0.03, 0.10, 0.02),
                                    Eigen::Vector3d::UnitX());
    limits(b, clav, {{-15, 15}, {-15, 15}});
    b.setSegment(clav, 1.0, {side * 0.07, 0, 0});
    const JointId shoulder = b.addJoint(p + "shoulder", clav, JointType::Ball, at(side * 0.15, 0, 0));
    limits(b, shoulder, {{-90, 90}, {-90, 90}, {-90, 90}});
    b.setSegment(shoulder, 2.0, {side * 0.14, 0, 0});
    const JointId elbow = b.addJoint(p + "elbow", shoulder, JointType::Revolute, at(side * 0.28, 0, 0),
                                     Eigen::Vector3d::UnitY());
    b.setLimits({elbow, 0}, side > 0 ? 0.0 : -150 * kDeg, side > 0 ? 150 * kDeg : 0.0);
    b.setNeutral({elbow, 0}, side * 30 * kDeg);  // slightly bent: a straight arm is singular
    const JointId twist = b.addJoint(p + "forearm", elbow, JointType::Revolute, at(side * 0.12, 0, 0),
                                     Eigen::Vector3d::UnitX());
    limits(b, twist, {{-80, 80}});
    b.setSegment(twist, 1.2, {side * 0.06, 0, 0});
    const JointId wrist = b.addJoint(p + "wrist", twist, JointType::Swing, at(side * 0.13, 0, 0),
                                     Eigen::Vector3d::UnitX());
    limits(b, wrist, {{-60, 60}, {-60, 60}});
    b.setSegment(wrist, 0.5, {side * 0.08, 0, 0});
    hands[s] = b.addJoint(p + "hand_end", wrist, JointType::Fixed, at(side * 0.09, 0, 0));
  }
  // Legs.
  JointId ankles[2] = {0, 0};
  for (int s = 0; s < 2; ++s) {
    const double side = s == 0 ? 1.0 : -1.0;
    const std::string p = s == 0 ? "left_" : "right_";
    const JointId hip = b.addJoint(p + "hip", hips, JointType::Ball, at(side * 0.09, -0.05, 0));
    limits(b, hip, {{-100, 30}, {-40, 40}, {-45, 45}});
    b.setSegment(hip, 8.0, {0, -0.2, 0});
    const JointId knee = b.addJoint(p + "knee", hip, JointType::Revolute, at(0, -0.43, 0), Eigen::Vector3d::UnitX());
    limits(b, knee, {{0, 140}});
    b.setNeutral({knee, 0}, 15 * kDeg);
    b.setNeutral({hip, 0}, -8 * kDeg);
    b.setSegment(knee, 3.5, {0, -0.2, 0});
    const JointId ankle = b.addJoint(p + "ankle", knee, JointType::Ball, at(0, -0.42, 0));
    limits(b, ankle, {{-45, 30}, {-25, 25}, {-25, 25}});
    b.setNeutral({ankle, 0}, -7 * kDeg);
    b.setSegment(ankle, 1.0, {0, -0.04, 0.06});
    const JointId toes = b.addJoint(p + "toes", ankle, JointType::Revolute, at(0, -0.06, 0.14), Eigen::Vector3d::UnitX());
    limits(b, toes, {{-40, 40}});
    b.setSegment(toes, 0.2, {0, 0, 0.03});
    ankles[s] = ankle;
  }
  b.addTask(poseTask("left_foot", ankles[0], 0, {0, -0.06, 0.05}));
  b.addTask(poseTask("right_foot", ankles[1], 0, {0, -0.06, 0.05}));
  TaskDesc com;
  com.name = "com";
  com.type = TaskType::CenterOfMass;
  com.level = 1;
  b.addTask(com);
  b.addTask(poseTask("head", headEnd, 2, Eigen::Vector3d::Zero()));
  b.addTask(poseTask("left_hand", hands[0], 3, Eigen::Vector3d::Zero()));
  b.addTask(poseTask("right_hand", hands[1], 3, Eigen::Vector3d::Zero()));
  return b.build();
}

Result<Model> sampleSpine(bool coupled) {
  ModelBuilder b;
  const JointId pelvis = b.addJoint("pelvis", kNoParent, JointType::Fixed, at(0, 1.0, 0));
  b.setSegment(pelvis, 10.0, Eigen::Vector3d::Zero());
  struct Region {
    const char* name;
    int count;
    double spacing;
    double range_deg;  // per-level range of each component
  };
  const Region regions[] = {{"l", 5, 0.035, 12}, {"t", 12, 0.022, 5}, {"c", 7, 0.016, 12}};
  JointId parent = pelvis;
  JointId chest = 0;
  for (int r = 0; r < 3; ++r) {
    const Region& region = regions[r];
    JointId prevSwing = -1, prevTwist = -1;
    for (int i = 0; i < region.count; ++i) {
      // Two torsion (revolute) vertebrae per region, the others swing.
      const bool twist = i == 1 || i == region.count - 2;
      const std::string name = std::string("v") + region.name + std::to_string(region.count - i);
      const JointId j = b.addJoint(name, parent, twist ? JointType::Revolute : JointType::Swing,
                                   at(0, region.spacing, 0), Eigen::Vector3d::UnitY());
      // Ranges vary a little along the region so the coupling ratios are not all 1.
      const double range = region.range_deg * (0.8 + 0.4 * i / std::max(1, region.count - 1)) * kDeg;
      b.setSegment(j, 1.0, {0, region.spacing / 2, 0});
      if (twist) {
        b.setLimits({j, 0}, -range, range);
        if (coupled && prevTwist >= 0) {
          const double ratio = range / b.joints()[prevTwist].upper[0];
          b.addEquality(name + " torsion", {j, 0}, 1.0, {prevTwist, 0}, -ratio);
        }
        prevTwist = j;
      } else {
        b.setLimits({j, 0}, -range, range);
        b.setLimits({j, 1}, -range, range);
        if (coupled && prevSwing >= 0) {
          const double ratio = range / b.joints()[prevSwing].upper[0];
          b.addEquality(name + " flexion", {j, 0}, 1.0, {prevSwing, 0}, -ratio);
          b.addEquality(name + " bending", {j, 1}, 1.0, {prevSwing, 1}, -ratio);
        }
        prevSwing = j;
      }
      parent = j;
    }
    if (r == 1) chest = parent;
  }
  const JointId head = b.addJoint("head", parent, JointType::Fixed, at(0, 0.10, 0.02));
  b.setSegment(head, 5.0, {0, 0.05, 0});
  b.addTask({.name = "head_orientation", .type = TaskType::Orientation, .joint = head, .level = 0});
  b.addTask({.name = "head_position", .type = TaskType::Position, .joint = head, .level = 1});
  b.addTask({.name = "chest_orientation", .type = TaskType::Orientation, .joint = chest, .level = 2});
  return b.build();
}

const ik::Model& sharedSampleHumanoid() {
  static const ik::Model m = sampleHumanoid().value();
  return m;
}

const ik::Model& sharedSampleSpine(bool coupled) {
  static const ik::Model coupledModel = sampleSpine(true).value(), uncoupledModel = sampleSpine(false).value();
  return coupled ? coupledModel : uncoupledModel;
}

}  // namespace embody::test
