#pragma once
// The rhythm of a walk, read from the head's height. A walking head dips once a step: lowest in
// double support, just as the front foot lands, highest as the body passes over the planted foot
// (the inverted pendulum of the stance leg). In cmu_12_01_walk the head dips 1.2-2 cm every
// 0.63 s and each dip falls within 0.03 s of a foot coming flat on the floor; between them a
// shallower dip of 0.3-0.5 cm (the push-off) comes and goes. Three points show nothing else of
// the feet, so the foot planner lands its steps on the dips while they come regularly
// (foot_planner.h; where they do not, a head carried level, it keeps its quick steps).
//
// Which foot lands on a dip comes from the sway: the head moves sideways towards the foot that is
// taking the weight. At each of the walk's 7 landings the head's sideways velocity (against its
// mean over a second) pointed to the landing foot, 0.12-0.17 m/s; in cmu_007_01 (a head carried
// level, no dips) 0.13-0.28 m/s, all 5 the right way.
//
// Dips are found by hysteresis: a minimum counts once the head has risen `dip` above it, and the
// next one only after the head has fallen `dip` below a maximum since; the minimum's own time is
// kept (it is seen 0.05-0.13 s later in that walk, but the prediction needs its time, not when
// it was seen). The clock locks on the first two dips a step apart, with nothing yet to disagree
// with, and stays locked while each step agrees with the one before (within `regularity`); a
// step that does not unlocks it until the next one agrees.
namespace embody::runtime {

struct GaitClockConfig {
  double dip = 0.008;           // metres at the avatar's scale: how far a dip falls and rises
  double minPeriod = 0.3;       // seconds between dips a step may take ...
  double maxPeriod = 1.0;       // ... (slower is not walking)
  double regularity = 0.2;      // the last two periods agree within this share of the step
  double swayFloor = 0.03;      // m/s at the avatar's scale: a smaller sway names no foot
  double swaySmoothing = 0.03;  // seconds
};

class GaitClock {
 public:
  void configure(const GaitClockConfig& config, double scale);
  void reset();
  // `sway`: the head's sideways velocity against its mean, positive towards the left foot.
  void update(double time, double height, double sway);
  // Whether the dips came regularly: the last two periods within `regularity` (or the first
  // period since a start or a pause), the last dip no longer than 1.5 periods ago.
  bool locked(double time) const;
  double period() const { return period_; }
  // The first dip expected after `time` (locked only): the last one plus whole periods.
  double nextDip(double time) const;
  int dips() const { return dips_; }  // seen since construction
  // The foot (0 left, 1 right) that lands on the first dip after `time`: -1 while the last two
  // dips' feet, read from the sway, did not alternate.
  int nextFoot(double time) const;

 private:
  GaitClockConfig config_;
  double scale_ = 1.0;
  bool seekingMin_ = true, started_ = false;
  double extreme_ = 0.0, extremeTime_ = 0.0;  // the lowest (or highest) height since the last turn
  double lastTime_ = 0.0;
  double lastDip_ = -1e9, period_ = 0.0;
  double sway_ = 0.0, extremeSway_ = 0.0;  // smoothed; its value at the extreme's time
  int dips_ = 0, lastFoot_ = -1;
  // The last step agreed with the one before (within `regularity`), or is the first since a start
  // or a pause, with nothing yet to disagree with.
  bool steady_ = false;
  bool alternating_ = false;
};

}  // namespace embody::runtime
