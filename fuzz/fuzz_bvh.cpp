// BVH motion capture (avatar/bvh): the parser, forward kinematics of the first and last frame,
// and the tracking side's clip -> trackers conversion (tracking/bvh_source), which the CLI's
// --motion FILE.bvh and the headless runtime's EMBODY_XR_POSES=FILE.bvh both go through.
#include <cmath>
#include <string_view>

#include "avatar/bvh/bvh.h"
#include "fuzz/fuzz_target.h"
#include "tracking/bvh_source.h"

EMBODY_FUZZ_TARGET(bvh) {
  using namespace embody;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto clip = avatar::parseBvh(text, "fuzz.bvh");
  if (!clip.ok()) return 0;
  const avatar::BvhClip& c = clip.value();
  EMBODY_FUZZ_CHECK(c.frameCount > 0);
  EMBODY_FUZZ_CHECK(c.values.size() == c.frameCount * static_cast<size_t>(c.channelCount));
  for (size_t j = 0; j < c.joints.size(); ++j)
    EMBODY_FUZZ_CHECK(c.joints[j].parent < static_cast<int>(j));
  for (float v : c.values) EMBODY_FUZZ_CHECK(std::isfinite(v));
  std::vector<avatar::BvhGlobal> globals;
  avatar::bvhGlobals(c, c.frame(c.frameCount - 1), globals);
  EMBODY_FUZZ_CHECK(globals.size() == c.joints.size());
  // Only short clips go on to the tracker conversion: it samples every frame.
  if (c.frameCount > 2000) return 0;
  auto trace = tracking::bvhToTrace(c, {});
  if (!trace.ok()) return 0;
  for (const auto& s : trace->samples)
    for (const auto& t : s.trackers)
      if (t.valid) EMBODY_FUZZ_CHECK(std::isfinite(t.position.x + t.position.y + t.position.z));
  return 0;
}
