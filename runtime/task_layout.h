#pragma once
// Trackers -> IK tasks: which tasks the runtime asks the solver for, at which priority, for the
// trackers a source provides. Data only: the body model and PIK solver turn it into Jacobian
// rows. Priority 1 is the most important (strict priorities, Baerlocher & Boulic 2004);
// the ordering follows Raunhardt & Boulic 2008 section 5.2: balance and support first, then the
// end effectors the user sees, then the rest. docs/runtime.md has the table and the reasons.
#include <string>
#include <vector>

#include "tracking/tracking_guard.h"

namespace embody::runtime {

enum class TaskKind : uint8_t {
  Balance,           // centre of mass projected on the floor, over the support polygon (2 rows)
  FootPlant,         // an inferred planted foot (three-point mode): position + orientation
  TrackerPosition,   // a tracker's position (3 rows)
  TrackerOrientation, // a tracker's orientation (3 rows)
  InferredHips,       // three-point mode: the pelvis under the head, upright, facing the heading
  SeatedHip,          // seated mode: a hip joint centre on the seat (3 rows; `tracker` names the side's foot)
  SeatedKnee,         // seated mode: a knee ahead of its hip joint over the planted foot (3 rows)
  SeatedPelvis,       // seated mode: the pelvis upright, facing the seat (3 rows)
  ClavicleRest,       // a clavicle at its rest turn on its parent bone (`tracker` = the side's hand; 3 rows)
  LimbPole            // a knee (`tracker` = the side's foot) or an elbow (the side's hand) on its
                      // limb's swivel circle in the anatomical direction (pole_tasks.h; 3 rows)
};

struct TaskSpec {
  TaskKind kind = TaskKind::TrackerPosition;
  tracking::TrackerId tracker = tracking::TrackerId::Head;  // for tracker and foot tasks
  int priority = 1;
  float weight = 1.0f;  // within its level
};

struct TaskLayout {
  std::vector<TaskSpec> tasks;  // by priority, then tracker
  bool inferLowerBody = false;  // no foot trackers: feet planted and stepping procedurally
  bool seated = false;          // seated mode: the lower body sits on a seat (seatedTaskLayoutFor)
  int levels() const;
  std::string describe() const;  // one line per task, for `embody motion info` and logs
};

// The layout for the trackers a source provides (e.g. threePoint() or all()).
TaskLayout taskLayoutFor(tracking::TrackerMask trackers);

// Seated mode: the lower body sits (hip joints, knees and feet pinned at priority 1), then the
// head position (2), the hand positions (3), the pelvis upright (4: a lean bends the spine where
// the head and hands leave it free, the pelvis tilts for the rest) and the orientations (5). Hips
// and feet trackers are unused.
TaskLayout seatedTaskLayoutFor(tracking::TrackerMask trackers);

// How strongly a target with this status should pull (0 = drop the task this frame). Held and
// easing targets still drive their limb; a never-tracked hand's neutral pose pulls gently.
float statusWeight(tracking::TrackerStatus status);

std::string_view taskKindName(TaskKind kind);

}  // namespace embody::runtime
