#include "runtime/task_layout.h"

#include <algorithm>

#include "core/enum_names.h"

namespace embody::runtime {

using tracking::TrackerId;
using tracking::TrackerStatus;

constexpr EnumName<TaskKind> kTaskKindNames[] = {{TaskKind::Balance, "balance"},
                                                 {TaskKind::FootPlant, "foot_plant"},
                                                 {TaskKind::TrackerPosition, "position"},
                                                 {TaskKind::TrackerOrientation, "orientation"},
                                                 {TaskKind::InferredHips, "inferred_hips"},
                                                 {TaskKind::SeatedHip, "seated_hip"},
                                                 {TaskKind::SeatedKnee, "seated_knee"},
                                                 {TaskKind::SeatedPelvis, "seated_pelvis"},
                                                 {TaskKind::ClavicleRest, "clavicle_rest"},
                                                 {TaskKind::LimbPole, "pole"}};

std::string_view taskKindName(TaskKind kind) {
  return enumName(kTaskKindNames, kind);
}

TaskLayout taskLayoutFor(tracking::TrackerMask trackers) {
  TaskLayout l;
  const bool feet = trackers.has(TrackerId::LeftFoot) && trackers.has(TrackerId::RightFoot);
  l.inferLowerBody = !feet;
  // Three-point: 1 the support (the planted feet, and the centre of mass over them), 2 the head
  // position. Feet trackers: 1 the head position, 2 the feet. A tracked foot is the user's own
  // and may stand where this avatar's legs cannot reach while the eyes are where the HMD is (the
  // performer's legs longer, or a stride at the straight-knee singularity); the eyes are what a
  // user sees through, so the feet yield a few millimetres, not the eyes centimetres. Measured
  // with all six trackers (scripts/bvh_matrix.sh, 10 iterations at 60 Hz, head / hands p95),
  // feet above the head -> below it: `cmu_007_01` on the default avatar 19.1 / 0.2 -> 0.1 / 0.1 mm,
  // on the Mixamo fixture 88.9 / 50.4 -> 4.6 / 5.1 mm; `embody eval --trackers 6` (90 Hz, 4
  // iterations, 8 clips) MPJPE 3.03 -> 2.95 cm, feet 0.88 -> 0.95 cm (docs/runtime.md).
  const int headLevel = feet ? 1 : 2;
  for (auto foot : {TrackerId::LeftFoot, TrackerId::RightFoot}) {
    if (feet) {
      l.tasks.push_back({TaskKind::TrackerPosition, foot, 2, 1.0f});
      l.tasks.push_back({TaskKind::TrackerOrientation, foot, 2, 0.5f});
    } else {
      l.tasks.push_back({TaskKind::FootPlant, foot, 1, 1.0f});
    }
  }
  // Balance is an inequality (enabled only while the centre of mass leaves the support polygon)
  // and only where the lower body is inferred: with foot trackers the user's own feet are the
  // support, and a walking user is balanced dynamically, not statically (the CoM runs ahead of
  // the stance foot), so a static balance row would hold the tracked body back.
  if (l.inferLowerBody) l.tasks.push_back({TaskKind::Balance, TrackerId::Hips, 1, 1.0f});
  // The head position (the eyes): the user's viewpoint; a mismatch is seen at once in first
  // person. Its orientation is lower (4, or 5 with a tracked pelvis): in first person the view
  // turns with the HMD whatever the avatar's head does, and sharing a level with the position
  // would let the orientation rows trade eye position for head angle (least squares) whenever the
  // trunk is short of reach.
  if (trackers.has(TrackerId::Head)) l.tasks.push_back({TaskKind::TrackerPosition, TrackerId::Head, headLevel, 1.0f});
  // 3: hand positions.
  for (auto hand : {TrackerId::LeftHand, TrackerId::RightHand})
    if (trackers.has(hand)) l.tasks.push_back({TaskKind::TrackerPosition, hand, 3, 1.0f});
  // 4: orientations, which matter less than positions; the head's a level lower with a tracked
  // pelvis (below).
  const bool pelvis = trackers.has(TrackerId::Hips);
  if (trackers.has(TrackerId::Head))
    l.tasks.push_back({TaskKind::TrackerOrientation, TrackerId::Head, pelvis ? 5 : 4, 1.0f});
  for (auto hand : {TrackerId::LeftHand, TrackerId::RightHand})
    if (trackers.has(hand)) l.tasks.push_back({TaskKind::TrackerOrientation, hand, 4, 1.0f});
  // A tracked pelvis. 4: its position, over the ground only: its height follows from the head and
  // the legs, whose proportions differ between user and avatar, and when the scaled performer's
  // trunk is longer than the avatar's the pelvis must yield, not the head. Strict priorities keep
  // it from disturbing anything above to first order; its weight 0.1 damps it (a row scaled by √w
  // is damped as if λ were λ/√w), so while it conflicts its steps, and with them their
  // second-order pull on the levels above, stay small (docs/runtime.md).
  // 5: its orientation, on one level with the head's. Without it nothing held the pelvis's turn
  // (each leg's swivel and the spine's torsion leave it free) and the minimum-norm steps turned it
  // 38-96 degrees (p95, stats.json trackers.hips.turn_error_p95_deg) off the tracker's. Under the
  // head's orientation it was still 58-87 degrees off where the performer turned the head further
  // from the pelvis than the coupled spine twists: the pelvis took the rest. On one level the two
  // share it. Below the position, which it would otherwise pull off where the coupled spine cannot
  // take the performer's shape (the root 1.0 -> 3.5 cm). `embody eval --trackers 6` (8 clips,
  // 90 Hz, 4 iterations) MPJPE 2.63 -> 1.85 cm, every clip within 2.6 cm; --trackers 4 8.12 ->
  // 7.77 cm; scripts/bvh_matrix.sh pelvis turn p95 on the default avatar 39-70 -> 8-23 degrees
  // (docs/runtime.md, "Six trackers: the pelvis's turn").
  if (pelvis) {
    l.tasks.push_back({TaskKind::TrackerPosition, TrackerId::Hips, 4, 0.1f});
    l.tasks.push_back({TaskKind::TrackerOrientation, TrackerId::Hips, 5, 1.0f});
  }
  // 5 in three-point mode: the pelvis inferred from the head (task_targets_job.cpp: under it with
  // the rest offset, turned with its heading, the trunk leant forward when the head sinks, let go
  // in a deep squat), with the tracked pelvis's weight and for the same reasons. Without it the
  // pelvis went wherever the minimum-norm step left it: over the eight eval clips at 90 Hz, 4
  // iterations, MPJPE 9.70 -> 9.03 cm, upper body 5.81 -> 4.74, root 12.1 -> 7.7, collapsed
  // frames 22 -> 0; hands 0.58 -> 0.67, head 1.37 -> 1.46 (docs/eval.md).
  // With a tracked pelvis and no feet (four trackers) it stays beside the tracked pelvis's rows:
  // without it `embody eval --trackers 4` went 7.77 -> 7.87 cm (head 1.48 -> 1.66).
  if (l.inferLowerBody) l.tasks.push_back({TaskKind::InferredHips, TrackerId::Hips, 5, 0.1f});
  // Lowest: where knees and elbows point (pole_tasks.h). Every tracker leaves each limb a free
  // turn about its root-to-end line; these take only that freedom, so they never pull a tracked
  // point off. Low weight: their targets move with the body and need not be met exactly.
  const int poles = l.levels() + 1;
  for (auto id : {TrackerId::LeftFoot, TrackerId::RightFoot, TrackerId::LeftHand, TrackerId::RightHand})
    l.tasks.push_back({TaskKind::LimbPole, id, poles, 0.3f});
  // Below them all: each clavicle at its rest turn on the chest (body_rig.cpp). The hand tasks
  // recruit the clavicles, and minimum-norm steps spread an arm's motion over clavicle and shoulder
  // alike: nothing brought them back, and on the CMU walk the right clavicle hung 17-21 degrees
  // lowered and 10-13 back (the shoulder joint 13 cm off) with the hand on its target. Lowest, it
  // only takes the freedom every other task leaves, and it lets go as a hand's target nears the
  // arm's reach (task_targets_job.cpp), so a hand beyond it still raises its clavicle. Weight 0.1:
  // with 0.3 or 1.0 the solution's jitter rose more (embody eval, three trackers, eight clips,
  // before the let-go: x clip 2.06 / 2.10 against 2.02, upper body 3.78 / 3.79 against 3.77 cm;
  // docs/eval.md, "Session 16").
  const int clavicles = l.levels() + 1;
  for (auto hand : {TrackerId::LeftHand, TrackerId::RightHand}) l.tasks.push_back({TaskKind::ClavicleRest, hand, clavicles, 0.1f});
  return l;
}

TaskLayout seatedTaskLayoutFor(tracking::TrackerMask trackers) {
  TaskLayout l;
  l.seated = true;
  // 1: the seat. Both hip joint centres (the pelvis can only pitch about the line through them:
  // leaning bends the hips and the spine, never lifts the pelvis), the knees (the one free turn of
  // each leg about its hip-ankle line) and the feet (position and orientation, flat). The targets
  // are one consistent rigid leg pose (seated_pose.h), so this level is met exactly.
  for (auto foot : {TrackerId::LeftFoot, TrackerId::RightFoot}) {
    l.tasks.push_back({TaskKind::SeatedHip, foot, 1, 1.0f});
    l.tasks.push_back({TaskKind::SeatedKnee, foot, 1, 1.0f});
    l.tasks.push_back({TaskKind::FootPlant, foot, 1, 1.0f});
  }
  // 2: the head position, as standing.
  if (trackers.has(TrackerId::Head)) l.tasks.push_back({TaskKind::TrackerPosition, TrackerId::Head, 2, 1.0f});
  // 3: the hand positions, as standing.
  for (auto hand : {TrackerId::LeftHand, TrackerId::RightHand})
    if (trackers.has(hand)) l.tasks.push_back({TaskKind::TrackerPosition, hand, 3, 1.0f});
  // 4: the pelvis upright, facing the seat, weight 0.1. With the hip joints pinned the pelvis
  // can only pitch about them; this level leaves a lean to the spine wherever the head and hands
  // leave it the freedom, so the pelvis tilts (the hips flex past 90 degrees) for the rest. Where
  // it was tried instead:
  //   - lowest (under the orientations, which leave it no freedom): a lean became pelvis tilt
  //     alone, 30 degrees with a straight spine;
  //   - above the hands (3): the shoulders stayed back and the hands out of reach when the user
  //     leant sideways and forward;
  //   - with a target tilted by a share of the lean (a lumbopelvic rhythm): where the coupled
  //     spine's bands sat at their limits the head stalled 2-3 cm off its target.
  // The low weight damps its steps while it conflicts (as the tracked pelvis's row standing).
  l.tasks.push_back({TaskKind::SeatedPelvis, TrackerId::Hips, 4, 0.1f});
  // 5: the orientations (level 4 standing).
  if (trackers.has(TrackerId::Head)) l.tasks.push_back({TaskKind::TrackerOrientation, TrackerId::Head, 5, 1.0f});
  for (auto hand : {TrackerId::LeftHand, TrackerId::RightHand})
    if (trackers.has(hand)) l.tasks.push_back({TaskKind::TrackerOrientation, hand, 5, 1.0f});
  return l;
}

int TaskLayout::levels() const {
  int m = 0;
  for (const auto& t : tasks) m = std::max(m, t.priority);
  return m;
}

std::string TaskLayout::describe() const {
  std::string s;
  for (const auto& t : tasks) {
    s += "  " + std::to_string(t.priority) + "  " + std::string(taskKindName(t.kind));
    if (t.kind == TaskKind::SeatedHip || t.kind == TaskKind::SeatedKnee)
      s += t.tracker == TrackerId::LeftFoot ? " left" : " right";
    else if (t.kind == TaskKind::ClavicleRest)
      s += t.tracker == TrackerId::LeftHand ? " left" : " right";
    else if (t.kind == TaskKind::LimbPole)
      s += std::string(t.tracker == TrackerId::LeftFoot || t.tracker == TrackerId::RightFoot ? " knee" : " elbow") +
           (t.tracker == TrackerId::LeftFoot || t.tracker == TrackerId::LeftHand ? " left" : " right");
    else if (t.kind != TaskKind::Balance && t.kind != TaskKind::InferredHips && t.kind != TaskKind::SeatedPelvis)
      s += " " + std::string(tracking::trackerKey(t.tracker));
    if (t.weight != 1.0f) s += " (weight " + std::to_string(t.weight).substr(0, 4) + ")";
    s += "\n";
  }
  if (seated) s += "  seated: the lower body sits on the seat, the spine and arms follow the head and hands\n";
  else if (inferLowerBody) s += "  lower body inferred: feet planted, stepping when the user walks or turns\n";
  return s;
}

float statusWeight(TrackerStatus status) {
  switch (status) {
    case TrackerStatus::Tracked:
    case TrackerStatus::Recovering:
    case TrackerStatus::Held:
    case TrackerStatus::Easing: return 1.0f;
    case TrackerStatus::Neutral: return 0.3f;
    case TrackerStatus::Absent: return 0.0f;
  }
  return 0.0f;
}

}  // namespace embody::runtime
