#include "xr/tracking/pose_source.h"

#include <cctype>

#include "xr/tracking/bvh_source.h"
#include "xr/tracking/synthetic_source.h"
#include "xr/tracking/trace.h"

namespace embody::tracking {

namespace {

bool endsWith(std::string_view s, std::string_view suffix) {
  if (s.size() < suffix.size()) return false;
  for (size_t i = 0; i < suffix.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(s[s.size() - suffix.size() + i])) != suffix[i]) return false;
  return true;
}

class MaskedSource final : public PoseSource {
 public:
  MaskedSource(std::unique_ptr<PoseSource> inner, TrackerMask keep) : inner_(std::move(inner)), keep_(keep) {}
  std::string name() const override { return inner_->name(); }
  TrackerMask trackers() const override { return TrackerMask(inner_->trackers().bits() & keep_.bits()); }
  double duration() const override { return inner_->duration(); }
  bool periodic() const override { return inner_->periodic(); }
  double nativeRate() const override { return inner_->nativeRate(); }
  size_t frameCount() const override { return inner_->frameCount(); }
  std::vector<std::string> notes() const override { return inner_->notes(); }
  PoseSample sample(double time) override {
    PoseSample s = inner_->sample(time);
    for (auto id : kAllTrackers)
      if (!keep_.has(id)) s[id] = TrackerPose{};
    return s;
  }

 private:
  std::unique_ptr<PoseSource> inner_;
  TrackerMask keep_;
};

}  // namespace

std::unique_ptr<PoseSource> maskTrackers(std::unique_ptr<PoseSource> source, TrackerMask keep) {
  return std::make_unique<MaskedSource>(std::move(source), keep);
}

Result<std::unique_ptr<PoseSource>> openPoseSource(std::string_view spec, const SourceOptions& options) {
  std::unique_ptr<PoseSource> source;
  constexpr std::string_view kSynthetic = "synthetic:";
  if (spec.rfind(kSynthetic, 0) == 0) {
    auto s = SyntheticSource::create(spec.substr(kSynthetic.size()), options.userHeight);
    if (!s) return Error{s.error()};
    source = std::move(*s);
  } else if (endsWith(spec, ".bvh")) {
    BvhTrackerOptions o;
    o.userHeight = options.userHeight;
    o.scale = options.bvhScale;
    auto s = openBvhSource(std::string(spec), o);
    if (!s) return Error{s.error()};
    source = std::move(*s);
  } else if (endsWith(spec, ".jsonl") || endsWith(spec, ".json")) {
    auto t = readTrace(std::string(spec));
    if (!t) return Error{t.error()};
    source = std::make_unique<TraceSource>(std::move(*t), std::string(spec));
  } else {
    return Error{"unknown motion '" + std::string(spec) +
                 "': expected synthetic:NAME, a .bvh file or a .jsonl trace"};
  }
  if (options.trackers != TrackerMask::all()) source = maskTrackers(std::move(source), options.trackers);
  return source;
}

}  // namespace embody::tracking
