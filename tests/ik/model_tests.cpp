// ModelBuilder validation and the recruiting rules (pik.md eqs. 3-5), after ozz's habit of one
// test that tries every invalid input.
#include <catch2/catch.hpp>

#include "ik/model.h"
#include "ik/solver.h"
#include "tests/support/sample_models.h"

using namespace embody;
using namespace embody::ik;

namespace {

Eigen::Isometry3d up(double y) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation().y() = y;
  return t;
}

// root (free) - spine1 (swing) - spine2 (swing) - neck (ball) - head (fixed)
//                             \- arm (ball) - hand (fixed)
struct Chain {
  ModelBuilder b;
  JointId root, spine1, spine2, neck, head, arm, hand;
  Chain() {
    root = b.addJoint("root", kNoParent, JointType::Free);
    spine1 = b.addJoint("spine1", root, JointType::Swing, up(0.1), Eigen::Vector3d::UnitY());
    spine2 = b.addJoint("spine2", spine1, JointType::Swing, up(0.1), Eigen::Vector3d::UnitY());
    neck = b.addJoint("neck", spine2, JointType::Ball, up(0.1));
    head = b.addJoint("head", neck, JointType::Fixed, up(0.1));
    arm = b.addJoint("arm", spine1, JointType::Ball, up(0.05));
    hand = b.addJoint("hand", arm, JointType::Fixed, up(0.3));
    for (JointId j : {root, spine1, spine2, neck, head, arm, hand}) b.setSegment(j, 1.0, Eigen::Vector3d::Zero());
  }
  TaskDesc task(const std::string& name, JointId joint, int level) {
    TaskDesc t;
    t.name = name;
    t.joint = joint;
    t.level = level;
    return t;
  }
};

std::string buildError(const ModelBuilder& b) {
  embody::Result<Model> m = b.build();
  return m ? std::string() : m.error();
}

}  // namespace

TEST_CASE("model layout: dofs, limits as inequality rows (user couplings first), levels sorted") {
  Chain c;
  c.b.setLimits({c.neck, 1}, -0.5, 0.7);
  c.b.addInequality({"user", {{{c.spine1, 0}, 1.0}, {{c.spine2, 0}, -1.0}}, 0.1, InequalityKind::UserCoupling});
  c.b.addTask(c.task("hand", c.hand, 5));
  c.b.addTask(c.task("head", c.head, -2));
  const Model m = c.b.build().value();
  CHECK(m.dofs == 6 + 2 + 2 + 3 + 3);
  CHECK(m.joints[c.neck].first_dof == 10);
  REQUIRE(m.inequalities.size() == 3);
  CHECK(m.inequalities[0].name == "user");
  CHECK(m.inequalities[1].kind == InequalityKind::JointLimit);
  CHECK(m.inequalities[1].rhs == 0.7);
  CHECK(m.inequalities[2].rhs == 0.5);  // -q <= 0.5
  REQUIRE(m.levels.size() == 2);
  CHECK(m.levels[0].priority == -2);
  CHECK(m.tasks[m.findTask("head")].first_row == 0);
  CHECK(m.tasks[m.findTask("hand")].first_row == 3);
  CHECK(m.dofName(11) == "neck[1]");
  // Exp-map joints without constraint rows may be re-parameterised; constrained ones may not.
  CHECK(m.joints[c.root].reparameterize);
  CHECK_FALSE(m.joints[c.neck].reparameterize);
  CHECK_FALSE(m.joints[c.spine1].reparameterize);
  // Swing basis: orthonormal and orthogonal to the twist axis.
  const auto& basis = m.joints[c.spine1].swing_basis;
  CHECK(std::abs(basis.col(0).dot(Eigen::Vector3d::UnitY())) < 1e-12);
  CHECK(std::abs(basis.col(1).dot(Eigen::Vector3d::UnitY())) < 1e-12);
  CHECK(std::abs(basis.col(0).dot(basis.col(1))) < 1e-12);
}

TEST_CASE("ModelBuilder rejects every invalid input with a readable error") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto expectError = [](const ModelBuilder& b, const std::string& fragment) {
    const std::string e = buildError(b);
    INFO("error: " << e);
    CHECK(e.find(fragment) != std::string::npos);
  };
  { ModelBuilder b; expectError(b, "no joints"); }
  { Chain c; c.b.addJoint("bad", 42, JointType::Ball); expectError(c.b, "parent 42"); }
  { Chain c; c.b.addJoint("root", c.root, JointType::Ball); expectError(c.b, "duplicate name"); }
  { Chain c; c.b.addJoint("", c.root, JointType::Ball); expectError(c.b, "empty name"); }
  { Chain c; Eigen::Isometry3d t = Eigen::Isometry3d::Identity(); t.translation().x() = nan;
    c.b.addJoint("nan", c.root, JointType::Ball, t); expectError(c.b, "not finite"); }
  { Chain c; Eigen::Isometry3d t = Eigen::Isometry3d::Identity(); t.linear() *= 2;
    c.b.addJoint("scaled", c.root, JointType::Ball, t); expectError(c.b, "not a rotation"); }
  { Chain c; c.b.addJoint("axis", c.root, JointType::Revolute, Eigen::Isometry3d::Identity(), Eigen::Vector3d::Zero());
    expectError(c.b, "axis"); }
  { Chain c; c.b.setLimits({c.neck, 0}, 1.0, -1.0); expectError(c.b, "not an interval"); }
  { Chain c; c.b.setLimits({c.neck, 3}, -1.0, 1.0); expectError(c.b, "limits need 3"); }
  { Chain c; c.b.setSegment(c.neck, -1.0, Eigen::Vector3d::Zero()); expectError(c.b, "mass"); }
  { Chain c; c.b.setNeutral({c.neck, 0}, nan); expectError(c.b, "neutral"); }
  { Chain c; c.b.addEquality("e", {c.head, 0}, 1.0, {c.neck, 0}, 1.0); expectError(c.b, "has no dof 0"); }
  { Chain c; c.b.addEquality("e", {99, 0}, 1.0, {c.neck, 0}, 1.0); expectError(c.b, "does not exist"); }
  { Chain c; c.b.addEquality("e", {c.neck, 0}, nan, {c.neck, 1}, 1.0); expectError(c.b, "coefficient"); }
  { Chain c; c.b.addEquality("e", {c.neck, 0}, 1.0, {c.neck, 0}, -1.0); expectError(c.b, "all coefficients are zero"); }
  { Chain c; c.b.addInequality({"i", {}, 0.0, InequalityKind::UserCoupling}); expectError(c.b, "no terms"); }
  { Chain c; c.b.addInequality({"i", {{{c.neck, 0}, 1.0}}, nan, InequalityKind::UserCoupling}); expectError(c.b, "rhs"); }
  { Chain c; TaskDesc t = c.task("t", 99, 0); c.b.addTask(t); expectError(c.b, "joint 99"); }
  { Chain c; TaskDesc t = c.task("t", c.hand, 0); t.weight = 0; c.b.addTask(t); expectError(c.b, "weight"); }
  { Chain c; TaskDesc t = c.task("t", c.hand, 0); t.axes = 0; c.b.addTask(t); expectError(c.b, "axes"); }
  { Chain c; TaskDesc t = c.task("t", c.hand, 0); t.max_position_error = 0; c.b.addTask(t); expectError(c.b, "clamps"); }
  { Chain c; TaskDesc t = c.task("t", c.hand, 0); c.b.addTask(t); c.b.addTask(t); expectError(c.b, "duplicate name"); }
  { Chain c; TaskDesc t = c.task("t", c.hand, 0); t.recruit = Recruit::Depth; c.b.addTask(t); expectError(c.b, "depth"); }
  { Chain c; TaskDesc t = c.task("t", c.hand, 0); t.recruit = Recruit::Explicit; t.joints = {c.neck};
    c.b.addTask(t); expectError(c.b, "not an ancestor"); }
  { ModelBuilder b; b.addJoint("r", kNoParent, JointType::Ball);
    TaskDesc t; t.name = "com"; t.type = TaskType::CenterOfMass; b.addTask(t); expectError(b, "segment masses"); }
  { Chain c; c.b.setUp(Eigen::Vector3d::Zero()); expectError(c.b, "up axis"); }
}

TEST_CASE("recruiting eq. 3: a lower task may not move an ancestor of a higher task that it does not recruit") {
  Chain c;
  TaskDesc head = c.task("head", c.head, 0);
  head.recruit = Recruit::Depth;
  head.depth = 2;  // head + neck
  c.b.addTask(head);
  c.b.addTask(c.task("hand", c.hand, 1));  // recruits arm, spine1, root: ancestors of the head
  const std::string e = buildError(c.b);
  INFO(e);
  CHECK(e.find("eq. 3") != std::string::npos);
  CHECK(e.find("'hand'") != std::string::npos);
  CHECK(e.find("'head'") != std::string::npos);
  CHECK((e.find("'spine1'") != std::string::npos || e.find("'root'") != std::string::npos));
  // The same tasks with the priorities swapped are fine: the hand's chain is not the head's.
  Chain ok;
  TaskDesc h2 = ok.task("head", ok.head, 1);
  h2.recruit = Recruit::Depth;
  h2.depth = 2;
  ok.b.addTask(h2);
  ok.b.addTask(ok.task("hand", ok.hand, 0));
  CHECK(ok.b.build().ok());
}

TEST_CASE("recruiting eq. 4: implicit recruitment through a coupling counts") {
  Chain c;
  c.b.addEquality("couple spine", {c.spine2, 0}, 1.0, {c.spine1, 0}, -0.5);
  TaskDesc head = c.task("head", c.head, 0);
  head.recruit = Recruit::Explicit;
  head.joints = {c.neck, c.spine2};  // not spine1
  c.b.addTask(head);
  TaskDesc hand = c.task("hand", c.hand, 1);
  hand.recruit = Recruit::Explicit;
  hand.joints = {c.arm};  // explicit: no ancestor of the head directly...
  c.b.addTask(hand);
  TaskDesc other = c.task("spine_user", c.spine1, 1);
  other.type = TaskType::Orientation;
  other.recruit = Recruit::Explicit;
  other.joints = {c.spine1};  // ...but spine1 is an ancestor of the head it does not recruit: eq. 3
  c.b.addTask(other);
  std::string e = buildError(c.b);
  CHECK(e.find("eq. 3") != std::string::npos);

  // Implicit only: a lower task recruits spine2 (recruited by the head), which is coupled to
  // spine1 (an ancestor of the head the head does not recruit).
  Chain d;
  d.b.addEquality("couple spine", {d.spine2, 0}, 1.0, {d.spine1, 0}, -0.5);
  TaskDesc head2 = d.task("head", d.head, 0);
  head2.recruit = Recruit::Explicit;
  head2.joints = {d.neck, d.spine2};
  d.b.addTask(head2);
  TaskDesc low = d.task("chest", d.spine2, 1);
  low.type = TaskType::Orientation;
  low.recruit = Recruit::Explicit;
  low.joints = {d.spine2};
  d.b.addTask(low);
  e = buildError(d.b);
  INFO(e);
  CHECK(e.find("eq. 4") != std::string::npos);
  CHECK(e.find("'chest'") != std::string::npos);
  CHECK(e.find("'spine1'") != std::string::npos);
  CHECK(e.find("'head'") != std::string::npos);
}

TEST_CASE("recruiting eq. 5: every coupled joint must be recruited by some task") {
  Chain c;
  c.b.addEquality("couple", {c.spine2, 1}, 1.0, {c.spine1, 1}, -1.0);
  TaskDesc t = c.task("neck", c.neck, 0);
  t.type = TaskType::Orientation;
  t.recruit = Recruit::Explicit;
  t.joints = {c.neck, c.spine2};
  c.b.addTask(t);
  const std::string e = buildError(c.b);
  INFO(e);
  CHECK(e.find("eq. 5") != std::string::npos);
  CHECK(e.find("'spine1'") != std::string::npos);
  CHECK(e.find("'neck'") != std::string::npos);
}

TEST_CASE("the sample models satisfy the recruiting rules") {
  CHECK(test::sampleHumanoid().ok());
  CHECK(test::sampleSpine(true).ok());
  CHECK(test::sampleSpine(false).ok());
}

TEST_CASE("an orientation relative to a reference joint: validated, unmoved by the reference, met by the recruited joints") {
  // The neck held at a turn on spine2 (the runtime's clavicles at rest on the chest), below a
  // head orientation task that turns the whole chain.
  {
    Chain c;
    TaskDesc rel = c.task("neck_on_spine2", c.neck, 1);
    rel.type = TaskType::Orientation;
    rel.recruit = Recruit::Explicit;
    rel.joints = {c.spine1};  // moves its own reference
    rel.reference = c.spine2;
    c.b.addTask(rel);
    CHECK(buildError(c.b).find("relative to joint 'spine2', which its recruited joint 'spine1' moves") != std::string::npos);
  }
  {
    Chain c;
    TaskDesc rel = c.task("neck_on_arm", c.neck, 1);
    rel.type = TaskType::Orientation;
    rel.reference = c.arm;  // not an ancestor
    rel.recruit = Recruit::Explicit;
    rel.joints = {c.neck};
    c.b.addTask(rel);
    CHECK(buildError(c.b).find("is not an ancestor of its joint") != std::string::npos);
  }
  {
    Chain c;
    TaskDesc rel = c.task("neck_point", c.neck, 1);  // a position task
    rel.reference = c.spine2;
    rel.recruit = Recruit::Explicit;
    rel.joints = {c.neck};
    c.b.addTask(rel);
    CHECK(buildError(c.b).find("only an orientation task takes a reference joint") != std::string::npos);
  }
  Chain c;
  TaskDesc head = c.task("head", c.head, 0);
  head.type = TaskType::Orientation;
  head.recruit = Recruit::Explicit;
  head.joints = {c.spine1, c.spine2, c.neck};  // the trunk and the neck turn the head
  TaskDesc rel = c.task("neck_on_spine2", c.neck, 1);
  rel.type = TaskType::Orientation;
  rel.recruit = Recruit::Explicit;
  rel.joints = {c.neck};
  rel.reference = c.spine2;
  const TaskId headTask = c.b.addTask(head), relTask = c.b.addTask(rel);
  INFO(buildError(c.b));
  const Model m = c.b.build().value();
  Data d(m);
  // A fresh Data holds the relative task at its current relative turn: the rest one, met.
  CHECK(d.targetOrientation(relTask).angularDistance(Eigen::Quaterniond::Identity()) < 1e-12);
  const Eigen::Quaterniond onSpine(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 0, 1).normalized()));
  const Eigen::Quaterniond headTurn(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
  REQUIRE(d.setTarget(relTask, onSpine));
  REQUIRE(d.setTarget(headTask, headTurn * onSpine));  // reachable: the trunk turns by headTurn
  SolveOptions o;
  o.max_iterations = 200;
  solve(m, d, o);
  const Eigen::Quaterniond spine2(d.jointFrame(c.spine2).rotation()), neck(d.jointFrame(c.neck).rotation());
  INFO("neck on spine2 " << (spine2.conjugate() * neck).angularDistance(onSpine) << " rad off, head "
                         << neck.angularDistance(headTurn * onSpine) << " rad off, trunk turned "
                         << spine2.angularDistance(Eigen::Quaterniond::Identity()) << " rad");
  CHECK((spine2.conjugate() * neck).angularDistance(onSpine) < 1e-3);  // relative to the moved reference
  CHECK(neck.angularDistance(headTurn * onSpine) < 1e-3);
  CHECK(spine2.angularDistance(Eigen::Quaterniond::Identity()) > 0.2);  // the reference did move
}
