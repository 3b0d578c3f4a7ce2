#include "runtime/frame_stats.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <nlohmann/json.hpp>

#include "core/percentile.h"

namespace embody::runtime {

StatsSummary StatsRecorder::summary() const {
  StatsSummary s;
  s.frames = frames_.size();
  if (frames_.empty()) return s;
  std::vector<double> ik, render;
  double iterations = 0.0;
  for (const auto& f : frames_) {
    if (f.renderSeconds > 0.0) render.push_back(f.renderSeconds * 1e3);
    s.budgetMs = f.budgetSeconds * 1e3;
    if (f.startup) {
      s.startupMs = std::max(s.startupMs, f.ikSeconds * 1e3);
      s.startupIterations = std::max(s.startupIterations, f.iterations);
      continue;
    }
    ik.push_back(f.ikSeconds * 1e3);
    iterations += f.iterations;
    s.deadlineMisses += f.deadlineMiss ? 1 : 0;
  }
  s.ikMaxMs = ik.empty() ? 0.0 : *std::max_element(ik.begin(), ik.end());
  s.ikP50Ms = percentileNearestRank(ik, 50);
  s.ikP99Ms = percentileNearestRank(ik, 99);
  s.renderP50Ms = percentileNearestRank(render, 50);
  s.iterationsMean = ik.empty() ? 0.0 : iterations / static_cast<double>(ik.size());
  for (auto id : tracking::kAllTrackers) {
    const auto i = static_cast<size_t>(tracking::index(id));
    std::vector<double> r, turn;
    size_t tracked = 0;
    for (const auto& f : frames_) {
      if (f.residual[i] >= 0.0f) r.push_back(f.residual[i]);
      if (f.turnResidual[i] >= 0.0f) turn.push_back(f.turnResidual[i] * 180.0 / std::numbers::pi);
      tracked += f.status[i] == tracking::TrackerStatus::Tracked ? 1 : 0;
    }
    s.residualP95[i] = r.empty() ? -1.0 : percentileNearestRank(r, 95);
    s.turnResidualP95Deg[i] = turn.empty() ? -1.0 : percentileNearestRank(turn, 95);
    s.trackedFraction[i] = static_cast<double>(tracked) / static_cast<double>(frames_.size());
  }
  std::vector<double> head, hands;
  for (const auto& f : frames_) {
    bool finite = std::isfinite(f.ikSeconds);
    for (float r : f.residual) finite = finite && std::isfinite(r);
    for (float r : f.turnResidual) finite = finite && std::isfinite(r);
    s.nonFiniteFrames += finite ? 0 : 1;
    const float h = f.residual[static_cast<size_t>(tracking::index(tracking::TrackerId::Head))];
    if (h >= 0.0f) head.push_back(h);
    for (auto id : {tracking::TrackerId::LeftHand, tracking::TrackerId::RightHand}) {
      const auto i = static_cast<size_t>(tracking::index(id));
      if (f.residual[i] < 0.0f) continue;
      if (f.reachable[i]) hands.push_back(f.residual[i]);
      else ++s.handFramesOutOfReach;
    }
  }
  s.headErrorP95 = head.empty() ? -1.0 : percentileNearestRank(head, 95);
  s.handErrorP95 = hands.empty() ? -1.0 : percentileNearestRank(hands, 95);
  return s;
}

void toJson(nlohmann::json& j, const StatsSummary& s) {
  j["frames"] = s.frames;
  j["ik"] = {{"budget_ms", s.budgetMs},          {"p50_ms", s.ikP50Ms},
             {"p99_ms", s.ikP99Ms},              {"max_ms", s.ikMaxMs},
             {"deadline_misses", s.deadlineMisses}, {"iterations_mean", s.iterationsMean}};
  if (s.startupMs >= 0.0) {
    j["ik"]["startup_ms"] = s.startupMs;
    j["ik"]["startup_iterations"] = s.startupIterations;
  }
  j["tracking"] = {{"head_error_p95_m", s.headErrorP95},
                   {"hand_error_p95_m", s.handErrorP95},
                   {"hand_frames_out_of_reach", s.handFramesOutOfReach},
                   {"non_finite_frames", s.nonFiniteFrames}};
  nlohmann::json trackers = nlohmann::json::object();
  for (auto id : tracking::kAllTrackers) {
    const auto i = static_cast<size_t>(tracking::index(id));
    nlohmann::json t = {{"tracked_fraction", s.trackedFraction[i]}};
    if (s.residualP95[i] >= 0.0) t["residual_p95_m"] = s.residualP95[i];
    if (s.turnResidualP95Deg[i] >= 0.0) t["turn_error_p95_deg"] = s.turnResidualP95Deg[i];
    trackers[std::string(tracking::trackerKey(id))] = t;
  }
  j["trackers"] = trackers;
  j["render"] = {{"p50_ms", s.renderP50Ms}};
}

}  // namespace embody::runtime
