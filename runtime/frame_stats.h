#pragma once
// Per-frame statistics of the runtime and their summary (the "ik" and "tracking" parts of
// `embody render`'s stats.json).
#include <array>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <vector>

#include "tracking/tracking_guard.h"

namespace embody::runtime {

struct FrameStats {
  uint64_t sequence = 0;     // 1, 2, ... per solved sample
  double sampleTime = 0.0;   // the tracking sample's time
  double ikSeconds = 0.0;    // filter + guard + solve, on the runtime's clock
  double budgetSeconds = 0.0;
  int iterations = 0;
  bool converged = false;
  bool deadlineMiss = false;  // returned after the deadline (a start-up solve never counts)
  bool startup = false;       // the body's start, settled outside the budget once (SolveResult::settled)
  std::array<float, tracking::kTrackerCount> residual{-1, -1, -1, -1, -1, -1};  // metres, < 0: no task
  std::array<float, tracking::kTrackerCount> turnResidual{-1, -1, -1, -1, -1, -1};  // radians, < 0: no task
  std::array<bool, tracking::kTrackerCount> reachable{true, true, true, true, true, true};
  std::array<tracking::TrackerStatus, tracking::kTrackerCount> status{};
  double renderSeconds = 0.0;  // filled in by the render side when it has drawn the frame
};

struct StatsSummary {
  size_t frames = 0;
  double budgetMs = 0.0;
  // Per frame, over the frames after start-up (the start-up solve runs outside the budget by
  // design: its time and iterations are startupMs and startupIterations, -1 / 0 without one; the
  // longest where the body started again after a reset).
  double ikP50Ms = 0.0, ikP99Ms = 0.0, ikMaxMs = 0.0;
  size_t deadlineMisses = 0;
  double iterationsMean = 0.0;
  double startupMs = -1.0;
  int startupIterations = 0;
  double renderP50Ms = 0.0;
  // Per tracker: p95 of the residual over frames where it drove a task (-1: never), and the
  // fraction of frames it was live-tracked.
  std::array<double, tracking::kTrackerCount> residualP95{-1, -1, -1, -1, -1, -1};
  std::array<double, tracking::kTrackerCount> turnResidualP95Deg{-1, -1, -1, -1, -1, -1};  // degrees
  std::array<double, tracking::kTrackerCount> trackedFraction{};
  // stats.json "tracking": p95 of the head residual, and of both hands' residuals on frames where
  // the hand's target is within reach (-1: none).
  double headErrorP95 = -1.0, handErrorP95 = -1.0;
  size_t handFramesOutOfReach = 0;
  size_t nonFiniteFrames = 0;  // frames whose pose or residuals were not finite (must stay 0)
};

// Collects frames (reserve up front; add() does not allocate within the reserved size).
class StatsRecorder {
 public:
  void reserve(size_t frames) { frames_.reserve(frames); }
  void add(const FrameStats& s) { frames_.push_back(s); }
  const std::vector<FrameStats>& frames() const { return frames_; }
  StatsSummary summary() const;

 private:
  std::vector<FrameStats> frames_;
};

// {"frames", "ik": {budget_ms, p50_ms, p99_ms, max_ms, deadline_misses, iterations_mean[,
//  startup_ms, startup_iterations]},
//  "tracking": {head_error_p95_m, hand_error_p95_m, hand_frames_out_of_reach, non_finite_frames},
//  "trackers": {"head": {"tracked_fraction", "residual_p95_m", "turn_error_p95_deg"}, ...}, "render": {"p50_ms"}}
void toJson(nlohmann::json& j, const StatsSummary& s);

}  // namespace embody::runtime
