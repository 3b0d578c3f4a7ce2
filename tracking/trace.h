#pragma once
// Recorded traces: JSON Lines, one pose sample per line, OpenXR conventions (docs/tracking.md):
//   {"t": 0.011, "head": {"p": [x,y,z], "q": [x,y,z,w], "valid": true}, "left": {...}, "right": {...}}
// with optional "hips", "left_foot", "right_foot". An optional first line
//   {"embody_trace": 1, "source": "synthetic:idle", "user_height": 1.75}
// says where the trace came from. Non-finite numbers (null, NaN, Infinity) make a tracker invalid;
// malformed lines are errors that name the line.
#include <cstdio>
#include <istream>
#include <string>
#include <vector>

#include "tracking/pose_source.h"

namespace embody::tracking {

struct Trace {
  std::vector<PoseSample> samples;  // times non-decreasing
  TrackerMask trackers;             // every tracker that appears on some line
  std::string source;               // from the header line, "" when absent
  float userHeight = 0.0f;          // from the header line, 0 when absent
  std::vector<std::string> notes;   // ignored keys and similar, with line numbers
};

inline constexpr size_t kMaxTraceLineBytes = 1 << 20;

Result<Trace> parseTrace(std::istream& in, const std::string& name);
Result<Trace> readTrace(const std::string& path);

// One line of the format (no newline), writing only the trackers in `trackers`.
std::string formatTraceLine(const PoseSample& sample, TrackerMask trackers);

// Streams samples to a file; the header line is written on open.
class TraceWriter {
 public:
  TraceWriter() = default;
  TraceWriter(const TraceWriter&) = delete;
  TraceWriter& operator=(const TraceWriter&) = delete;
  ~TraceWriter();

  Status open(const std::string& path, TrackerMask trackers, const std::string& source, float userHeight);
  Status write(const PoseSample& sample);
  Status close();

 private:
  std::FILE* file_ = nullptr;
  std::string path_;
  TrackerMask trackers_;
};

// Replays a trace: linear interpolation between samples where the tracker is valid on both
// sides, the earlier sample's value otherwise (sample and hold); time 0 is the first sample.
class TraceSource final : public PoseSource {
 public:
  TraceSource(Trace trace, std::string name);

  std::string name() const override { return name_; }
  TrackerMask trackers() const override { return trace_.trackers; }
  double duration() const override;
  double nativeRate() const override;
  size_t frameCount() const override { return trace_.samples.size(); }
  std::vector<std::string> notes() const override { return trace_.notes; }
  PoseSample sample(double time) override;

  const Trace& trace() const { return trace_; }

 private:
  Trace trace_;
  std::string name_;
};

}  // namespace embody::tracking
