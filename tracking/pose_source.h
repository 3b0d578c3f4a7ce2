#pragma once
// PoseSource: one interface for every origin of tracking data (synthetic scripted motions,
// recorded JSON Lines traces, BVH motion capture; OpenXR plugs in from xr).
// A source is sampled at a time in seconds; clips interpolate between their frames, synthetic
// motions evaluate closed-form curves, a live source returns its newest prediction.
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "avatar/bvh/bvh_body.h"
#include "core/result.h"
#include "tracking/tracker.h"

namespace embody::tracking {

class PoseSource {
 public:
  virtual ~PoseSource() = default;
  // What was opened: "synthetic:idle", a file path, "openxr".
  virtual std::string name() const = 0;
  // The trackers this source provides at all (each may still be invalid in a given sample).
  virtual TrackerMask trackers() const = 0;
  // Length in seconds. Periodic sources give one period and repeat; clips hold their last frame.
  virtual double duration() const = 0;
  virtual bool periodic() const { return false; }
  // Rate of the underlying data in Hz (BVH frame rate, trace sample rate); 0 for continuous.
  virtual double nativeRate() const { return 0.0; }
  // Number of recorded frames (0 for continuous sources).
  virtual size_t frameCount() const { return 0; }
  // Things a user should know: trackers whose joint is missing, units assumed, ignored data.
  virtual std::vector<std::string> notes() const { return {}; }
  // The pose at `time` seconds. Valid trackers are finite with unit quaternions (sanitize()).
  virtual PoseSample sample(double time) = 0;
};

struct SourceOptions {
  float userHeight = 1.75f;  // synthetic motions are built for it; BVH clips are scaled to it
  double bvhScale = 0.0;     // metres per BVH unit; 0 = fit the performer's measured height
  TrackerMask trackers = TrackerMask::all();  // trackers to keep (e.g. threePoint()); others absent
  TrackerMask required = TrackerMask::threePoint();  // BVH: trackers whose joint must be found
  avatar::BvhBodyOptions bvh;  // --bvh-up, --bvh-forward, --bvh-bone-map (the file's contents)
};

// Opens "synthetic:NAME", "FILE.bvh" or "FILE.jsonl" (by extension). Errors name the file and,
// for broken files, the line.
Result<std::unique_ptr<PoseSource>> openPoseSource(std::string_view spec, const SourceOptions& options = {});

// Wraps a source and keeps only the trackers in `keep` (others are reported absent and invalid).
std::unique_ptr<PoseSource> maskTrackers(std::unique_ptr<PoseSource> source, TrackerMask keep);

// Wraps a source and marks the trackers in `lost` invalid from `from` to `to` seconds (their
// positions set to NaN, as a broken driver might): tracking-loss tests and demos.
std::unique_ptr<PoseSource> withTrackingLoss(std::unique_ptr<PoseSource> source, TrackerMask lost, double from,
                                             double to);

// Parses "left,right@2.0-3.0" (tracker keys, then a time window in seconds) for withTrackingLoss.
struct TrackingLossSpec {
  TrackerMask lost;
  double from = 0.0, to = 0.0;
};
Result<TrackingLossSpec> parseTrackingLoss(std::string_view spec);

}  // namespace embody::tracking
