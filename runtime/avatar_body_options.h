#pragma once
// What an AvatarBodySolver is asked to be: the trackers, the spine, the calibration's inputs, the
// per-level trust region and the modes (three-point stepping, seated, joint markers, same body).
// Read once at create(): the body rig (body_rig.h) and the per-frame jobs take what they need.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>

#include "avatar/body/body_model.h"
#include "runtime/collapse_guard.h"
#include "runtime/foot_planner.h"
#include "runtime/seated_pose.h"
#include "tracking/tracking_guard.h"

namespace embody::runtime {

struct AvatarBodyOptions {
  avatar::SpineMode spine = avatar::SpineMode::Auto;
  tracking::TrackerMask trackers = tracking::TrackerMask::all();  // what the source provides
  // The user's height in metres (profile / --user-height); 0 = from the first valid head sample
  // (its height is taken as a standing eye height).
  float userHeight = 0.0f;
  int maxIterations = 40;
  double totalMass = 75.0;
  FootPlannerConfig feet;
  // Balance in three-point mode is kept by stepping: a step starts as soon as the centre of mass
  // leaves the support polygon. The centre-of-mass row of the layout (an inequality: enabled only
  // while the CoM is outside, target the nearest point of the polygon) no longer destabilises
  // the solve (the solver's per-level trust region), but it shares level 1 with the planted
  // feet, and trading the two in least squares let planted feet slide by up to 2.6 cm on the
  // CMU walk (the limit is 2 cm); off by default until it gets a level of its own.
  bool balanceRow = false;
  // A tracked pelvis steers the trunk over the ground at the lowest level (it yields to the
  // head and hands whenever the user's proportions differ from the avatar's).
  bool pelvisRow = true;
  // The user's arm (shoulder to wrist) over the avatar's scaled to the user's height (from a
  // profile's arm_span_m: avatar::BodyProfile::armLengthScale; 1 = proportional). Hands are placed
  // relative to the shoulders by 1 / armScale (tracker_targets_job.h). avatar::plausibleArmScale.
  double armScale = 1.0;
  // The coupled spine (ik/spine, Raunhardt & Boulic 2008; default) or one uncoupled ball
  // joint per spine site with its vertebrae's summed ranges (the escape hatch).
  bool coupledSpine = true;
  // ik::SolveOptions::max_level_step for this solver (the per-level trust region). Smaller than
  // the library's 0.1: the pelvis, head and hand levels push against the feet's level every
  // iteration on a walk, and their second-order pull on the feet shrinks with the cap (CMU walk,
  // 30 Hz, coupled spine, feet p95: none 42/57 mm, 0.2: 16/35, 0.1: 17/26, 0.05: 10/17,
  // 0.025: 1.2/8.5 mm; docs/runtime.md). 0.05 keeps a per-frame step far above what tracking
  // needs.
  double maxLevelStep = 0.05;
  // Seated mode (seatedTaskLayoutFor, seated_pose.h): the lower body sits on a seat placed under
  // the first tracked head (again after resetWarmStart), the spine and arms follow the head and
  // hands. A seated head says nothing about the user's stature: give userHeight (else 1.75 m).
  SeatOptions seat;
  // Standing: a body found in a heap (collapse_guard.h) is re-seeded standing under the head
  // (body_seed.h) and the published pose fades to the new solution over `recoveryBlendSeconds`.
  CollapseGuardConfig collapse;
  double recoveryBlendSeconds = 0.2;
  // Knee and elbow direction tasks at the lowest level (pole_tasks.h).
  bool limbPoles = true;
  // The elbows' poles too (a swivel from the palm's direction, pole_tasks.h). Off: on the eval
  // clips they pulled elbows off the performers' (3 trackers: upper body 6.7 -> 8.2 cm, reverse
  // elbows 65 -> 273 frames; 6 trackers worse on 7 of 8 clips; docs/eval.md).
  bool elbowPoles = false;
  // Each clavicle held at its rest turn on the chest at the lowest level (task_layout.cpp), so it
  // moves only when a hand needs it beyond the arm's reach. Off: the clavicles take a share of
  // every arm motion and keep it (the shoulder joint 13 cm off on the CMU walk).
  bool restClavicles = true;
  // The tracked person IS this avatar (embody eval: the avatar is the clip's own skeleton, built
  // in tracking space, tracking/bvh_avatar.h): tracking space is avatar space (scale 1, floor at
  // y = 0, no turn), no height or stride calibration, and the trackers' rest references are the
  // source's (tracking::BvhMapping), so a perfect solve puts every joint where the clip's is.
  // Joint markers (embody eval --trackers full, the paper's §5.2.3): on every avatar joint an IK
  // joint pivots at, a position task one level below the tracker layout and an orientation task
  // one level lower (body_rig.cpp says why); targets from setMarkers() before each solve. They
  // do not come from a tracking source: no filter, no loss guard.
  bool jointMarkers = false;
  struct SameBody {
    bool enabled = false;
    Eigen::Vector3d eyeOffset = Eigen::Vector3d::Zero();  // from the head joint, rest pose, tracking axes
    // Eigen's quaternion default constructor leaves it uninitialised: start from identity.
    std::array<Eigen::Quaterniond, tracking::kTrackerCount> reference = [] {
      std::array<Eigen::Quaterniond, tracking::kTrackerCount> r;
      r.fill(Eigen::Quaterniond::Identity());
      return r;
    }();  // tracker orientation at rest
  } sameBody;
};

}  // namespace embody::runtime
