#include "tracking/pose_source.h"

#include <cctype>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "tracking/bvh_source.h"
#include "tracking/synthetic_source.h"
#include "tracking/trace.h"

namespace embody::tracking {

namespace {

bool endsWith(std::string_view s, std::string_view suffix) {
  if (s.size() < suffix.size()) return false;
  for (size_t i = 0; i < suffix.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(s[s.size() - suffix.size() + i])) != suffix[i]) return false;
  return true;
}

// Forwards everything to the wrapped source; subclasses change the samples.
class SourceDecorator : public PoseSource {
 public:
  explicit SourceDecorator(std::unique_ptr<PoseSource> inner) : inner_(std::move(inner)) {}
  std::string name() const override { return inner_->name(); }
  TrackerMask trackers() const override { return inner_->trackers(); }
  double duration() const override { return inner_->duration(); }
  bool periodic() const override { return inner_->periodic(); }
  double nativeRate() const override { return inner_->nativeRate(); }
  size_t frameCount() const override { return inner_->frameCount(); }
  std::vector<std::string> notes() const override { return inner_->notes(); }
  PoseSample sample(double time) override { return inner_->sample(time); }

 protected:
  std::unique_ptr<PoseSource> inner_;
};

class LossSource final : public SourceDecorator {
 public:
  LossSource(std::unique_ptr<PoseSource> inner, TrackerMask lost, double from, double to)
      : SourceDecorator(std::move(inner)), lost_(lost), from_(from), to_(to) {}
  PoseSample sample(double time) override {
    PoseSample s = inner_->sample(time);
    if (time >= from_ && time < to_)
      for (auto id : kAllTrackers)
        if (lost_.has(id)) s[id] = {glm::vec3(std::numeric_limits<float>::quiet_NaN()), s[id].orientation, false};
    return s;
  }

 private:
  TrackerMask lost_;
  double from_, to_;
};

class MaskedSource final : public SourceDecorator {
 public:
  MaskedSource(std::unique_ptr<PoseSource> inner, TrackerMask keep) : SourceDecorator(std::move(inner)), keep_(keep) {}
  TrackerMask trackers() const override { return TrackerMask(inner_->trackers().bits() & keep_.bits()); }
  PoseSample sample(double time) override {
    PoseSample s = inner_->sample(time);
    for (auto id : kAllTrackers)
      if (!keep_.has(id)) s[id] = TrackerPose{};
    return s;
  }

 private:
  TrackerMask keep_;
};

}  // namespace

std::unique_ptr<PoseSource> withTrackingLoss(std::unique_ptr<PoseSource> source, TrackerMask lost, double from,
                                             double to) {
  return std::make_unique<LossSource>(std::move(source), lost, from, to);
}

Result<TrackingLossSpec> parseTrackingLoss(std::string_view spec) {
  const auto fail = [&] {
    return Error{"tracking loss '" + std::string(spec) + "': expected TRACKERS@FROM-TO, e.g. left,right@2.0-3.0"};
  };
  const size_t at = spec.find('@');
  if (at == std::string_view::npos) return fail();
  TrackingLossSpec r;
  std::string_view keys = spec.substr(0, at);
  while (!keys.empty()) {
    const size_t comma = keys.find(',');
    const std::string_view key = keys.substr(0, comma);
    const auto id = trackerFromKey(key);
    if (!id) return Error{"tracking loss: unknown tracker '" + std::string(key) + "'"};
    r.lost.set(*id);
    keys = comma == std::string_view::npos ? std::string_view() : keys.substr(comma + 1);
  }
  const std::string window(spec.substr(at + 1));
  const size_t dash = window.find('-', 1);
  if (r.lost.bits() == 0 || dash == std::string::npos) return fail();
  try {
    size_t used = 0;
    r.from = std::stod(window.substr(0, dash), &used);
    if (used != dash) return fail();
    r.to = std::stod(window.substr(dash + 1), &used);
    if (used != window.size() - dash - 1) return fail();
  } catch (const std::exception&) {
    return fail();
  }
  if (!(std::isfinite(r.from) && std::isfinite(r.to) && r.from < r.to)) return fail();
  return r;
}

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
    o.body = options.bvh;
    o.required = TrackerMask(static_cast<uint8_t>(options.required.bits() & options.trackers.bits()));
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
