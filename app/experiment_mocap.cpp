// `embody experiment mocap` (Raunhardt & Boulic 2008, §5.2.3): marker positions taken from a BVH
// clip drive the default mannequin's body, coupled vs uncoupled spine. Only positions reach the
// solver: a marker is a clip joint's world position; orientations of the head, the wrists and
// the toes come from groups of two or three markers (a frame from three non-collinear markers,
// else the swing that turns the direction between two), relative to the first frame, applied to
// the body's segment orientation after it settled on that frame. Priorities:
//   0  ankles (the support)
//   1  every other marker the clip and the mannequin share (hips, spine bones, neck, head,
//      shoulders, elbows, wrists, knees, toes) and the three orientation groups
// Reported per frame: marker error, orientation error, and the spine's plausibility (swing
// spread, torsion sign changes, largest swing over its limit, equality residual).
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/angles.h"
#include "app/experiments.h"
#include "avatar/procedural/default_avatar.h"
#include "tracking/bvh_avatar.h"

namespace embody::app::experiment {
namespace {

using avatar::HumanBone;

size_t at(int index) {
  return static_cast<size_t>(index);
}

struct Marker {
  HumanBone bone;
  int clipJoint = -1;
  ik::JointId joint = -1;  // IK joint whose pivot the marker drives
  ik::TaskId task = -1;
};

// An orientation from two or three markers (clip joints a, b, c; c = -1 for two).
struct MarkerGroup {
  std::string name;
  std::array<int, 3> clip{-1, -1, -1};
  ik::JointId joint = -1;
  ik::TaskId task = -1;
  bool threeMarkers = false;
  Eigen::Matrix3d firstFrame = Eigen::Matrix3d::Identity();  // marker frame at frame 0
  Eigen::Vector3d firstDir = Eigen::Vector3d::UnitY();
  Eigen::Quaterniond bodyFirst = Eigen::Quaterniond::Identity();  // body segment after settling
};

struct MocapSetup {
  std::vector<Marker> markers;
  std::vector<MarkerGroup> groups;
};

const HumanBone kMarkerBones[] = {
    HumanBone::hips,         HumanBone::spine,         HumanBone::chest,        HumanBone::upperChest,
    HumanBone::neck,         HumanBone::head,          HumanBone::leftUpperLeg, HumanBone::rightUpperLeg,
    HumanBone::leftLowerLeg, HumanBone::rightLowerLeg, HumanBone::leftFoot,     HumanBone::rightFoot,
    HumanBone::leftToes,     HumanBone::rightToes,     HumanBone::leftUpperArm, HumanBone::rightUpperArm,
    HumanBone::leftLowerArm, HumanBone::rightLowerArm, HumanBone::leftHand,     HumanBone::rightHand};

int firstChild(const avatar::BvhClip& clip, int joint) {
  for (size_t j = 0; j < clip.joints.size(); ++j)
    if (clip.joints[j].parent == joint) return static_cast<int>(j);
  return -1;
}

TaskAdder mocapTasks(const avatar::AvatarAsset& asset, const tracking::BvhAvatar& clip, MocapSetup& s) {
  return [&asset, &clip, &s](ik::ModelBuilder& b, const avatar::BodyModel& body) {
    s.markers.clear();
    s.groups.clear();
    auto ikOf = [&](HumanBone bone) {
      const int a = asset.humanoid.joint(bone);
      return a < 0 ? -1 : body.ikJointOfAvatar[static_cast<size_t>(a)];
    };
    for (HumanBone bone : kMarkerBones) {
      const int c = clip.asset.humanoid.joint(bone);
      const ik::JointId j = ikOf(bone);
      if (c < 0 || j < 0) continue;
      // Two bones on one IK joint (a simplified-spine site standing for several bones): keep the first.
      if (std::any_of(s.markers.begin(), s.markers.end(), [&](const Marker& m) { return m.joint == j; }))
        continue;
      ik::TaskDesc d;
      d.name = "marker_" + std::string(avatar::humanBoneName(bone));
      d.type = ik::TaskType::Position;
      d.joint = j;
      d.level = bone == HumanBone::leftFoot || bone == HumanBone::rightFoot ? 0 : 1;
      s.markers.push_back({bone, c, j, b.addTask(d)});
    }
    auto group = [&](const char* name, HumanBone proximal, HumanBone bone, HumanBone segment) {
      MarkerGroup g;
      g.name = name;
      const int mid = clip.asset.humanoid.joint(bone);
      g.clip = {clip.asset.humanoid.joint(proximal), mid, mid < 0 ? -1 : firstChild(clip.clip, mid)};
      g.joint = ikOf(segment);
      if (g.clip[1] < 0 || g.clip[2] < 0 || g.joint < 0) return;
      ik::TaskDesc d;
      d.name = std::string("orientation_") + name;
      d.type = ik::TaskType::Orientation;
      d.joint = g.joint;
      d.level = 1;
      g.task = b.addTask(d);
      s.groups.push_back(g);
    };
    group("head", HumanBone::neck, HumanBone::head, HumanBone::head);
    group("left_wrist", HumanBone::leftLowerArm, HumanBone::leftHand, HumanBone::leftHand);
    group("right_wrist", HumanBone::rightLowerArm, HumanBone::rightHand, HumanBone::rightHand);
    group("left_toes", HumanBone::leftFoot, HumanBone::leftToes, HumanBone::leftToes);
    group("right_toes", HumanBone::rightFoot, HumanBone::rightToes, HumanBone::rightToes);
  };
}

// The clip's joints at one time, in the body's space (turned to face the mannequin's way, the
// first frame's hips over the mannequin's hips).
struct ClipSpace {
  Eigen::Matrix3d turn = Eigen::Matrix3d::Identity();
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
};
std::vector<Eigen::Vector3d> markersAt(const tracking::BvhAvatar& clip, const ClipSpace& space, double t) {
  std::vector<avatar::BvhGlobal> g;
  tracking::bvhJointsAt(clip.clip, clip.mapping, t, g);
  std::vector<Eigen::Vector3d> out(g.size());
  for (size_t j = 0; j < g.size(); ++j)
    out[j] = space.turn * Eigen::Vector3d(g[j].position.x, g[j].position.y, g[j].position.z) + space.shift;
  return out;
}

// Marker frame of a group: three markers give a full frame, two the direction only.
Eigen::Matrix3d groupFrame(const MarkerGroup& g, const std::vector<Eigen::Vector3d>& p) {
  const Eigen::Vector3d u = (p[at(g.clip[2])] - p[at(g.clip[1])]).normalized();
  Eigen::Matrix3d f;
  const Eigen::Vector3d w = u.cross(p[at(g.clip[1])] - p[at(g.clip[0])]).normalized();
  f << u, w, u.cross(w);
  return f;
}

Eigen::Quaterniond groupTarget(const MarkerGroup& g, const std::vector<Eigen::Vector3d>& p) {
  Eigen::Quaterniond delta;
  if (g.threeMarkers)
    delta = Eigen::Quaterniond(groupFrame(g, p) * g.firstFrame.transpose());
  else
    delta =
        Eigen::Quaterniond::FromTwoVectors(g.firstDir, (p[at(g.clip[2])] - p[at(g.clip[1])]).normalized());
  return (delta * g.bodyFirst).normalized();
}

struct MocapRun {
  ExperimentBody body;
  MocapSetup setup;
  std::string framesCsv;
  std::vector<Eigen::VectorXd> qs;  // per frame
  nlohmann::json summary;
};

void setPositionTargets(Targets& targets, const MocapSetup& s, const std::vector<Eigen::Vector3d>& p) {
  for (const Marker& m : s.markers) targets.set(m.task, p[at(m.clipJoint)]);
}

// Frame 0: positions only, then the orientation groups are calibrated on the settled body.
void settleFirstFrame(const ik::Model& m, Targets& targets, MocapSetup& s,
                      const std::vector<Eigen::Vector3d>& p, int iterations) {
  ik::Data& data = targets.data;
  for (const MarkerGroup& g : s.groups) targets.enable(g.task, false);
  setPositionTargets(targets, s, p);
  ik::SolveOptions so;
  for (int i = 0; i < iterations; ++i) ik::iterate(m, data, so);
  ik::kinematics(m, data, false);
  for (MarkerGroup& g : s.groups) {
    const Eigen::Vector3d b = p[at(g.clip[2])] - p[at(g.clip[1])];
    const Eigen::Vector3d a =
        g.clip[0] >= 0 ? Eigen::Vector3d(p[at(g.clip[1])] - p[at(g.clip[0])]) : Eigen::Vector3d::Zero();
    g.threeMarkers = a.norm() > 1e-6 && a.normalized().cross(b.normalized()).norm() > 0.2;
    if (g.threeMarkers) g.firstFrame = groupFrame(g, p);
    g.firstDir = b.normalized();
    g.bodyFirst = data.taskOrientation(g.task);
    targets.enable(g.task, true);
  }
}

Result<MocapRun> solveMocap(const avatar::AvatarAsset& asset, const tracking::BvhAvatar& clip,
                            const ClipSpace& space, bool coupled, const MocapOptions& o,
                            avatar::SpineMode mode, int frames) {
  MocapRun run;
  auto body = buildExperimentBody(asset, mode, coupled, mocapTasks(asset, clip, run.setup));
  if (!body) return Error{body.error()};
  run.body = std::move(*body);
  const ik::Model& m = run.body.body.model;
  ik::Data data(m);
  Targets targets{data, {}};
  ik::SolveOptions so;
  run.framesCsv =
      "frame,marker_error_mean_m,marker_error_max_m,orientation_error_mean_deg,swing_spread,"
      "max_normalised_swing,torsion_changes_within,torsion_changes_between,equality_residual\n";
  std::vector<double> markerMean, orientMean, spread, maxSwing;
  int worstTorsion = 0;
  double worstResidual = 0.0, worstMarker = 0.0;
  for (int f = 0; f < frames; ++f) {
    const std::vector<Eigen::Vector3d> p = markersAt(clip, space, f * clip.clip.frameTime);
    if (f == 0) {
      settleFirstFrame(m, targets, run.setup, p, o.settleIterations);
    } else {
      setPositionTargets(targets, run.setup, p);
    }
    for (const MarkerGroup& g : run.setup.groups) targets.set(g.task, groupTarget(g, p));
    if (!targets.error.empty()) return Error{targets.error};
    for (int i = 0; i < o.iterationsPerFrame; ++i) ik::iterate(m, data, so);
    ik::kinematics(m, data, false);
    double sum = 0.0, worst = 0.0, osum = 0.0;
    for (const Marker& mk : run.setup.markers) {
      const double e = (data.taskPosition(mk.task) - p[static_cast<size_t>(mk.clipJoint)]).norm();
      sum += e;
      worst = std::max(worst, e);
    }
    for (const MarkerGroup& g : run.setup.groups)
      osum += data.taskOrientation(g.task).angularDistance(data.targetOrientation(g.task));
    const SpineShape shape = spineShape(run.body, data.q());
    const double residual = equalityResidual(m, data.q());
    markerMean.push_back(sum / double(std::max<size_t>(1, run.setup.markers.size())));
    orientMean.push_back(osum / double(std::max<size_t>(1, run.setup.groups.size())) / kDeg);
    spread.push_back(shape.swingSpread);
    maxSwing.push_back(shape.maxNormalisedSwing);
    worstTorsion = std::max(worstTorsion, shape.torsionChangesWithin);
    worstResidual = std::max(worstResidual, residual);
    worstMarker = std::max(worstMarker, worst);
    char line[256];
    std::snprintf(line, sizeof line, "%d,%.9g,%.9g,%.9g,%.9g,%.9g,%d,%d,%.3g\n", f, markerMean.back(), worst,
                  orientMean.back(), shape.swingSpread, shape.maxNormalisedSwing, shape.torsionChangesWithin,
                  shape.torsionChangesBetween, residual);
    run.framesCsv += line;
    run.qs.push_back(data.q());
  }
  auto mean = [](const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return v.empty() ? 0.0 : s / double(v.size());
  };
  run.summary = bodySummary(run.body, spineShape(run.body, run.qs.back()), run.qs.back());
  run.summary["frames"] = frames;
  run.summary["markers"] = run.setup.markers.size();
  run.summary["orientation_groups"] = run.setup.groups.size();
  run.summary["marker_error_mean_m"] = mean(markerMean);
  run.summary["marker_error_max_m"] = worstMarker;
  run.summary["orientation_error_mean_deg"] = mean(orientMean);
  run.summary["swing_spread_mean"] = mean(spread);
  run.summary["max_normalised_swing_max"] = *std::max_element(maxSwing.begin(), maxSwing.end());
  run.summary["torsion_sign_changes_within_regions_max"] = worstTorsion;
  run.summary["equality_residual_max_over_frames"] = worstResidual;
  return run;
}

std::string mocapPlots() {
  return gnuplotHeader("mocap", "size 1200,480") +
         multiplotFigure("fig_mocap.png", "1,3", "Motion-capture markers driving the mannequin: coupled vs uncoupled spine") +
         R"gp(set grid
set xlabel 'frame'
set key top left
)gp" +
         runsPanels({{"metres", "mean marker error", "frames", "1:2", "linespoints lw 2"},
                     {"swing spread", "spine swing spread (0 = proportional)", "frames", "1:5", "linespoints lw 2"},
                     {"count", "torsion sign changes within regions", "frames", "1:7", "steps lw 2"}}) +
         R"gp(unset multiplot
)gp";
}

// The clip turned to face the mannequin's way, its first frame's hips over the mannequin's hips.
ClipSpace clipSpace(const avatar::AvatarAsset& asset, const tracking::BvhAvatar& clip) {
  ClipSpace s;
  // A turn about the vertical that takes the clip's facing (-Z, tracking space) to the mannequin's.
  const double yaw = std::atan2(-double(asset.humanoid.forward.x), -double(asset.humanoid.forward.z));
  s.turn = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const std::vector<Eigen::Vector3d> p = markersAt(clip, s, 0.0);
  std::vector<glm::mat4> globals;
  avatar::computeGlobals(asset.skeleton, avatar::SkeletonPose::rest(asset.skeleton), globals);
  const glm::vec3 hips(globals[static_cast<size_t>(asset.humanoid.joint(HumanBone::hips))][3]);
  const Eigen::Vector3d clipHips = p[static_cast<size_t>(clip.asset.humanoid.joint(HumanBone::hips))];
  s.shift = Eigen::Vector3d(hips.x - clipHips.x(), 0.0, hips.z - clipHips.z());
  return s;
}

}  // namespace

int runMocap(const MocapOptions& o, nlohmann::json& summary) {
  avatar::SpineMode mode;
  if (!spineModeOf(o.spine, mode)) return fail("mocap: unknown spine '" + o.spine + "'");
  const avatar::AvatarAsset asset = avatar::buildDefaultAvatar();
  tracking::BvhTrackerOptions bo;
  bo.userHeight = 1.75f;  // the mannequin's height
  bo.body = o.bvh;
  auto clip = tracking::loadBvhAvatar(o.motion, bo);
  if (!clip) {
    const bool relative = fs::path(o.motion).is_relative() && !fs::exists(o.motion);
    return fail("mocap: " + clip.error() +
                (relative ? " (the path is relative: run from the repository root or pass --motion FILE.bvh)" : ""));
  }
  const int available = static_cast<int>(clip->clip.frameCount - clip->mapping.firstFrame);
  const int frames = o.maxFrames > 0 ? std::min(o.maxFrames, available) : available;
  if (frames < 1) return fail("mocap: " + o.motion + " has no frames");
  const ClipSpace space = clipSpace(asset, *clip);
  std::string error;
  if (!makeFolder(o.common.out, error)) return fail(error);
  std::vector<MocapRun> runs;
  for (bool coupled : {true, false}) {
    auto run = solveMocap(asset, *clip, space, coupled, o, mode, frames);
    if (!run) return fail("mocap: " + run.error());
    const std::string v = coupled ? "coupled" : "uncoupled";
    if (!writeFile(o.common.out / (v + "_frames.csv"), run->framesCsv))
      return fail("cannot write in " + o.common.out.string());
    summary[v] = run->summary;
    runs.push_back(std::move(*run));
  }
  summary["setup"] = {{"motion", o.motion},
                      {"frames", frames},
                      {"iterations_per_frame", o.iterationsPerFrame},
                      {"settle_iterations", o.settleIterations},
                      {"spine", o.spine},
                      {"avatar", "default"}};
  if (o.common.plots)
    if (auto e = runGnuplot(o.common.out, "plots.gp", mocapPlots()); !e.empty()) return fail(e);
  if (o.common.frames) {
    auto renderer = PostureRenderer::create(asset, o.common.frameSize, o.common.frameSize);
    if (!renderer) return fail("mocap: rendering: " + renderer.error());
    std::vector<std::pair<const ExperimentBody*, Eigen::VectorXd>> poses;
    std::vector<std::string> names;
    for (const MocapRun& run : runs)
      for (int f : {0, frames / 2, frames - 1}) {
        poses.emplace_back(&run.body, run.qs[static_cast<size_t>(f)]);
        names.push_back(std::string("mocap_") + (run.body.coupled ? "coupled" : "uncoupled") + "_frame" +
                        std::to_string(f));
      }
    auto shots = renderPostures(**renderer, o.common.out, poses, names, {0.6f}, "fig_mocap_postures.png");
    if (!shots) return fail("mocap: rendering: " + shots.error());
  }
  if (!writeFile(o.common.out / "summary.json", summary.dump(2) + "\n"))
    return fail("cannot write summary.json");
  for (const char* v : {"coupled", "uncoupled"}) {
    const auto& s = summary[v];
    std::printf(
        "%-9s %d frames, %d markers: marker error mean %.3f m (max %.3f), orientation %.1f deg; spine swing "
        "spread %.3g, torsion sign changes within regions <= %d\n",
        v, frames, s["markers"].get<int>(), s["marker_error_mean_m"].get<double>(),
        s["marker_error_max_m"].get<double>(), s["orientation_error_mean_deg"].get<double>(),
        s["swing_spread_mean"].get<double>(), s["torsion_sign_changes_within_regions_max"].get<int>());
  }
  std::printf("wrote mocap results to %s\n", o.common.out.string().c_str());
  return 0;
}

}  // namespace embody::app::experiment
