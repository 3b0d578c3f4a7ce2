// The headless OpenXR runtime's EMBODY_XR_POSES input (tools/xr_runtime/poses.cpp): every input
// goes through both of its readers (the project's trace reader and BVH reader + bvhToTrace, as
// the runtime calls them), then the accepted samples are replayed by PoseProvider the way
// xrLocateSpace/xrLocateViews read them.
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "fuzz/fuzz_target.h"
#include "tools/xr_runtime/runtime.h"

namespace {

using embody::xr_runtime::BodySample;
using embody::xr_runtime::TrackerPose;

void checkPose(const TrackerPose& p) {
  if (!p.valid) return;
  EMBODY_FUZZ_CHECK(std::isfinite(p.position.x + p.position.y + p.position.z));
  const float n = glm::length(p.orientation);
  EMBODY_FUZZ_CHECK(std::isfinite(n) && std::abs(n - 1.0f) < 1e-3f);
}

void checkSample(const BodySample& s) {
  checkPose(s.head);
  checkPose(s.left);
  checkPose(s.right);
  EMBODY_FUZZ_CHECK(s.leftTrigger >= 0.0f && s.leftTrigger <= 1.0f);
  EMBODY_FUZZ_CHECK(s.rightTrigger >= 0.0f && s.rightTrigger <= 1.0f);
}

void checkAccepted(std::vector<BodySample> samples) {
  EMBODY_FUZZ_CHECK(!samples.empty());
  for (size_t i = 0; i < samples.size(); ++i) {
    EMBODY_FUZZ_CHECK(std::isfinite(samples[i].t));
    if (i > 0) EMBODY_FUZZ_CHECK(samples[i].t >= samples[i - 1].t);
    checkSample(samples[i]);
  }
  const double span = samples.back().t - samples.front().t;
  embody::xr_runtime::PoseProvider provider;
  provider.use(std::move(samples), "fuzz");
  for (double t : {-1.0, 0.0, 0.013, 0.37 * span, span, span + 0.5, 1e6})
    checkSample(provider.sample(t));
}

}  // namespace

EMBODY_FUZZ_TARGET(xr_poses) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::vector<BodySample> samples;
  {
    std::istringstream in(text);
    if (embody::xr_runtime::parseTraceSamples(in, "fuzz.jsonl", samples).empty()) checkAccepted(samples);
  }
  {
    std::istringstream in(text);
    if (embody::xr_runtime::parseBvhSamples(in, "fuzz.bvh", samples).empty()) checkAccepted(samples);
  }
  return 0;
}
