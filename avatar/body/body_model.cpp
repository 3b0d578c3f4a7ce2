// IK body model from a mapped avatar (see body_model.h).
#include "avatar/body/body_model.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/angles.h"
#include "avatar/body/neutral_pose.h"
#include "avatar/glm_eigen.h"
#include "ik/expmap.h"
#include "ik/spine/spine_model.h"

namespace embody::avatar {
namespace {

// Per intervertebral joint, bottom (vl5 = L5-S1) to top (skullbase = Occ-C1): flexion+extension,
// lateral bending to one side, axial rotation to one side, degrees. White & Panjabi (1990) as
// transcribed in spine.md §1; where the transcriptions disagree the first value is used.
constexpr std::array<std::array<double, 3>, kVertebralJointCount> kLevelRangeDeg = {{
    {20, 3, 5}, {17, 6, 2}, {15, 8, 2}, {14, 6, 2},  {12, 6, 2},                           // L5-S1 .. L1-L2
    {12, 8, 2}, {12, 9, 2}, {9, 7, 2},  {6, 6, 4},   {6, 6, 6},   {6, 6, 8},   {5, 6, 8},  // T12-L1 .. T6-T7
    {4, 6, 8},  {4, 6, 9},  {4, 6, 9},  {4, 6, 9},   {4, 6, 9},                            // T5-T6 .. T1-T2
    {9, 4, 2},  {17, 7, 6}, {20, 8, 7}, {20, 11, 7}, {15, 11, 7}, {10, 10, 3}, {20, 5, 40},  // C7-T1 .. C1-C2
    {25, 5, 5},                                                                              // Occ-C1
}};
constexpr double kFlexionShare = 0.6;
// Knees and elbows bend at least this much (radians, ~1.7 degrees), never straight and never
// backwards: a hinge at exactly 0 is the straight-limb singularity (shortening the limb has no
// first-order effect there, and a local solver stalls), and below 0 it bends against its
// anatomical direction.
constexpr double kMinHingeBend = 0.03;

// de Leva (1996), male, percent of body mass; trunk split into lower (pelvis), middle and upper.
constexpr double kHeadNeck = 6.94, kUpperTrunk = 15.96, kMiddleTrunk = 16.33, kLowerTrunk = 11.17;
constexpr double kUpperArm = 2.71, kForearm = 1.62, kHand = 0.61, kThigh = 14.16, kShank = 4.33, kFoot = 1.37;
// Centre of mass along the segment from the proximal joint (de Leva 1996, male).
constexpr double kUpperArmCom = 0.5772, kForearmCom = 0.4574, kHandCom = 0.79, kThighCom = 0.4095,
                 kShankCom = 0.4459, kFootCom = 0.4415;

// Mass share (percent) of one vertebral level's segment: middle trunk over L5..T7, upper trunk
// over T6..T1, 15 % of head+neck over the cervical levels, the rest to the head.
double levelMassPercent(int level) {
  if (level <= 10) return kMiddleTrunk / 11.0;
  if (level <= 16) return kUpperTrunk / 6.0;
  if (level <= 23) return 0.15 * kHeadNeck / 7.0;
  return 0.85 * kHeadNeck;
}

// +Y along the bone, +X = Y x forward (falls back to up x Y when the bone points forward).
Eigen::Matrix3d boneFrame(const Eigen::Vector3d& dir, const Eigen::Vector3d& forward,
                          const Eigen::Vector3d& up) {
  const Eigen::Vector3d y = dir.normalized();
  Eigen::Vector3d x = y.cross(forward);
  if (x.norm() < 0.3) x = up.cross(y);
  if (x.norm() < 1e-6) x = Eigen::Vector3d::UnitX();
  x.normalize();
  const Eigen::Vector3d z = x.cross(y);
  Eigen::Matrix3d r;
  r.col(0) = x;
  r.col(1) = y;
  r.col(2) = z;
  return r;
}

// The bone kinds the IK model drives, and per kind what the joint is (the per-bone spec table).
enum class Kind { None, Hips, Spine, Clavicle, UpperArm, Elbow, Hand, UpperLeg, Knee, Ankle, Toes };

// One limb joint: type, limits for the left side (the right side mirrors the third component:
// its lower limit is minus the left's upper, and the other way), de Leva mass share (percent)
// and centre of mass along the segment. Hinge axes of elbow and knee come from the rest geometry.
struct LimbSpec {
  Kind kind;
  HumanBone left, right;
  ik::JointType type;
  std::vector<double> lower, upper;
  bool mirrorLast = false;
  double massPercent = 0.0, com = 0.0;
};

const std::vector<LimbSpec>& limbSpecs() {
  using B = HumanBone;
  using T = ik::JointType;
  static const std::vector<LimbSpec> specs = {
      {Kind::Clavicle, B::leftShoulder, B::rightShoulder, T::Swing, {-0.35, -0.35}, {0.35, 0.35}},
      {Kind::UpperArm, B::leftUpperArm, B::rightUpperArm, T::Ball, {-1.0, -1.5, -0.8}, {3.0, 1.5, 2.8}, true, kUpperArm, kUpperArmCom},
      {Kind::Elbow, B::leftLowerArm, B::rightLowerArm, T::Revolute, {kMinHingeBend}, {2.6}, false, kForearm, kForearmCom},
      {Kind::Hand, B::leftHand, B::rightHand, T::Ball, {-1.2, -0.25, -0.6}, {1.2, 0.25, 0.6}, false, kHand, kHandCom},
      {Kind::UpperLeg, B::leftUpperLeg, B::rightUpperLeg, T::Ball, {-0.5, -0.7, -0.5}, {2.1, 0.7, 0.8}, true, kThigh, kThighCom},
      {Kind::Knee, B::leftLowerLeg, B::rightLowerLeg, T::Revolute, {kMinHingeBend}, {2.4}, false, kShank, kShankCom},
      // The foot's turn about the sole's normal (z, ±34°) also stands for the shank's own rotation,
      // which the knee's hinge lacks (30-40° with the knee bent): at ±29° a dancer's turned-out
      // feet were met by turning the whole leg (docs/eval.md, Session 11). Inversion / eversion
      // (y) ±34° (AAOS: 35° / 15°; one range for both signs, as +y inverts one foot and everts
      // the other).
      {Kind::Ankle, B::leftFoot, B::rightFoot, T::Ball, {-0.9, -0.6, -0.6}, {0.6, 0.6, 0.6}, false, kFoot, kFootCom},
      {Kind::Toes, B::leftToes, B::rightToes, T::Revolute, {-0.6}, {0.6}},
  };
  return specs;
}

// The configuration that puts every IK joint at `restWorld` (its world rotation at the avatar's
// rest pose), per joint of the builder. The neutral turns limb bones only, about their pivots,
// and the hinges about their axes: Ball joints take the rotation's log, Revolute joints its angle
// about the axis; the hips (Free), the spine and the clavicles (Swing) rest at 0.
std::vector<std::vector<double>> restConfiguration(const std::vector<ik::JointDesc>& joints,
                                                   const std::vector<Eigen::Quaterniond>& restWorld) {
  std::vector<std::vector<double>> q(joints.size());
  for (size_t j = 0; j < joints.size(); ++j) {
    const ik::JointDesc& d = joints[j];
    const Eigen::Quaterniond parent = d.parent >= 0 ? restWorld[static_cast<size_t>(d.parent)] : Eigen::Quaterniond::Identity();
    Eigen::Quaterniond rel(d.rest.linear().transpose() * (parent.conjugate() * restWorld[j]).toRotationMatrix());
    if (rel.w() < 0.0) rel.coeffs() = -rel.coeffs();
    if (d.type == ik::JointType::Ball) {
      const Eigen::Vector3d v = ik::rotationLog(rel.toRotationMatrix());
      q[j] = {v.x(), v.y(), v.z()};
    } else if (d.type == ik::JointType::Revolute) {
      q[j] = {2.0 * std::atan2(rel.vec().dot(d.axis.normalized()), rel.w())};
    }
    // Below a nano-radian the rest is the neutral (the rounding of the frames' products).
    for (double& v : q[j])
      if (std::abs(v) < 1e-9) v = 0.0;
  }
  return q;
}

void setLimits(ik::JointDesc& d, std::vector<double> lo, std::vector<double> hi) {
  d.lower = std::move(lo);
  d.upper = std::move(hi);
}

// Builds the body model in steps (one object for the state they share): rest frames, spine
// sites, the kind of each avatar joint, then the joints hips-first (the coupled spine with the
// hips), then the tasks.
class BodyModelBuilder {
 public:
  BodyModelBuilder(const AvatarAsset& avatar, const BodyModelOptions& options)
      : map_(avatar.humanoid),
        sk_(avatar.skeleton),
        options_(options),
        n_(sk_.joints.size()),
        names_(uniqueJointNames(sk_)),
        restGlobals_(restGlobalsOf(sk_)) {}

  Result<BodyModel> build() {
    if (auto s = checkMapping(); !s) return Error{s.error()};
    if (auto s = checkNoMirroring(); !s) return Error{s.error()};
    if (!(options_.scale > 0.05 && options_.scale < 20.0)) return Error{"body scale must be between 0.05 and 20"};
    body_.scale = options_.scale;
    restFrames();
    chooseSpineSites();
    classifyJoints();
    neutralFrames();
    b_.setUp(up_);
    body_.ikJointOfAvatar.assign(n_, -1);
    for (size_t a = 0; a < n_; ++a)
      if (auto s = addJointsOf(static_cast<int>(a)); !s) return Error{s.error()};
    if (body_.head < 0 || body_.leftHand < 0 || body_.rightHand < 0 || body_.leftFoot < 0 || body_.rightFoot < 0)
      return Error{"the mapped hands, feet or head do not hang below the hips; cannot build the body model"};
    if (options_.addTasks) addTasks();
    // A fresh ik::Data starts at the avatar's rest pose (JointDesc::neutral), q = 0 is neutral.
    const auto rest = restConfiguration(b_.joints(), body_.ikRestRotation);
    for (size_t j = 0; j < rest.size(); ++j)
      for (size_t k = 0; k < rest[j].size(); ++k)
        if (rest[j][k] != 0.0) b_.setNeutral({static_cast<ik::JointId>(j), static_cast<int>(k)}, rest[j][k]);
    auto model = b_.build();
    if (!model.ok()) return Error{"body model: " + model.error()};
    body_.model = std::move(model.value());
    body_.restConfiguration = body_.model.neutral;
    for (const std::string& name : neckBandNames_)
      if (const int row = body_.model.findInequality(name); row >= 0) body_.neckBandRows.push_back(row);
    return std::move(body_);
  }

 private:
  const HumanoidMap& map_;
  const Skeleton& sk_;
  const BodyModelOptions& options_;
  const size_t n_;
  const std::vector<std::string> names_;  // per avatar joint, unique (duplicate glTF node names)
  const std::vector<glm::mat4> restGlobals_;  // per avatar joint, the rest pose's model-space matrix

  static std::vector<glm::mat4> restGlobalsOf(const Skeleton& sk) {
    std::vector<glm::mat4> globals;
    computeGlobals(sk, SkeletonPose::rest(sk), globals);
    return globals;
  }
  BodyModel body_;
  std::vector<Eigen::Vector3d> pivot_;  // per avatar joint at the neutral pose, model space at the user's scale
  NeutralPose neutral_;
  Eigen::Vector3d up_, forward_;
  double height_ = 0.0, massScale_ = 0.0;
  bool perVertebra_ = false;             // one spine bone per vertebral joint
  std::vector<SpineBone> sites_;
  std::vector<Kind> kind_;
  std::vector<int> siteIndexOf_;
  ik::ModelBuilder b_;
  std::vector<Eigen::Isometry3d> world_;  // per IK joint at rest
  std::vector<std::string> neckBandNames_;  // the coupled spine's thoracic-cervical band rows

  size_t at(int joint) const { return static_cast<size_t>(joint); }

  Status checkMapping() const {
    if (!map_.usable()) {
      std::string missing;
      for (HumanBone b : map_.missingRequired) missing += (missing.empty() ? "" : ", ") + std::string(humanBoneName(b));
      return Error{"the avatar's humanoid mapping is incomplete; missing required bones: " +
                   (missing.empty() ? std::string("(no mapping)") : missing)};
    }
    if (map_.spine.empty()) return Error{"the avatar has no spine between hips and head"};
    return {};
  }

  // A bone whose rest frame is mirrored (a negative scale on it or above it) has no rotation that
  // retargeting could give it: a file with scale -1 on its root rested right and folded over in
  // motion, reported upright (the robustness probe, session 20). Refused by name.
  Status checkNoMirroring() const {
    const std::vector<glm::mat4>& globals = restGlobals_;
    for (int bone : map_.bones)
      for (int j = bone; j >= 0; j = sk_.joints[at(j)].parent)
        if (glm::determinant(glm::mat3(globals[at(j)])) < 0.0f) {
          int top = j;  // the highest mirrored node: where the negative scale is
          for (int k = sk_.joints[at(j)].parent; k >= 0 && glm::determinant(glm::mat3(globals[at(k)])) < 0.0f;
               k = sk_.joints[at(k)].parent)
            top = k;
          return Error{"the skeleton is mirrored from node '" + sk_.joints[at(top)].name +
                       "' down (a negative scale): the body cannot be retargeted onto a mirrored bone; apply the "
                       "mirror to the mesh and bones in the modelling tool and export without negative scales"};
        }
    return {};
  }

  // Rest global rotations and scales (for retargeting), up, forward.
  void restFrames() {
    const std::vector<glm::mat4>& globals = restGlobals_;
    body_.avatarRestGlobalRotation.resize(n_);
    body_.avatarRestGlobalScale.resize(n_);
    for (size_t j = 0; j < n_; ++j) {
      const glm::vec3 c0(globals[j][0]), c1(globals[j][1]), c2(globals[j][2]);
      body_.avatarRestGlobalScale[j] = glm::vec3(glm::length(c0), glm::length(c1), glm::length(c2));
      const int parent = sk_.joints[j].parent;
      const glm::quat parentRotation = parent >= 0 ? body_.avatarRestGlobalRotation[at(parent)] : glm::quat(1, 0, 0, 0);
      body_.avatarRestGlobalRotation[j] = globalRotationOf(globals[j], parentRotation * sk_.joints[j].rest.rotation);
    }
    up_ = toEigen(map_.up).normalized();
    forward_ = toEigen(map_.forward).normalized();
  }

  // The neutral pose the model is built at (neutral_pose.h): pivots, hinge axes, height, masses.
  void neutralFrames() {
    auto driven = [&](HumanBone b) { return map_.has(b) && kind_[at(map_.joint(b))] != Kind::None ? map_.joint(b) : -1; };
    NeutralLimbs limbs;
    for (size_t k = 0; k < 4; ++k) {
      const bool left = k % 2 == 0, arm = k < 2;
      const LimbSpec& upper = *specOf(arm ? Kind::UpperArm : Kind::UpperLeg);
      const LimbSpec& hinge = *specOf(arm ? Kind::Elbow : Kind::Knee);
      const LimbSpec& end = *specOf(arm ? Kind::Hand : Kind::Ankle);
      NeutralLimb& l = limbs[k];
      l.arm = arm;
      l.left = left;
      l.upper = driven(left ? upper.left : upper.right);
      l.hinge = driven(left ? hinge.left : hinge.right);
      l.end = driven(left ? end.left : end.right);
      l.endNext = l.end >= 0 ? nextOf(l.end) : -1;
    }
    neutral_ = computeNeutralPose(sk_, limbs, up_, forward_);
    pivot_.resize(n_);
    for (size_t j = 0; j < n_; ++j) pivot_[j] = options_.scale * neutral_.position[j];
    const double lowestFoot = std::min(pivot_[at(map_.joint(HumanBone::leftFoot))].dot(up_),
                                       pivot_[at(map_.joint(HumanBone::rightFoot))].dot(up_));
    height_ = std::max(0.5, pivot_[at(map_.joint(HumanBone::head))].dot(up_) - lowestFoot + 0.18);
    massScale_ = options_.totalMass / 100.0;
  }

  // Spine sites: every spine bone that stands for a vertebra (full / the avatar's own bones), or
  // the eight groups of the simplified model when the avatar has a bone per vertebra.
  void chooseSpineSites() {
    perVertebra_ = map_.spine.size() == kVertebralJointCount &&
                   std::all_of(map_.spine.begin(), map_.spine.end(), [](const SpineBone& b) { return b.levelCount() == 1; });
    if (options_.spine == SpineMode::Simplified && perVertebra_) {
      // 3 lumbar, 3 thoracic, 2 cervical sites (Raunhardt & Boulic's simplified model) + the head.
      const int starts[] = {0, 2, 4, 5, 9, 13, 17, 20, 24, 25};
      for (int g = 0; g + 1 < 10; ++g) sites_.push_back({map_.spine[at(starts[g])].joint, starts[g], starts[g + 1]});
      body_.spineModel = "simplified";
    } else {
      for (const SpineBone& b : map_.spine)
        if (b.levelCount() > 0) sites_.push_back(b);
      body_.spineModel = perVertebra_ ? "full" : "bones";
    }
    body_.spineSites = sites_;
  }

  // Which avatar joints the IK model drives: the hips, the spine sites, and the limb bones of
  // the spec table that hang below the hips.
  void classifyJoints() {
    kind_.assign(n_, Kind::None);
    siteIndexOf_.assign(n_, -1);
    const int hips = map_.joint(HumanBone::hips);
    kind_[at(hips)] = Kind::Hips;
    for (size_t s = 0; s < sites_.size(); ++s) {
      kind_[at(sites_[s].joint)] = Kind::Spine;
      siteIndexOf_[at(sites_[s].joint)] = static_cast<int>(s);
    }
    for (const LimbSpec& spec : limbSpecs())
      for (HumanBone b : {spec.left, spec.right})
        if (map_.has(b) && sk_.isAncestor(hips, map_.joint(b)) && map_.joint(b) != hips) kind_[at(map_.joint(b))] = spec.kind;
  }

  const LimbSpec* specOf(Kind kind) const {
    for (const LimbSpec& spec : limbSpecs())
      if (spec.kind == kind) return &spec;
    return nullptr;
  }

  bool isLeft(int j) const {
    for (const LimbSpec& spec : limbSpecs())
      if (map_.joint(spec.left) == j) return true;
    return false;
  }

  // The bone's direction: towards the next mapped bone down the limb, the next spine site, or
  // (for ends) the first child / the parent's direction.
  int nextOf(int j) const {
    const Kind kind = kind_[at(j)];
    if (kind == Kind::Hips) return sites_.empty() ? -1 : sites_.front().joint;
    if (kind == Kind::Spine) {
      const int s = siteIndexOf_[at(j)];
      return s + 1 < static_cast<int>(sites_.size()) ? sites_[at(s) + 1].joint : -1;
    }
    if (kind == Kind::Hand) {  // towards the fingers: the middle knuckle (else another), not the thumb
      const auto first = static_cast<int>(isLeft(j) ? HumanBone::leftIndexProximal : HumanBone::rightIndexProximal);
      for (int f : {1, 0, 2, 3}) {
        const int k = map_.joint(static_cast<HumanBone>(first + 3 * f));  // index, middle, ring, little proximal
        if (k >= 0 && k != j && sk_.isAncestor(j, k)) return k;
      }
      return -1;
    }
    if (kind == Kind::None || kind == Kind::Toes) return -1;
    const LimbSpec* next = specOf(static_cast<Kind>(static_cast<int>(kind) + 1));  // the next bone down the limb
    return map_.joint(isLeft(j) ? next->left : next->right);
  }

  Eigen::Vector3d direction(int j) const {
    const int next = nextOf(j);
    if (next >= 0 && (pivot_[at(next)] - pivot_[at(j)]).norm() > 1e-5) return (pivot_[at(next)] - pivot_[at(j)]).normalized();
    if (kind_[at(j)] == Kind::Spine) return up_;  // the head: up
    for (int c : sk_.children(j))
      if ((pivot_[at(c)] - pivot_[at(j)]).norm() > 1e-4) return (pivot_[at(c)] - pivot_[at(j)]).normalized();
    const int p = sk_.joints[at(j)].parent;
    if (p >= 0 && (pivot_[at(j)] - pivot_[at(p)]).norm() > 1e-5) return (pivot_[at(j)] - pivot_[at(p)]).normalized();
    return up_;
  }

  double segmentLength(int j) const {
    const int next = nextOf(j);
    if (next >= 0) return (pivot_[at(next)] - pivot_[at(j)]).norm();
    return 0.045 * height_;  // hands and toes without a child: a typical length
  }

  // Adds an IK joint at the avatar joint's pivot, under the IK joint of its nearest driven
  // ancestor (or, sameParent, under the joint already at this pivot).
  ik::JointId add(int avatarJoint, ik::JointDesc desc, const Eigen::Matrix3d& rot, bool sameParent = false) {
    int parentIk = -1;
    if (sameParent || body_.ikJointOfAvatar[at(avatarJoint)] >= 0) {
      parentIk = body_.ikJointOfAvatar[at(avatarJoint)];  // a second joint at the same pivot
    } else {
      int parentAvatar = sk_.joints[at(avatarJoint)].parent;
      while (parentAvatar >= 0 && body_.ikJointOfAvatar[at(parentAvatar)] < 0) parentAvatar = sk_.joints[at(parentAvatar)].parent;
      parentIk = parentAvatar >= 0 ? body_.ikJointOfAvatar[at(parentAvatar)] : -1;
    }
    Eigen::Isometry3d w = Eigen::Isometry3d::Identity();
    w.linear() = rot;
    w.translation() = pivot_[at(avatarJoint)];
    desc.parent = parentIk;
    desc.rest = parentIk >= 0 ? world_[at(parentIk)].inverse() * w : w;
    const ik::JointId id = b_.addJoint(desc);
    world_.push_back(w);
    body_.avatarJoint.push_back(avatarJoint);
    body_.ikRestRotation.push_back(neutral_.restFromNeutral[at(avatarJoint)] * Eigen::Quaterniond(rot));
    body_.ikJointOfAvatar[at(avatarJoint)] = id;
    return id;
  }

  Status addJointsOf(int j) {
    const Kind kind = kind_[at(j)];
    if (kind == Kind::None) return {};
    if (kind != Kind::Hips && !sk_.isAncestor(map_.joint(HumanBone::hips), j)) return {};
    const Eigen::Matrix3d rot = boneFrame(direction(j), forward_, up_);
    ik::JointDesc d;
    d.name = names_[at(j)];
    if (kind == Kind::Hips) {
      d.type = ik::JointType::Free;
      d.mass = kLowerTrunk * massScale_;
      d.com = Eigen::Vector3d(0, 0.5 * segmentLength(j), 0);
      body_.hips = add(j, d, rot);
      return options_.coupledSpine ? addCoupledSpine() : Status{};
    }
    if (kind == Kind::Spine) {
      if (!options_.coupledSpine) addUncoupledSpineSite(j, d, rot);  // else added with the coupled spine
      return {};
    }
    addLimbJoint(j, *specOf(kind), d, rot);
    return {};
  }

  // One row of the spec table; elbow and knee get their hinge axis, the elbow a forearm twist.
  void addLimbJoint(int j, const LimbSpec& spec, ik::JointDesc& d, const Eigen::Matrix3d& rot) {
    const bool left = isLeft(j);
    d.type = spec.type;
    d.lower = spec.lower;
    d.upper = spec.upper;
    if (spec.mirrorLast && !left) {
      d.lower.back() = -spec.upper.back();
      d.upper.back() = -spec.lower.back();
    }
    d.mass = spec.massPercent * massScale_;
    if (spec.massPercent > 0.0) d.com = Eigen::Vector3d(0, spec.com * segmentLength(j), 0);
    if (spec.kind == Kind::Clavicle) d.axis = Eigen::Vector3d::UnitY();
    if (spec.kind == Kind::Toes) d.axis = Eigen::Vector3d::UnitX();
    if (spec.kind == Kind::Elbow || spec.kind == Kind::Knee) d.axis = rot.transpose() * hingeAxis(j, spec, rot);
    const ik::JointId id = add(j, d, rot);
    if (spec.kind == Kind::Hand) (left ? body_.leftHand : body_.rightHand) = id;
    if (spec.kind == Kind::Ankle) (left ? body_.leftFoot : body_.rightFoot) = id;
    if (spec.kind == Kind::Elbow) {
      ik::JointDesc twist;
      twist.name = d.name + "_twist";
      twist.type = ik::JointType::Revolute;
      twist.axis = Eigen::Vector3d::UnitY();
      setLimits(twist, {-1.4}, {1.4});
      add(j, twist, rot);
    }
  }

  // World hinge axis of an elbow (+ flexes the forearm forward) or a knee (+ flexes the shank
  // back), from the rest geometry at the neutral pose (neutral_pose.h).
  Eigen::Vector3d hingeAxis(int j, const LimbSpec& spec, const Eigen::Matrix3d& rot) const {
    const size_t limb = (spec.kind == Kind::Elbow ? 0 : 2) + (isLeft(j) ? 0 : 1);
    const Eigen::Vector3d& axis = neutral_.hingeAxis[limb];
    return axis.norm() > 0.5 ? axis : Eigen::Vector3d(rot.col(0));
  }

  // Without the coupled spine: one Ball per site with its vertebrae's summed ranges.
  void addUncoupledSpineSite(int j, ik::JointDesc& d, const Eigen::Matrix3d& rot) {
    const SpineBone& s = sites_[at(siteIndexOf_[at(j)])];
    Eigen::Vector3d r = Eigen::Vector3d::Zero();
    double mass = 0.0;
    for (int l = s.firstLevel; l < s.endLevel; ++l) {
      for (int k = 0; k < 3; ++k) r[k] += kLevelRangeDeg[at(l)][at(k)] * kDeg;
      mass += levelMassPercent(l);
    }
    // exp-map components in the site frame: x flexion (+ forward), y torsion, z bending.
    d.type = ik::JointType::Ball;
    setLimits(d, {-(1.0 - kFlexionShare) * r[0], -r[2], -r[1]}, {kFlexionShare * r[0], r[2], r[1]});
    d.mass = mass * massScale_;
    const bool head = s.endLevel == kVertebralJointCount;
    d.com = Eigen::Vector3d(0, head ? 0.06 * height_ / 1.75 : 0.5 * segmentLength(j), 0);
    const ik::JointId id = add(j, d, rot);
    if (head) body_.head = id;
  }

  // The coupled spine's description for the avatar: the default full / simplified one for a
  // bone-per-vertebra avatar, else one site per spine bone below the head, split where a bone
  // spans two regions (the pieces share its pivot).
  Result<ik::spine::SpineDescription> spineDescription() const {
    if (perVertebra_)
      return options_.spine != SpineMode::Simplified ? ik::spine::defaultFullSpine() : ik::spine::defaultSimplifiedSpine();
    std::vector<ik::spine::SiteSpec> specs;
    const int regionEnd[] = {5, 17, 24};
    for (const SpineBone& sb : sites_) {
      const int end = std::min(sb.endLevel, kVertebralJointCount - 1);  // the head (Occ-C1) is not a site
      for (int from = sb.firstLevel; from < end;) {
        int to = end;
        for (int e : regionEnd)
          if (from < e && to > e) to = e;
        std::string name = names_[at(sb.joint)];
        if (from != sb.firstLevel) name.append("_").append(vertebralJointName(from));
        specs.push_back({std::move(name), std::string(vertebralJointName(from)), std::string(vertebralJointName(to - 1)),
                         true, true});
        from = to;
      }
    }
    auto d = ik::spine::withSites(ik::spine::defaultFullSpine(), specs);
    if (!d.ok()) return Error{"spine: " + d.error()};
    return std::move(d.value());
  }

  // The coupled spine (Raunhardt & Boulic 2008, ik/spine) laid onto the avatar's spine bones;
  // each site takes the coupling rows and ranges of the vertebrae it stands for; the head
  // (Occ-C1) is a Ball joint on top.
  Status addCoupledSpine() {
    const SpineBone headSite = sites_.back();
    if (headSite.endLevel != kVertebralJointCount) return Error{"spine: the head bone does not close the spine"};
    auto desc = spineDescription();
    if (!desc) return Error{desc.error()};
    std::vector<int> siteJoint;  // avatar joint of each description site
    for (const auto& site : desc->sites) {
      int joint = -1;
      for (const SpineBone& sb : map_.spine)
        if (sb.standsFor(site.first)) joint = sb.joint;
      if (joint < 0) return Error{"spine: no avatar bone stands for " + desc->vertebrae[at(site.first)].name};
      siteJoint.push_back(joint);
    }
    std::vector<Eigen::Isometry3d> siteWorld, rests;
    if (auto s = siteRestFrames(siteJoint, headSite.joint, siteWorld, rests); !s) return s;
    const size_t before = b_.joints().size();
    auto added = ik::spine::appendSpine(b_, *desc, body_.hips, rests, ik::spine::SpineOptions{});
    if (!added.ok()) return Error{"spine: " + added.error()};
    recordSpineJoints(*desc, *added, before, siteJoint, siteWorld, headSite);
    for (const auto& band : added->bands)
      if (band.below == ik::spine::Region::Thoracic) neckBandNames_.insert(neckBandNames_.end(), {band.upper, band.lower});
    body_.bandSlack = desc->band_slack;
    addHead(headSite.joint, added->top);
    return {};
  }

  // World rest frames of the sites: at each site's bone pivot, +Y towards the next distinct
  // pivot; and each relative to the one below (the first to the hips).
  Status siteRestFrames(const std::vector<int>& siteJoint, int headJoint, std::vector<Eigen::Isometry3d>& siteWorld,
                        std::vector<Eigen::Isometry3d>& rests) const {
    siteWorld.resize(siteJoint.size());
    rests.resize(siteJoint.size());
    for (size_t k = 0; k < siteJoint.size(); ++k) {
      const Eigen::Vector3d here = pivot_[at(siteJoint[k])];
      Eigen::Vector3d next = pivot_[at(headJoint)];
      for (size_t m = k + 1; m < siteJoint.size(); ++m)
        if ((pivot_[at(siteJoint[m])] - here).norm() > 1e-6) {
          next = pivot_[at(siteJoint[m])];
          break;
        }
      if ((next - here).norm() < 1e-6) return Error{"spine: two spine bones share a pivot with the head"};
      siteWorld[k].setIdentity();
      siteWorld[k].linear() = boneFrame(next - here, forward_, up_);
      siteWorld[k].translation() = here;
      rests[k] = (k == 0 ? world_[at(body_.hips)] : siteWorld[k - 1]).inverse() * siteWorld[k];
    }
    return {};
  }

  // Book-keeping for the joints appendSpine added (pivot, rest rotation), the sites' masses and
  // which joint drives each spine bone.
  void recordSpineJoints(const ik::spine::SpineDescription& desc, const ik::spine::SpineJoints& added, size_t before,
                         const std::vector<int>& siteJoint, const std::vector<Eigen::Isometry3d>& siteWorld,
                         const SpineBone& headSite) {
    for (size_t id = before; id < b_.joints().size(); ++id) {
      size_t k = 0;
      for (size_t m = 0; m < added.sites.size(); ++m) {
        const auto& sj = added.sites[m];
        if (sj.swing == static_cast<int>(id) || sj.revolute == static_cast<int>(id) || sj.ball == static_cast<int>(id)) k = m;
      }
      world_.push_back(siteWorld[k]);
      body_.avatarJoint.push_back(siteJoint[k]);
      body_.ikRestRotation.push_back(neutral_.restFromNeutral[at(siteJoint[k])] * Eigen::Quaterniond(siteWorld[k].linear()));
    }
    body_.spineSites.clear();
    for (size_t k = 0; k < desc.sites.size(); ++k) {
      const auto& site = desc.sites[k];
      const ik::JointId last = added.sites[k].last();
      body_.ikJointOfAvatar[at(siteJoint[k])] = last;  // the bone takes the composed rotation
      double mass = 0.0;
      for (int l = site.first; l < site.first + site.count; ++l) mass += levelMassPercent(l);
      const Eigen::Vector3d top = k + 1 < desc.sites.size() ? Eigen::Vector3d(siteWorld[k + 1].translation())
                                                            : pivot_[at(headSite.joint)];
      b_.setSegment(last, mass * massScale_, Eigen::Vector3d(0, 0.5 * (top - siteWorld[k].translation()).norm(), 0));
      body_.spineSites.push_back({siteJoint[k], site.first, site.first + site.count});
    }
    body_.spineSites.push_back(headSite.firstLevel == kVertebralJointCount - 1
                                   ? headSite
                                   : SpineBone{headSite.joint, kVertebralJointCount - 1, kVertebralJointCount});
    body_.spineEqualities = added.equalities;
  }

  // The head: a Ball joint for Occ-C1 on top of the spine.
  void addHead(int headJoint, ik::JointId spineTop) {
    ik::JointDesc h;
    h.name = names_[at(headJoint)];
    h.type = ik::JointType::Ball;
    const auto& r = kLevelRangeDeg[kVertebralJointCount - 1];
    setLimits(h, {-(1.0 - kFlexionShare) * r[0] * kDeg, -r[2] * kDeg, -r[1] * kDeg},
              {kFlexionShare * r[0] * kDeg, r[2] * kDeg, r[1] * kDeg});
    h.mass = levelMassPercent(kVertebralJointCount - 1) * massScale_;
    h.com = Eigen::Vector3d(0, 0.06 * height_ / 1.75, 0);
    body_.ikJointOfAvatar[at(headJoint)] = spineTop;  // parent for add()
    body_.head = add(headJoint, h, boneFrame(up_, forward_, up_), /*sameParent=*/true);
  }

  // PIK's levels: feet (0), centre of mass (1), head and hips (2), hands (3).
  void addTasks() {
    auto pose = [&](const char* name, ik::JointId joint, int level, bool enabled = true) {
      ik::TaskDesc t;
      t.name = name;
      t.type = ik::TaskType::Pose;
      t.joint = joint;
      t.level = level;
      t.enabled = enabled;
      return b_.addTask(t);
    };
    body_.leftFootTask = pose("left_foot", body_.leftFoot, 0);
    body_.rightFootTask = pose("right_foot", body_.rightFoot, 0);
    ik::TaskDesc com;
    com.name = "com";
    com.type = ik::TaskType::CenterOfMass;
    com.level = 1;
    body_.comTask = b_.addTask(com);
    body_.headTask = pose("head", body_.head, 2);
    // A waist tracker, when there is one (off until the runtime binds and enables it).
    body_.hipsTask = pose("hips", body_.hips, 2, false);
    body_.leftHandTask = pose("left_hand", body_.leftHand, 3);
    body_.rightHandTask = pose("right_hand", body_.rightHand, 3);
  }
};

}  // namespace

bool parseSpineMode(const std::string& text, SpineMode& out) {
  if (text == "auto")
    out = SpineMode::Auto;
  else if (text == "full")
    out = SpineMode::Full;
  else if (text == "simplified")
    out = SpineMode::Simplified;
  else
    return false;
  return true;
}

Result<BodyModel> buildBodyModel(const AvatarAsset& avatar, const BodyModelOptions& options) {
  return BodyModelBuilder(avatar, options).build();
}

void retarget(const BodyModel& body, const AvatarAsset& avatar, const ik::Data& data, SkeletonPose& pose) {
  const Skeleton& sk = avatar.skeleton;
  const size_t n = sk.joints.size();
  pose.local.resize(n);
  // Global matrices as we go (parents first); thread-local scratch keeps the call allocation-free
  // after the first one.
  thread_local std::vector<glm::mat4> globals;
  thread_local std::vector<glm::quat> rotations;  // the globals' rotations (zero-scaled bones too)
  globals.resize(n);
  rotations.resize(n);
  for (size_t a = 0; a < n; ++a) {
    const Joint& joint = sk.joints[a];
    Transform local = joint.rest;
    const glm::mat4 parent = joint.parent >= 0 ? globals[static_cast<size_t>(joint.parent)] : glm::mat4(1.0f);
    const glm::quat parentRotation =
        joint.parent >= 0 ? rotations[static_cast<size_t>(joint.parent)] : glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
    const int ikJoint = body.ikJointOfAvatar[a];
    if (ikJoint >= 0) {
      const Eigen::Isometry3d& frame = data.jointFrame(ikJoint);
      const Eigen::Quaterniond delta = Eigen::Quaterniond(frame.rotation()) *
                                       body.ikRestRotation[static_cast<size_t>(ikJoint)].conjugate();
      const glm::quat d = toGlm(delta);
      const glm::quat wanted = glm::normalize(d * body.avatarRestGlobalRotation[a]);
      local.rotation = glm::normalize(glm::inverse(parentRotation) * wanted);
      if (ikJoint == body.hips) {
        const Eigen::Vector3d p = frame.translation() / body.scale;
        local.translation =
            glm::vec3(glm::inverse(parent) * glm::vec4(toGlm(p), 1.0f));
      }
    }
    pose.local[a] = local;
    globals[a] = parent * local.matrix();
    rotations[a] = globalRotationOf(globals[a], parentRotation * local.rotation);
  }
}

}  // namespace embody::avatar
