#pragma once
// Three-point mode (head and hands only, e.g. an HMD with two controllers): where the feet are.
// The feet stay planted while the body's centre stays over them; when the user walks or turns far
// enough, the avatar steps, one foot at a time, instead of sliding or twisting its legs.
//
// Works in the avatar's model space (metres, `up` the avatar's vertical). Each frame it takes the
// body centre inferred from the head (the point under the neck, and the heading), keeps a
// low-passed ground velocity, and for each foot:
//   planted   its target is fixed in the world (a level-0 task: it does not slide);
//   swinging  it travels from where it lifted to a landing spot on an arc `liftHeight` high over
//             `stepSeconds` (smoothstep along the ground, a squared sine up: it lifts and lands
//             at zero vertical speed); the landing spot keeps following the body until 70 % of
//             the swing, then is fixed.
// A planted foot left behind the body rises on its toes about the ball of the foot (the ball
// stays put), and lets the heel down over its next swing.
// A step starts (only one foot swings at a time, after `doubleSupportSeconds` on both feet) when
// a foot is farther than the threshold from where it would stand under the body, turned more than
// `turnRadians` from the heading, or the centre of mass has left the support polygon. While the
// body moves (over `movingSpeed` along the ground, rising or sinking slower than `maxClimb` of
// that: reaching down is not walking; and travelling: its velocity averaged over
// `travelSmoothing` over `travelSpeed`, or its centre farther than `standThreshold` from over the
// feet, so a body swaying on the spot does not walk) the threshold is `walkThreshold` and the
// landing spot leads the body by its velocity times the swing's rest and `quickAheadShare` of a
// step (eased in and out over `leadEasing`): the foot comes down a little ahead of the body and
// trails it through the stance. A planted foot farther than
// `reachRadius` from where it would stand lifts at once, even while the other swings.
// The foot that stepped last waits for the other unless the other is already where it should be:
// feet alternate.
// Walking with the head dipping once a step (gait_clock.h), the steps keep the walker's rhythm
// instead, while the body travels: each lands on a dip, the foot the head sways towards, the swing
// as long as the walk's stride needs, while that stride fits the avatar's legs (stepRhythm). A
// planted foot that reaches its leg's limit then swings until its own dip, not as a quick step.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <vector>

#include "runtime/gait_clock.h"

namespace embody::runtime {

struct FootPlannerConfig {
  double stepSeconds = 0.3;          // one swing
  double doubleSupportSeconds = 0.04;
  double liftHeight = 0.07;          // metres at the avatar's scale (scaled by `scale` below)
  double walkThreshold = 0.05;       // foot error that starts a step while the body moves
  double standThreshold = 0.22;      // ... while it stands (leaning does not make it step)
  double movingSpeed = 0.15;         // m/s: above this the body counts as moving ...
  double maxClimb = 0.5;             // ... while it sinks or rises slower than this times that
  double turnRadians = 0.55;         // ~30 degrees
  double velocitySmoothing = 0.15;   // seconds, low-pass time constant of the body's velocity
  double travelSpeed = 0.3;          // m/s: ... and while its travel (below) is over this
  double travelSmoothing = 1.0;      // seconds, the travel's time constant: a sway averages out
  double leadEasing = 0.2;           // seconds over which the landing spots start or stop leading
  // How far past the landing a moving body's landing spot leads it, in steps (`stepSeconds`),
  // while the steps are the planner's own (no walker's rhythm, below). Half a step was meant to
  // put the body over each foot at mid-stance, but the quick steps' stances are short. 0.15,
  // swept from 0 to 0.5 with `embody eval --fps 60,90,120` (3 trackers, 4 iterations, the eight
  // clips): MPJPE 7.50 -> 7.33 cm, jitter x clip 2.10 -> 1.81, foot skating 59 -> 45 cm/s,
  // reversed knee/elbow frames 125/45 -> 103/29; every share from 0.05 to 0.3 beat 0.5. Most on
  // cmu_007_01, a walk with a level head (all quick steps): skating 187 -> 40 cm/s (docs/eval.md).
  double quickAheadShare = 0.15;
  double reachRadius = 0.45;         // a planted foot this far from its spot lifts at once
  // Walking with the head dipping once a step (gait_clock.h), steps land on the dips, the foot
  // the sway names, while a step's travel fits twice reachRadius; the swing is at least
  // swingShare of the step, and long enough (up to the step less doubleSupportSeconds) that the
  // body passes over a planted foot for at most strideReach of twice reachRadius. The
  // landing spot then leads the body by aheadShare of the step (in cmu_12_01_walk a foot comes
  // flat 0.25-0.29 m ahead of the hips, at 1.0-1.13 m/s and 0.64 s steps: 0.35-0.4).
  bool followHeadDips = true;
  double swingShare = 0.75;
  double strideReach = 0.8;
  double aheadShare = 0.4;
  GaitClockConfig gait;
  // A planted foot left behind the body rises on its toes, as people's do from mid-stance on:
  // its heel lifts about the ball of the foot from heelRiseStart of reachRadius behind to
  // maxHeelRise at reachRadius, which lets the leg reach a walking stride.
  double heelRiseStart = 0.2;
  double maxHeelRise = 0.6;  // radians
};

// A foot's sole on the ground, for the support polygon: the ankle's ground point, the heel behind
// it and the toes ahead along the foot's heading, half the foot's width either side.
struct FootShape {
  double heelBack = 0.06, toeForward = 0.16, halfWidth = 0.045;
  double ball = 0.11;  // the ball of the foot ahead of the ankle: a rising heel pivots there
};

struct FootTarget {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // ankle (the IK foot joint's pivot)
  double yaw = 0.0;                                    // heading about `up` (radians)
  double roll = 0.0;  // the heel raised about the ball of the foot (radians, toes down)
  bool planted = true;
};

class FootPlanner {
 public:
  // `restAnkle` are the avatar's rest ankle positions relative to the body centre's ground point
  // at rest (left, right); `up` and `forward` the avatar's axes.
  void configure(const FootPlannerConfig& config, const FootShape& shape, const Eigen::Vector3d& up,
                 const Eigen::Vector3d& forward, const std::array<Eigen::Vector3d, 2>& restAnkleOffset, double scale);
  // Plants both feet under a body centre (ground point) with a heading; forgets the velocity.
  void reset(const Eigen::Vector3d& centre, double yaw, double time);
  // One frame: the body centre inferred from the head (any height; it is projected), its heading,
  // and the current centre of mass. Returns the foot targets for this frame.
  const std::array<FootTarget, 2>& update(double time, const Eigen::Vector3d& centre, double yaw,
                                          const Eigen::Vector3d& centerOfMass);
  const std::array<FootTarget, 2>& feet() const { return out_; }
  // Where a foot meets the ground: the ball of the foot. A planted foot's stays put while its
  // heel rises.
  Eigen::Vector3d ballPoint(int foot) const;
  bool initialised() const { return initialised_; }
  void restart() { initialised_ = false; }  // the next update() plants both feet afresh
  int steps() const { return steps_; }  // since construction: a re-plant (reset) keeps the count
  int lastStepFoot() const { return lastFoot_; }
  // Balance: whether the ground projection of `point` is over the support polygon (the planted
  // feet plus the landing spot of a swinging foot), and the nearest point of it (`margin` inside).
  bool overSupport(const Eigen::Vector3d& point) const;
  Eigen::Vector3d nearestSupportPoint(const Eigen::Vector3d& point, double margin) const;
  Eigen::Vector3d groundVelocity() const { return velocity_; }
  // The body's travel: its ground velocity averaged over `travelSmoothing`.
  Eigen::Vector3d travel() const { return travel_; }
  // 0 standing .. 1 walking (the landing spots' lead, eased over `leadEasing`).
  double walking() const { return leadWeight_; }
  const GaitClock& gait() const { return gait_; }

 private:
  struct Swing {
    bool active = false;
    double start = 0.0;
    Eigen::Vector3d from = Eigen::Vector3d::Zero(), to = Eigen::Vector3d::Zero();
    double fromYaw = 0.0, toYaw = 0.0;
    double duration = 0.3;  // seconds
    double fromRoll = 0.0;  // the heel's rise at lift-off, let down over the swing
    Eigen::Vector3d rollOffset = Eigen::Vector3d::Zero();  // the rolled ankle's offset at lift-off
    double ahead = 0.15;    // seconds the landing spot leads the moving body by
  };
  Eigen::Vector3d ground(const Eigen::Vector3d& p) const { return p - up_ * up_.dot(p); }
  Eigen::Vector3d standSpot(int foot, const Eigen::Vector3d& centre, double yaw) const;
  Eigen::Vector3d uncrossed(int foot, const Eigen::Vector3d& spot, double yaw) const;
  Eigen::Vector2d plane(const Eigen::Vector3d& p) const { return {p.dot(axisA_), p.dot(axisB_)}; }
  void buildSupport();
  void startSwing(int foot, double time, double duration, double ahead, const Eigen::Vector3d& to, double toYaw);
  struct Rhythm {
    double swing;          // seconds
    double ahead;          // seconds the landing spot leads a moving body by
    bool due;              // whether a step may start now
    int foot;              // the foot that must step (-1: the planner's choice)
    double beat, period;   // with a foot named: the next beat (seconds) and the step between beats
  };
  Rhythm stepRhythm(double time, bool walking, double speed) const;
  Eigen::Vector3d centreOverFeet() const;  // where the planted feet's body centre would stand

  FootPlannerConfig config_;
  FootShape shape_;
  Eigen::Vector3d up_ = Eigen::Vector3d::UnitY(), forward_ = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d axisA_ = Eigen::Vector3d::UnitX(), axisB_ = Eigen::Vector3d::UnitZ();
  std::array<Eigen::Vector3d, 2> restOffset_{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  double scale_ = 1.0;
  std::array<FootTarget, 2> feet_{};  // flat: a planted foot's ankle where it was put down
  std::array<FootTarget, 2> out_{};    // what update() returns: heels raised, swings let down
  void rollHeels(const Eigen::Vector3d& centre, double yaw, double time);
  std::array<Swing, 2> swing_{};
  double floorHeight_ = 0.0;
  Eigen::Vector3d lastCentre_ = Eigen::Vector3d::Zero(), velocity_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d travel_ = Eigen::Vector3d::Zero();  // the velocity over `travelSmoothing`
  double lastHeight_ = 0.0, verticalSpeed_ = 0.0;  // the centre's, low-passed as the velocity
  double lastTime_ = 0.0, lastLanding_ = -1e9, travelSince_ = 0.0;
  double leadWeight_ = 0.0;  // 0 standing .. 1 walking, eased over `leadEasing`
  GaitClock gait_;
  int lastFoot_ = -1, steps_ = 0;
  bool initialised_ = false;
  std::vector<Eigen::Vector2d> points_, hull_;  // support polygon (reserved: no per-frame allocation)
};

// Heading (radians about `up`, 0 = `forward`, positive turning towards `up x forward`) of a
// direction on the ground (0 when it is vertical): a travel's, a velocity's.
double headingOfDirection(const Eigen::Vector3d& f, const Eigen::Vector3d& up, const Eigen::Vector3d& forward);
// The same for a rotation that maps `forward` somewhere: where its forward points on the ground (0 when straight
// up or down). For a body segment: the pelvis's heading, the feet's.
double headingOf(const Eigen::Quaterniond& q, const Eigen::Vector3d& up, const Eigen::Vector3d& forward);
// The same for a head's turn: where the face points, also looking straight down or past the
// vertical (the turned `up` fills in as the forward leaves the ground plane). Not for the pelvis:
// its up vector brings its roll into the heading, and the knee poles taken from it made a body
// reaching beyond both arms' span cycle by 0.6 mm a frame.
double faceHeadingOf(const Eigen::Quaterniond& q, const Eigen::Vector3d& up, const Eigen::Vector3d& forward);
Eigen::Quaterniond yawRotation(double yaw, const Eigen::Vector3d& up);
// An angle (radians) brought into [-pi, pi]: the shorter way round between two headings.
double wrapAngle(double radians);

}  // namespace embody::runtime
