#include "runtime/foot_planner.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/smoothstep.h"

namespace embody::runtime {

namespace {

constexpr double kPi = std::numbers::pi;


double cross2(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
}

// Andrew's monotone chain into `hull` (counter-clockwise); `pts` is reordered.
void convexHull(std::vector<Eigen::Vector2d>& pts, std::vector<Eigen::Vector2d>& hull) {
  std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  hull.clear();
  if (pts.size() < 3) {
    hull = pts;
    return;
  }
  for (int pass = 0; pass < 2; ++pass) {
    const size_t start = hull.size();
    for (size_t k = 0; k < pts.size(); ++k) {
      const Eigen::Vector2d& p = pass == 0 ? pts[k] : pts[pts.size() - 1 - k];
      while (hull.size() >= start + 2 && cross2(hull[hull.size() - 2], hull.back(), p) <= 0.0) hull.pop_back();
      hull.push_back(p);
    }
    hull.pop_back();
  }
}

Eigen::Vector2d nearestOnSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return a + t * ab;
}

}  // namespace

double wrapAngle(double radians) { return std::remainder(radians, 2.0 * kPi); }

Eigen::Quaterniond yawRotation(double yaw, const Eigen::Vector3d& up) { return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, up)); }

namespace {
// The swinging foot's height over the ground, as a share of the lift, at `phase` of the swing: a
// squared sine, which leaves and meets the ground at zero vertical speed. The plain sine bump it
// replaces lifted the foot at 0.73 m/s from one frame to the next (0.07 m over a 0.3 s swing) and
// put it down as abruptly: a jerk the top-level foot task handed to the legs and the pelvis every
// step (embody eval, three trackers: jitter x clip 2.10 -> 1.92 over the eight clips, every one
// smoother, MPJPE unchanged; docs/eval.md, session 16).
double liftProfile(double phase) {
  const double s = std::sin(kPi * phase);
  return s * s;
}
}  // namespace

double headingOfDirection(const Eigen::Vector3d& f, const Eigen::Vector3d& up, const Eigen::Vector3d& forward) {
  const Eigen::Vector3d side = up.cross(forward);
  const double x = f.dot(forward), y = f.dot(side);
  if (x * x + y * y < 1e-12) return 0.0;
  return std::atan2(y, x);
}

double headingOf(const Eigen::Quaterniond& q, const Eigen::Vector3d& up, const Eigen::Vector3d& forward) {
  return headingOfDirection(q * forward, up, forward);
}

double faceHeadingOf(const Eigen::Quaterniond& q, const Eigen::Vector3d& up, const Eigen::Vector3d& forward) {
  // Looking down (or up) the turned forward's ground projection shrinks and, past the vertical,
  // flips; a head bent over and turned to look at one leg swings it far round (turned 35 degrees
  // about its own up at 55 degrees down, it reads 51 degrees). The turned up vector points the way
  // the face does there, so it is blended in by how far the forward leaves the ground plane (as
  // tracking::headingOf does in tracking space: 29 degrees for that head). With the forward alone
  // the user washing the legs in cmu_002_10 had the inferred pelvis turned 60-130 degrees from
  // theirs and the knees pointing backwards for 264 frames (docs/eval.md, "Session 14").
  const Eigen::Vector3d f = q * forward;
  return headingOfDirection(f - f.dot(up) * (q * up), up, forward);
}

void FootPlanner::configure(const FootPlannerConfig& config, const FootShape& shape, const Eigen::Vector3d& up,
                            const Eigen::Vector3d& forward, const std::array<Eigen::Vector3d, 2>& restAnkleOffset,
                            double scale) {
  config_ = config;
  shape_ = shape;
  up_ = up.normalized();
  forward_ = (forward - up_ * up_.dot(forward)).normalized();
  axisA_ = forward_;
  axisB_ = up_.cross(forward_);
  restOffset_ = restAnkleOffset;
  scale_ = scale;
  gait_.configure(config.gait, scale);
  points_.reserve(16);
  hull_.reserve(16);
  initialised_ = false;
}

Eigen::Vector3d FootPlanner::standSpot(int foot, const Eigen::Vector3d& centre, double yaw) const {
  const Eigen::Vector3d offset = yawRotation(yaw, up_) * ground(restOffset_[static_cast<size_t>(foot)]);
  return ground(centre) + offset + up_ * floorHeight_;
}

// A landing spot kept on its own side of the other foot: at least half the stance width from it
// across the heading `yaw`. Without this a turn or a sidestep could land a foot across the planted
// one (the body's heading moves on while the planted foot stays), and the legs crossed: on the eval
// clips the collapse guard then re-seeded the body 2-10 times a clip (docs/runtime.md).
Eigen::Vector3d FootPlanner::uncrossed(int foot, const Eigen::Vector3d& spot, double yaw) const {
  const size_t other = static_cast<size_t>(1 - foot);
  const Eigen::Vector3d otherAnkle = swing_[other].active ? swing_[other].to : feet_[other].position;
  const Eigen::Vector3d side = yawRotation(yaw, up_) * axisB_;
  const double restSide = (restOffset_[static_cast<size_t>(foot)] - restOffset_[other]).dot(axisB_);
  const double sign = restSide >= 0.0 ? 1.0 : -1.0;
  const double minimum = 0.5 * std::abs(restSide);
  const double across = sign * (spot - otherAnkle).dot(side);
  return across >= minimum ? spot : Eigen::Vector3d(spot + sign * (minimum - across) * side);
}

void FootPlanner::reset(const Eigen::Vector3d& centre, double yaw, double time) {
  floorHeight_ = up_.dot(restOffset_[0]);  // the rest ankle height above the centre's ground point
  for (int f = 0; f < 2; ++f) {
    feet_[static_cast<size_t>(f)] = {standSpot(f, centre, yaw), yaw, true};
    swing_[static_cast<size_t>(f)].active = false;
  }
  lastCentre_ = ground(centre);
  velocity_.setZero();
  travel_.setZero();
  travelSince_ = time;
  leadWeight_ = 0.0;
  lastHeight_ = up_.dot(centre);
  verticalSpeed_ = 0.0;
  lastTime_ = time;
  lastLanding_ = time - 1.0;
  lastFoot_ = -1;
  gait_.reset();
  initialised_ = true;
  out_ = feet_;
  buildSupport();
}

const std::array<FootTarget, 2>& FootPlanner::update(double time, const Eigen::Vector3d& centreIn, double yaw,
                                                     const Eigen::Vector3d& centerOfMass) {
  if (!initialised_) reset(centreIn, yaw, time);
  const Eigen::Vector3d centre = ground(centreIn);
  const double height = up_.dot(centreIn);
  const double dt = time - lastTime_;
  Eigen::Vector3d instant = Eigen::Vector3d::Zero();
  if (dt > 0.0 && dt < 0.5) {
    instant = (centre - lastCentre_) / dt;
    const double a = 1.0 - std::exp(-dt / config_.velocitySmoothing);
    velocity_ += a * (instant - velocity_);
    // The mean since the reset until there is a time constant's worth, then exponential: a body
    // planted mid-walk (a clip's first frame, tracking regained) reads as walking at once.
    const double weight = std::max(1.0 - std::exp(-dt / config_.travelSmoothing), dt / std::max(time - travelSince_, dt));
    travel_ += weight * (instant - travel_);
    verticalSpeed_ += a * ((height - lastHeight_) / dt - verticalSpeed_);
  } else if (dt >= 0.5) {
    velocity_.setZero();
    travel_.setZero();
    travelSince_ = time;
    verticalSpeed_ = 0.0;
  }
  lastCentre_ = centre;
  lastHeight_ = height;
  lastTime_ = time;
  const double step = config_.stepSeconds;
  // The sideways sway: the centre's velocity across its travel, against the travel's mean.
  const double travelled = travel_.norm();
  const Eigen::Vector3d left = travelled > 1e-9 ? Eigen::Vector3d(up_.cross(travel_) / travelled) : Eigen::Vector3d::Zero();
  gait_.update(time, height, (instant - travel_).dot(left));
  // Walking keeps the head's height; reaching down or standing up moves the inferred centre too
  // (forward with the head, then back once the bend is recognised), and taken for walking it made
  // a user picking something up shuffle: 6 steps, the feet 24 cm from where they stood
  // (body_plausibility_tests). So the body moves only while the centre's vertical speed stays
  // under `maxClimb` of its ground speed, and only a moving body's landing spots lead it.
  const double groundSpeed = velocity_.norm();
  // Travelling, not swaying: a boxer's or a dancer's head moves 0.3-1 m/s back and forth, and
  // taken for walking it stepped the feet 15 m over a clip where the performer's moved 1.6 m
  // (cmu_002_05; docs/eval.md, "Session 15"). Far from its feet a body travels whatever its
  // average says (a leap starts faster than the average follows), and so does one turned half a
  // step's turn from its feet: turning on the spot, the centre circles and averages out too.
  const double feetTurn = std::max(std::abs(wrapAngle(yaw - feet_[0].yaw)), std::abs(wrapAngle(yaw - feet_[1].yaw)));
  const bool travels = travelled > config_.travelSpeed * scale_;
  const bool travelling = travels ||
                          (centre - centreOverFeet()).norm() > config_.standThreshold * scale_ || feetTurn > 0.5 * config_.turnRadians;
  const bool moving = groundSpeed > config_.movingSpeed * scale_ && std::abs(verticalSpeed_) < config_.maxClimb * groundSpeed && travelling;
  // The lead eases in and out: switched, it moved a swinging foot's landing spot by up to half a
  // step in one frame.
  if (dt > 0.0) leadWeight_ = std::clamp(leadWeight_ + (moving ? dt : -dt) / config_.leadEasing, 0.0, 1.0);
  const Eigen::Vector3d lead = leadWeight_ * velocity_;
  // Where a foot landing after `remaining` seconds should go: under the body then, `ahead`
  // seconds ahead of it while it moves.
  auto landing = [&](int f, double remaining, double ahead) {
    return uncrossed(f, standSpot(f, centre + lead * (remaining + ahead), yaw), yaw);
  };

  // Swinging feet move along their arcs; a landing ends the swing.
  bool swinging = false;
  for (int f = 0; f < 2; ++f) {
    Swing& s = swing_[static_cast<size_t>(f)];
    FootTarget& foot = feet_[static_cast<size_t>(f)];
    if (!s.active) continue;
    const double phase = std::clamp((time - s.start) / s.duration, 0.0, 1.0);
    if (phase < 0.7) {
      s.to = landing(f, (1.0 - phase) * s.duration, s.ahead);
      s.toYaw = yaw;
    }
    if (phase >= 1.0) {
      s.active = false;
      foot = {s.to, s.toYaw, true};
      lastLanding_ = time;
      continue;
    }
    swinging = true;
    const double u = smoothstep(phase);
    foot.position = s.from + u * (s.to - s.from) + up_ * (config_.liftHeight * scale_ * liftProfile(phase));
    foot.yaw = s.fromYaw + u * wrapAngle(s.toYaw - s.fromYaw);
    foot.planted = false;
  }

  // A walk travels: a body swaying or turning on the spot (moving, not travelling) keeps its quick
  // steps whatever its head does.
  const Rhythm rhythm = stepRhythm(time, moving && travels, std::max(groundSpeed, travelled));
  const double swingTime = rhythm.swing, ahead = rhythm.ahead;

  // A planted foot left beyond its leg's reach (a leap, a spin) lifts at once, even while the
  // other swings: planted, it is the IK's top level and would drag the head and hands
  // (cmu_131_03's spinning leap: the head 20-70 cm off for a third of a second).
  for (int f = 0; f < 2; ++f) {
    const FootTarget& foot = feet_[static_cast<size_t>(f)];
    if (swing_[static_cast<size_t>(f)].active ||
        ground(standSpot(f, centre, yaw) - foot.position).norm() <= config_.reachRadius * scale_)
      continue;
    // Walking to a rhythm, the foot swings until its own beat (the next, or the one after where
    // the next is the other foot's), up to a step long: lifted as a quick step instead, it
    // landed between the beats and stepped again on its beat.
    double swing = step;
    if (rhythm.foot >= 0) {
      const double beat = rhythm.beat + (rhythm.foot == f ? 0.0 : rhythm.period);
      swing = std::clamp(beat - time, step, rhythm.period);
    }
    startSwing(f, time, swing, ahead, landing(f, swing, ahead), yaw);
    swinging = true;
  }

  // Start a step when a foot is out of place and both feet have been down long enough.
  if (!swinging && rhythm.due && time - lastLanding_ >= config_.doubleSupportSeconds) {
    const double threshold = (moving ? config_.walkThreshold : config_.standThreshold) * scale_;
    const bool unbalanced = !overSupport(centerOfMass);
    std::array<double, 2> need{};
    for (int f = 0; f < 2; ++f) {
      const FootTarget& foot = feet_[static_cast<size_t>(f)];
      const double dist = ground(landing(f, swingTime, ahead) - foot.position).norm();
      const double turn = std::abs(wrapAngle(yaw - foot.yaw));
      need[static_cast<size_t>(f)] = std::max(dist / threshold, turn / config_.turnRadians);
    }
    int pick = need[0] >= need[1] ? 0 : 1;
    // Alternate: the foot that stepped last waits while the other one has somewhere to go.
    if (pick == lastFoot_ && need[static_cast<size_t>(1 - pick)] > 0.3) pick = 1 - pick;
    if (rhythm.foot >= 0) pick = rhythm.foot;
    if (need[static_cast<size_t>(pick)] >= 1.0 || (unbalanced && need[static_cast<size_t>(pick)] > 0.2))
      startSwing(pick, time, swingTime, ahead, landing(pick, swingTime, ahead), yaw);
  }
  buildSupport();
  rollHeels(centre, yaw, time);
  return out_;
}

// The returned feet: a planted foot behind the body on its toes, a swinging one letting its heel
// down from the rise it lifted off with.
void FootPlanner::rollHeels(const Eigen::Vector3d& centre, double yaw, double time) {
  const double start = config_.heelRiseStart * config_.reachRadius * scale_, end = config_.reachRadius * scale_;
  for (size_t f = 0; f < 2; ++f) {
    const FootTarget& foot = feet_[f];
    FootTarget& out = out_[f];
    out = foot;
    const Swing& s = swing_[f];
    if (s.active) {
      const double u = 1.0 - smoothstep(std::clamp((time - s.start) / s.duration, 0.0, 1.0));
      out.roll = u * s.fromRoll;
      out.position += u * s.rollOffset;
      continue;
    }
    const Eigen::Vector3d forward = yawRotation(foot.yaw, up_) * forward_;
    const double behind = -ground(foot.position - standSpot(int(f), centre, yaw)).dot(forward);
    out.roll = end > start ? config_.maxHeelRise * smoothstep(std::clamp((behind - start) / (end - start), 0.0, 1.0)) : 0.0;
    if (out.roll <= 0.0) continue;
    // The ankle turns about the ball of the foot on the ground, `ball` ahead and the ankle's
    // height below it; toes down is a turn about the foot's left (up x forward).
    const Eigen::Vector3d pivot = ballPoint(int(f));
    out.position = pivot + Eigen::AngleAxisd(out.roll, up_.cross(forward)) * (foot.position - pivot);
  }
}

Eigen::Vector3d FootPlanner::ballPoint(int f) const {
  const FootTarget& foot = feet_[static_cast<size_t>(f)];
  return foot.position + scale_ * shape_.ball * (yawRotation(foot.yaw, up_) * forward_) - up_ * floorHeight_;
}

void FootPlanner::startSwing(int f, double time, double duration, double ahead, const Eigen::Vector3d& to, double toYaw) {
  Swing& s = swing_[static_cast<size_t>(f)];
  FootTarget& foot = feet_[static_cast<size_t>(f)];
  s.active = true;
  s.start = time;
  s.duration = duration;
  s.fromRoll = out_[static_cast<size_t>(f)].roll;
  s.rollOffset = out_[static_cast<size_t>(f)].position - foot.position;
  s.ahead = ahead;
  s.from = foot.position;
  s.fromYaw = foot.yaw;
  s.to = to;
  s.toYaw = toYaw;
  foot.planted = false;
  lastFoot_ = f;
  ++steps_;
}

// The rhythm of the next step. Standing, or walking without a regular head dip: quick steps
// (stepSeconds) as soon as doubleSupportSeconds allow, landing quickAheadShare of a step ahead of
// a moving body. Walking with one (gait_clock.h), steps land on the dips, the foot the sway names.
//
// `walking`: the body moves and travels. `speed` is the body's ground speed, the larger of the
// low-passed velocity and the travel (its mean since a walk started: the velocity trails a
// walk's start).
FootPlanner::Rhythm FootPlanner::stepRhythm(double time, bool walking, double speed) const {
  const double step = config_.stepSeconds;
  Rhythm r{step, config_.quickAheadShare * step, true, -1, time, 0.0};
  if (!walking || !config_.followHeadDips || !gait_.locked(time)) return r;
  const int foot = gait_.nextFoot(time);
  const double period = gait_.period();
  // A planted foot stays down for two steps less a swing while the body passes over it, and our
  // legs let it travel `strideReach` of twice reachRadius under the body (the heel rising; a
  // person's foot rolls further). A walk's stride longer than twice reachRadius (a run, a long
  // stride) keeps the quick steps; a shorter one gets a swing long enough to keep the stance
  // within `strideReach`, or a step long where that is not enough. The walk's own stride hovers
  // about strideReach's (0.69-0.81 m against 0.73 in cmu_12_01_walk): cut off there, the steps
  // switched between the beats and the quick steps every few frames.
  const double underBody = 2.0 * config_.strideReach * config_.reachRadius * scale_;
  if (foot < 0 || speed * period > 2.0 * config_.reachRadius * scale_) return r;
  const double longestStance = underBody / std::max(speed, 1e-9);
  const double swing = std::clamp(std::max(config_.swingShare * period, 2.0 * period - longestStance), step,
                                  std::max(step, period - config_.doubleSupportSeconds));
  r.ahead = config_.aheadShare * period;
  // Start when the next dip is a swing away (or nearer, but not nearer than the quickest step),
  // the swing as long as what is left.
  r.beat = gait_.nextDip(time);
  r.period = period;
  const double toDip = r.beat - time;
  r.due = toDip <= swing && toDip >= step;
  r.swing = std::clamp(toDip, step, swing);
  r.foot = foot;
  return r;
}

Eigen::Vector3d FootPlanner::centreOverFeet() const {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (size_t f = 0; f < 2; ++f) c += 0.5 * (ground(feet_[f].position) - yawRotation(feet_[f].yaw, up_) * ground(restOffset_[f]));
  return c;
}

void FootPlanner::buildSupport() {
  points_.clear();
  for (int f = 0; f < 2; ++f) {
    const Swing& s = swing_[static_cast<size_t>(f)];
    const Eigen::Vector3d ankle = s.active ? s.to : feet_[static_cast<size_t>(f)].position;
    const double yaw = s.active ? s.toYaw : feet_[static_cast<size_t>(f)].yaw;
    const Eigen::Quaterniond r = yawRotation(yaw, up_);
    const Eigen::Vector3d fwd = r * forward_, side = r * axisB_;
    const Eigen::Vector3d g = ground(ankle);
    for (double a : {-shape_.heelBack, shape_.toeForward})
      for (double b : {-shape_.halfWidth, shape_.halfWidth}) points_.push_back(plane(g + scale_ * (a * fwd + b * side)));
  }
  convexHull(points_, hull_);
}

bool FootPlanner::overSupport(const Eigen::Vector3d& point) const {
  if (hull_.size() < 3) return false;
  const Eigen::Vector2d p = plane(point);
  for (size_t i = 0; i < hull_.size(); ++i)
    if (cross2(hull_[i], hull_[(i + 1) % hull_.size()], p) < 0.0) return false;
  return true;
}

Eigen::Vector3d FootPlanner::nearestSupportPoint(const Eigen::Vector3d& point, double margin) const {
  if (hull_.empty()) return point;
  const Eigen::Vector2d p = plane(point);
  Eigen::Vector2d best = hull_[0];
  double bestD = 1e300;
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < hull_.size(); ++i) {
    centroid += hull_[i];
    const Eigen::Vector2d q = nearestOnSegment(p, hull_[i], hull_[(i + 1) % hull_.size()]);
    if ((q - p).squaredNorm() < bestD) bestD = (q - p).squaredNorm(), best = q;
  }
  centroid /= static_cast<double>(hull_.size());
  const Eigen::Vector2d in = centroid - best;
  if (in.norm() > margin) best += in.normalized() * margin;
  return best.x() * axisA_ + best.y() * axisB_ + up_ * up_.dot(point);
}

}  // namespace embody::runtime
