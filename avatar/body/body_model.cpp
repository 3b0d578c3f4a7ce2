// IK body model from a mapped avatar (see body_model.h).
#include "avatar/body/body_model.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "ik/spine/spine_model.h"

namespace embody::avatar {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

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
// Knees and elbows bend at least this much (radians, ~1.7 degrees): see the elbow's limits.
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

Eigen::Vector3d toEigen(const glm::vec3& v) {
  return {v.x, v.y, v.z};
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

struct SiteGroup {
  int joint;
  int firstLevel, endLevel;
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
  const HumanoidMap& map = avatar.humanoid;
  const Skeleton& sk = avatar.skeleton;
  if (!map.usable()) {
    std::string missing;
    for (HumanBone b : map.missingRequired)
      missing += (missing.empty() ? "" : ", ") + std::string(humanBoneName(b));
    return Error{"the avatar's humanoid mapping is incomplete; missing required bones: " +
                 (missing.empty() ? std::string("(no mapping)") : missing)};
  }
  if (map.spine.empty()) return Error{"the avatar has no spine between hips and head"};
  BodyModel body;
  std::vector<glm::mat4> globals;
  computeGlobals(sk, SkeletonPose::rest(sk), globals);
  const size_t n = sk.joints.size();
  body.avatarRestGlobalRotation.resize(n);
  body.avatarRestGlobalScale.resize(n);
  std::vector<Eigen::Vector3d> pivot(n);
  for (size_t j = 0; j < n; ++j) {
    const glm::vec3 c0(globals[j][0]), c1(globals[j][1]), c2(globals[j][2]);
    const glm::vec3 s(glm::length(c0), glm::length(c1), glm::length(c2));
    body.avatarRestGlobalScale[j] = s;
    body.avatarRestGlobalRotation[j] =
        glm::normalize(glm::quat_cast(glm::mat3(c0 / s.x, c1 / s.y, c2 / s.z)));
    pivot[j] = options.scale * toEigen(glm::vec3(globals[j][3]));
  }
  if (!(options.scale > 0.05 && options.scale < 20.0)) return Error{"body scale must be between 0.05 and 20"};
  body.scale = options.scale;
  const Eigen::Vector3d up = toEigen(map.up).normalized();
  const Eigen::Vector3d forward = toEigen(map.forward).normalized();
  const double height =
      std::max(0.5, pivot[static_cast<size_t>(map.joint(HumanBone::head))].dot(up) -
                        std::min(pivot[static_cast<size_t>(map.joint(HumanBone::leftFoot))].dot(up),
                                 pivot[static_cast<size_t>(map.joint(HumanBone::rightFoot))].dot(up)) +
                        0.18);
  const double massScale = options.totalMass / 100.0;

  // Spine sites: every spine bone that stands for a vertebra (full / the avatar's own bones), or
  // the eight groups of the simplified model when the avatar has a bone per vertebra.
  bool perVertebra = std::count_if(map.spine.begin(), map.spine.end(),
                                   [](const SpineBone& b) { return b.levelCount() == 1; }) ==
                         static_cast<long>(map.spine.size()) &&
                     map.spine.size() == kVertebralJointCount;
  std::vector<SpineBone> sites;
  if (options.spine == SpineMode::Simplified && perVertebra) {
    // 3 lumbar, 3 thoracic, 2 cervical sites (Raunhardt & Boulic's simplified model) + the head.
    const int starts[] = {0, 2, 4, 5, 9, 13, 17, 20, 24, 25};
    for (int g = 0; g + 1 < 10; ++g)
      sites.push_back({map.spine[static_cast<size_t>(starts[g])].joint, starts[g], starts[g + 1]});
    body.spineModel = "simplified";
  } else {
    for (const SpineBone& b : map.spine)
      if (b.levelCount() > 0) sites.push_back(b);
    body.spineModel = perVertebra ? "full" : "bones";
  }
  body.spineSites = sites;

  // Which avatar joints the IK model drives, and what each one's frame aims at.
  std::vector<int> kind(n, 0);  // 0 none, else a tag below
  enum Tag { Hips = 1, Spine, Clavicle, UpperArm, Elbow, Hand, UpperLeg, Knee, Ankle, Toes };
  const int hips = map.joint(HumanBone::hips);
  kind[static_cast<size_t>(hips)] = Hips;
  std::vector<int> siteIndexOf(n, -1);
  for (size_t s = 0; s < sites.size(); ++s) {
    kind[static_cast<size_t>(sites[s].joint)] = Spine;
    siteIndexOf[static_cast<size_t>(sites[s].joint)] = static_cast<int>(s);
  }
  auto mark = [&](HumanBone b, int tag) {
    if (map.has(b) && sk.isAncestor(hips, map.joint(b)) && map.joint(b) != hips)
      kind[static_cast<size_t>(map.joint(b))] = tag;
  };
  mark(HumanBone::leftShoulder, Clavicle);
  mark(HumanBone::rightShoulder, Clavicle);
  mark(HumanBone::leftUpperArm, UpperArm);
  mark(HumanBone::rightUpperArm, UpperArm);
  mark(HumanBone::leftLowerArm, Elbow);
  mark(HumanBone::rightLowerArm, Elbow);
  mark(HumanBone::leftHand, Hand);
  mark(HumanBone::rightHand, Hand);
  mark(HumanBone::leftUpperLeg, UpperLeg);
  mark(HumanBone::rightUpperLeg, UpperLeg);
  mark(HumanBone::leftLowerLeg, Knee);
  mark(HumanBone::rightLowerLeg, Knee);
  mark(HumanBone::leftFoot, Ankle);
  mark(HumanBone::rightFoot, Ankle);
  mark(HumanBone::leftToes, Toes);
  mark(HumanBone::rightToes, Toes);
  auto isLeft = [&](int j) {
    for (HumanBone b :
         {HumanBone::leftShoulder, HumanBone::leftUpperArm, HumanBone::leftLowerArm, HumanBone::leftHand,
          HumanBone::leftUpperLeg, HumanBone::leftLowerLeg, HumanBone::leftFoot, HumanBone::leftToes})
      if (map.joint(b) == j) return true;
    return false;
  };
  // The bone's direction: towards the next mapped bone down the limb, the next spine site, or
  // (for ends) the first child / the parent's direction.
  auto nextOf = [&](int j) -> int {
    auto pick = [&](HumanBone l, HumanBone r) { return map.joint(isLeft(j) ? l : r); };
    switch (kind[static_cast<size_t>(j)]) {
      case Hips:
        return sites.empty() ? -1 : sites.front().joint;
      case Spine: {
        const int s = siteIndexOf[static_cast<size_t>(j)];
        return s + 1 < static_cast<int>(sites.size()) ? sites[static_cast<size_t>(s) + 1].joint : -1;
      }
      case Clavicle:
        return pick(HumanBone::leftUpperArm, HumanBone::rightUpperArm);
      case UpperArm:
        return pick(HumanBone::leftLowerArm, HumanBone::rightLowerArm);
      case Elbow:
        return pick(HumanBone::leftHand, HumanBone::rightHand);
      case Hand:  // towards the fingers: the middle knuckle (else another), not a first child that may be the
                  // thumb
        for (int f : {1, 0, 2, 3}) {
          const auto first =
              static_cast<int>(isLeft(j) ? HumanBone::leftIndexProximal : HumanBone::rightIndexProximal);
          const int k =
              map.joint(static_cast<HumanBone>(first + 3 * f));  // index, middle, ring, little proximal
          if (k >= 0 && k != j && sk.isAncestor(j, k)) return k;
        }
        return -1;
      case UpperLeg:
        return pick(HumanBone::leftLowerLeg, HumanBone::rightLowerLeg);
      case Knee:
        return pick(HumanBone::leftFoot, HumanBone::rightFoot);
      case Ankle:
        return pick(HumanBone::leftToes, HumanBone::rightToes);
      default:
        return -1;
    }
  };
  auto direction = [&](int j) -> Eigen::Vector3d {
    const int next = nextOf(j);
    if (next >= 0 && (pivot[static_cast<size_t>(next)] - pivot[static_cast<size_t>(j)]).norm() > 1e-5)
      return (pivot[static_cast<size_t>(next)] - pivot[static_cast<size_t>(j)]).normalized();
    if (kind[static_cast<size_t>(j)] == Spine) return up;  // the head: up
    for (int c : sk.children(j))
      if ((pivot[static_cast<size_t>(c)] - pivot[static_cast<size_t>(j)]).norm() > 1e-4)
        return (pivot[static_cast<size_t>(c)] - pivot[static_cast<size_t>(j)]).normalized();
    const int p = sk.joints[static_cast<size_t>(j)].parent;
    if (p >= 0 && (pivot[static_cast<size_t>(j)] - pivot[static_cast<size_t>(p)]).norm() > 1e-5)
      return (pivot[static_cast<size_t>(j)] - pivot[static_cast<size_t>(p)]).normalized();
    return up;
  };
  auto segmentLength = [&](int j) {
    const int next = nextOf(j);
    if (next >= 0) return (pivot[static_cast<size_t>(next)] - pivot[static_cast<size_t>(j)]).norm();
    return 0.045 * height;  // hands and toes without a child: a typical length
  };

  auto limitsOf = [](ik::JointDesc& d, std::vector<double> lo, std::vector<double> hi) {
    d.lower = std::move(lo);
    d.upper = std::move(hi);
  };
  auto& limits = limitsOf;
  ik::ModelBuilder b;
  b.setUp(up);
  body.ikJointOfAvatar.assign(n, -1);
  std::vector<Eigen::Isometry3d> world;  // per IK joint at rest
  auto add = [&](int avatarJoint, ik::JointDesc desc, const Eigen::Matrix3d& rot, bool sameParent = false) {
    int parentAvatar = sk.joints[static_cast<size_t>(avatarJoint)].parent;
    int parentIk = -1;
    if (sameParent || body.ikJointOfAvatar[static_cast<size_t>(avatarJoint)] >= 0) {
      parentIk = body.ikJointOfAvatar[static_cast<size_t>(avatarJoint)];  // a second joint at the same pivot
    } else {
      while (parentAvatar >= 0 && body.ikJointOfAvatar[static_cast<size_t>(parentAvatar)] < 0)
        parentAvatar = sk.joints[static_cast<size_t>(parentAvatar)].parent;
      parentIk = parentAvatar >= 0 ? body.ikJointOfAvatar[static_cast<size_t>(parentAvatar)] : -1;
    }
    Eigen::Isometry3d w = Eigen::Isometry3d::Identity();
    w.linear() = rot;
    w.translation() = pivot[static_cast<size_t>(avatarJoint)];
    desc.parent = parentIk;
    desc.rest = parentIk >= 0 ? world[static_cast<size_t>(parentIk)].inverse() * w : w;
    const ik::JointId id = b.addJoint(desc);
    world.push_back(w);
    body.avatarJoint.push_back(avatarJoint);
    body.ikRestRotation.push_back(Eigen::Quaterniond(rot));
    body.ikJointOfAvatar[static_cast<size_t>(avatarJoint)] = id;
    return id;
  };

  // The coupled spine (Raunhardt & Boulic 2008, ik/spine) laid onto the avatar's spine
  // bones: one site per bone (split where a bone spans two regions, the pieces sharing its
  // pivot), or the default full / simplified descriptions for a bone-per-vertebra avatar. Each
  // site takes the coupling rows and ranges of the vertebrae it stands for; the head (Occ-C1) is
  // a Ball joint on top.
  auto addCoupledSpine = [&]() -> Status {
    std::vector<SpineBone> vertebral;  // sites below the head
    for (const SpineBone& sb : sites)
      if (sb.endLevel <= kVertebralJointCount - 1)
        vertebral.push_back(sb);
      else if (sb.firstLevel < kVertebralJointCount - 1)
        vertebral.push_back({sb.joint, sb.firstLevel, kVertebralJointCount - 1});
    const SpineBone headSite = sites.back();
    if (headSite.endLevel != kVertebralJointCount)
      return Error{"spine: the head bone does not close the spine"};
    ik::spine::SpineDescription desc;
    std::vector<int> siteJoint;  // avatar joint of each description site
    if (perVertebra && options.spine != SpineMode::Simplified) {
      desc = ik::spine::defaultFullSpine();
    } else if (perVertebra) {
      desc = ik::spine::defaultSimplifiedSpine();
    } else {
      std::vector<ik::spine::SiteSpec> specs;
      const int regionEnd[] = {5, 17, 24};
      for (const SpineBone& sb : vertebral)
        for (int from = sb.firstLevel; from < sb.endLevel;) {
          int to = sb.endLevel;
          for (int e : regionEnd)
            if (from < e && to > e) to = e;
          specs.push_back({sk.joints[static_cast<size_t>(sb.joint)].name +
                               (from == sb.firstLevel ? "" : "_" + std::string(vertebralJointName(from))),
                           std::string(vertebralJointName(from)), std::string(vertebralJointName(to - 1)),
                           true, true});
          from = to;
        }
      auto d = ik::spine::withSites(ik::spine::defaultFullSpine(), specs);
      if (!d.ok()) return Error{"spine: " + d.error()};
      desc = std::move(d.value());
    }
    for (const auto& site : desc.sites) {
      int joint = -1;
      for (const SpineBone& sb : map.spine)
        if (sb.standsFor(site.first)) joint = sb.joint;
      if (joint < 0)
        return Error{"spine: no avatar bone stands for " +
                     desc.vertebrae[static_cast<size_t>(site.first)].name};
      siteJoint.push_back(joint);
    }
    // World rest frames: at each site's bone pivot, +Y towards the next distinct pivot.
    std::vector<Eigen::Isometry3d> siteWorld(desc.sites.size());
    std::vector<Eigen::Isometry3d> rests(desc.sites.size());
    const int headJoint = headSite.joint;
    for (size_t k = 0; k < desc.sites.size(); ++k) {
      const Eigen::Vector3d here = pivot[static_cast<size_t>(siteJoint[k])];
      Eigen::Vector3d next = pivot[static_cast<size_t>(headJoint)];
      for (size_t m = k + 1; m < desc.sites.size(); ++m)
        if ((pivot[static_cast<size_t>(siteJoint[m])] - here).norm() > 1e-6) {
          next = pivot[static_cast<size_t>(siteJoint[m])];
          break;
        }
      if ((next - here).norm() < 1e-6) return Error{"spine: two spine bones share a pivot with the head"};
      siteWorld[k].setIdentity();
      siteWorld[k].linear() = boneFrame(next - here, forward, up);
      siteWorld[k].translation() = here;
      rests[k] = (k == 0 ? world[static_cast<size_t>(body.hips)] : siteWorld[k - 1]).inverse() * siteWorld[k];
    }
    const size_t before = b.joints().size();
    ik::spine::SpineOptions so;
    auto added = ik::spine::appendSpine(b, desc, body.hips, rests, so);
    if (!added.ok()) return Error{"spine: " + added.error()};
    // Book-keeping for the joints appendSpine added: pivot, rest rotation, masses.
    for (size_t id = before; id < b.joints().size(); ++id) {
      size_t k = 0;
      for (size_t m = 0; m < added->sites.size(); ++m) {
        const auto& sj = added->sites[m];
        if (sj.swing == static_cast<int>(id) || sj.revolute == static_cast<int>(id) ||
            sj.ball == static_cast<int>(id))
          k = m;
      }
      world.push_back(siteWorld[k]);
      body.avatarJoint.push_back(siteJoint[k]);
      body.ikRestRotation.push_back(Eigen::Quaterniond(siteWorld[k].linear()));
    }
    body.spineSites.clear();
    for (size_t k = 0; k < desc.sites.size(); ++k) {
      const auto& site = desc.sites[k];
      const ik::JointId last = added->sites[k].last();
      body.ikJointOfAvatar[static_cast<size_t>(siteJoint[k])] = last;  // the bone takes the composed rotation
      double mass = 0.0;
      for (int l = site.first; l < site.first + site.count; ++l) mass += levelMassPercent(l);
      const Eigen::Vector3d top = k + 1 < desc.sites.size() ? Eigen::Vector3d(siteWorld[k + 1].translation())
                                                            : pivot[static_cast<size_t>(headJoint)];
      const double length = (top - siteWorld[k].translation()).norm();
      b.setSegment(last, mass * massScale, Eigen::Vector3d(0, 0.5 * length, 0));
      body.spineSites.push_back({siteJoint[k], site.first, site.first + site.count});
    }
    body.spineSites.push_back(headSite.firstLevel == kVertebralJointCount - 1
                                  ? headSite
                                  : SpineBone{headJoint, kVertebralJointCount - 1, kVertebralJointCount});
    body.spineEqualities = added->equalities;
    // The head: a Ball joint for Occ-C1 on top of the spine.
    ik::JointDesc h;
    h.name = sk.joints[static_cast<size_t>(headJoint)].name;
    h.type = ik::JointType::Ball;
    const auto& r = kLevelRangeDeg[kVertebralJointCount - 1];
    limitsOf(h, {-(1.0 - kFlexionShare) * r[0] * kDeg, -r[2] * kDeg, -r[1] * kDeg},
             {kFlexionShare * r[0] * kDeg, r[2] * kDeg, r[1] * kDeg});
    h.mass = levelMassPercent(kVertebralJointCount - 1) * massScale;
    h.com = Eigen::Vector3d(0, 0.06 * height / 1.75, 0);
    body.ikJointOfAvatar[static_cast<size_t>(headJoint)] = added->top;  // parent for add()
    body.head = add(headJoint, h, boneFrame(up, forward, up), /*sameParent=*/true);
    return {};
  };

  for (size_t a = 0; a < n; ++a) {
    const int j = static_cast<int>(a);
    const int tag = kind[a];
    if (tag == 0) continue;
    if (tag != Hips && !sk.isAncestor(hips, j)) continue;
    const Eigen::Vector3d dir = direction(j);
    const Eigen::Matrix3d rot = boneFrame(dir, forward, up);
    const double side = isLeft(j) ? 1.0 : -1.0;
    const double len = segmentLength(j);
    ik::JointDesc d;
    d.name = sk.joints[a].name;
    switch (tag) {
      case Hips: {
        d.type = ik::JointType::Free;
        d.mass = kLowerTrunk * massScale;
        d.com = Eigen::Vector3d(0, 0.5 * len, 0);
        const ik::JointId id = add(j, d, rot);
        body.hips = id;
        if (options.coupledSpine) {
          if (auto s = addCoupledSpine(); !s.ok()) return Error{s.error()};
        }
        break;
      }
      case Spine: {
        if (options.coupledSpine) break;  // added with the coupled spine
        const SpineBone& s = sites[static_cast<size_t>(siteIndexOf[a])];
        Eigen::Vector3d r = Eigen::Vector3d::Zero();
        double mass = 0.0;
        for (int l = s.firstLevel; l < s.endLevel; ++l) {
          for (int k = 0; k < 3; ++k)
            r[k] += kLevelRangeDeg[static_cast<size_t>(l)][static_cast<size_t>(k)] * kDeg;
          mass += levelMassPercent(l);
        }
        // exp-map components in the site frame: x flexion (+ forward), y torsion, z bending.
        d.type = ik::JointType::Ball;
        limits(d, {-(1.0 - kFlexionShare) * r[0], -r[2], -r[1]}, {kFlexionShare * r[0], r[2], r[1]});
        d.mass = mass * massScale;
        d.com = Eigen::Vector3d(0, s.endLevel == kVertebralJointCount ? 0.06 * height / 1.75 : 0.5 * len, 0);
        const ik::JointId id = add(j, d, rot);
        if (s.endLevel == kVertebralJointCount) body.head = id;
        break;
      }
      case Clavicle:
        d.type = ik::JointType::Swing;
        d.axis = Eigen::Vector3d::UnitY();
        limits(d, {-0.35, -0.35}, {0.35, 0.35});
        add(j, d, rot);
        break;
      case UpperArm:
        d.type = ik::JointType::Ball;
        limits(d, {-1.0, -1.5, side > 0 ? -0.8 : -2.8}, {3.0, 1.5, side > 0 ? 2.8 : 0.8});
        d.mass = kUpperArm * massScale;
        d.com = Eigen::Vector3d(0, kUpperArmCom * len, 0);
        add(j, d, rot);
        break;
      case Elbow: {
        // Hinge axis from the rest geometry: upper arm x forward (so + flexes the forearm
        // forward); a bent rest elbow gives the axis directly.
        const int upper = map.joint(side > 0 ? HumanBone::leftUpperArm : HumanBone::rightUpperArm);
        const Eigen::Vector3d dUpper = (pivot[a] - pivot[static_cast<size_t>(upper)]).normalized();
        Eigen::Vector3d axis = dUpper.cross(forward);
        const Eigen::Vector3d bent = dUpper.cross(dir);
        if (bent.norm() > 0.17) axis = bent.dot(axis) >= 0 ? bent : -bent;
        if (axis.norm() < 1e-6) axis = rot.col(0);
        d.type = ik::JointType::Revolute;
        d.axis = rot.transpose() * axis.normalized();
        // Never straight and never backwards: a hinge at exactly 0 is the straight-limb
        // singularity (shortening the limb has no first-order effect there, and a local solver
        // stalls), and below 0 it bends against its anatomical direction.
        limits(d, {kMinHingeBend}, {2.6});
        d.mass = kForearm * massScale;
        d.com = Eigen::Vector3d(0, kForearmCom * len, 0);
        add(j, d, rot);
        ik::JointDesc twist;
        twist.name = d.name + "_twist";
        twist.type = ik::JointType::Revolute;
        twist.axis = Eigen::Vector3d::UnitY();
        limits(twist, {-1.4}, {1.4});
        add(j, twist, rot);
        break;
      }
      case Hand: {
        d.type = ik::JointType::Ball;
        limits(d, {-1.2, -0.25, -0.6}, {1.2, 0.25, 0.6});
        d.mass = kHand * massScale;
        d.com = Eigen::Vector3d(0, kHandCom * len, 0);
        const ik::JointId id = add(j, d, rot);
        (side > 0 ? body.leftHand : body.rightHand) = id;
        break;
      }
      case UpperLeg:
        d.type = ik::JointType::Ball;
        limits(d, {-0.5, -0.7, side > 0 ? -0.5 : -0.8}, {2.1, 0.7, side > 0 ? 0.8 : 0.5});
        d.mass = kThigh * massScale;
        d.com = Eigen::Vector3d(0, kThighCom * len, 0);
        add(j, d, rot);
        break;
      case Knee: {
        const int upper = map.joint(side > 0 ? HumanBone::leftUpperLeg : HumanBone::rightUpperLeg);
        const Eigen::Vector3d dUpper = (pivot[a] - pivot[static_cast<size_t>(upper)]).normalized();
        Eigen::Vector3d axis = dUpper.cross(-forward);  // + flexes the shank backwards
        if (axis.norm() < 1e-6) axis = rot.col(0);
        d.type = ik::JointType::Revolute;
        d.axis = rot.transpose() * axis.normalized();
        limits(d, {kMinHingeBend}, {2.4});  // as the elbow: never straight, never backwards
        d.mass = kShank * massScale;
        d.com = Eigen::Vector3d(0, kShankCom * len, 0);
        add(j, d, rot);
        break;
      }
      case Ankle: {
        d.type = ik::JointType::Ball;
        limits(d, {-0.9, -0.5, -0.5}, {0.6, 0.5, 0.5});
        d.mass = kFoot * massScale;
        d.com = Eigen::Vector3d(0, kFootCom * len, 0);
        const ik::JointId id = add(j, d, rot);
        (side > 0 ? body.leftFoot : body.rightFoot) = id;
        break;
      }
      case Toes:
        d.type = ik::JointType::Revolute;
        d.axis = Eigen::Vector3d::UnitX();
        limits(d, {-0.6}, {0.6});
        add(j, d, rot);
        break;
    }
  }
  if (body.head < 0 || body.leftHand < 0 || body.rightHand < 0 || body.leftFoot < 0 || body.rightFoot < 0)
    return Error{"the mapped hands, feet or head do not hang below the hips; cannot build the body model"};

  if (options.addTasks) {
    auto pose = [&](const char* name, ik::JointId joint, int level) {
      ik::TaskDesc t;
      t.name = name;
      t.type = ik::TaskType::Pose;
      t.joint = joint;
      t.level = level;
      return b.addTask(t);
    };
    body.leftFootTask = pose("left_foot", body.leftFoot, 0);
    body.rightFootTask = pose("right_foot", body.rightFoot, 0);
    ik::TaskDesc com;
    com.name = "com";
    com.type = ik::TaskType::CenterOfMass;
    com.level = 1;
    body.comTask = b.addTask(com);
    body.headTask = pose("head", body.head, 2);
    // A waist tracker, when there is one (off until the runtime binds and enables it).
    ik::TaskDesc waist;
    waist.name = "hips";
    waist.type = ik::TaskType::Pose;
    waist.joint = body.hips;
    waist.level = 2;
    waist.enabled = false;
    body.hipsTask = b.addTask(waist);
    body.leftHandTask = pose("left_hand", body.leftHand, 3);
    body.rightHandTask = pose("right_hand", body.rightHand, 3);
  }
  auto model = b.build();
  if (!model.ok()) return Error{"body model: " + model.error()};
  body.model = std::move(model.value());
  return body;
}

void retarget(const BodyModel& body, const AvatarAsset& avatar, const ik::Data& data, SkeletonPose& pose) {
  const Skeleton& sk = avatar.skeleton;
  const size_t n = sk.joints.size();
  pose.local.resize(n);
  // Global matrices as we go (parents first); thread-local scratch keeps the call allocation-free
  // after the first one.
  thread_local std::vector<glm::mat4> globals;
  globals.resize(n);
  for (size_t a = 0; a < n; ++a) {
    const Joint& joint = sk.joints[a];
    Transform local = joint.rest;
    const glm::mat4 parent = joint.parent >= 0 ? globals[static_cast<size_t>(joint.parent)] : glm::mat4(1.0f);
    const int ikJoint = body.ikJointOfAvatar[a];
    if (ikJoint >= 0) {
      const Eigen::Isometry3d& frame = data.jointFrame(ikJoint);
      const Eigen::Quaterniond delta = Eigen::Quaterniond(frame.rotation()) *
                                       body.ikRestRotation[static_cast<size_t>(ikJoint)].conjugate();
      const glm::quat d(static_cast<float>(delta.w()), static_cast<float>(delta.x()),
                        static_cast<float>(delta.y()), static_cast<float>(delta.z()));
      const glm::quat wanted = glm::normalize(d * body.avatarRestGlobalRotation[a]);
      const glm::vec3 c0(parent[0]), c1(parent[1]), c2(parent[2]);
      const glm::quat parentRot = glm::normalize(
          glm::quat_cast(glm::mat3(glm::normalize(c0), glm::normalize(c1), glm::normalize(c2))));
      local.rotation = glm::normalize(glm::inverse(parentRot) * wanted);
      if (ikJoint == body.hips) {
        const Eigen::Vector3d p = frame.translation() / body.scale;
        local.translation =
            glm::vec3(glm::inverse(parent) * glm::vec4(float(p.x()), float(p.y()), float(p.z()), 1.0f));
      }
    }
    pose.local[a] = local;
    globals[a] = parent * local.matrix();
  }
}

}  // namespace embody::avatar
