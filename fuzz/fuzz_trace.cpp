// JSON Lines traces (tracking/trace): the parser and the replaying source at a few times. The
// same parser reads --motion FILE.jsonl and the headless runtime's EMBODY_XR_POSES trace.
#include <cmath>
#include <sstream>
#include <string>

#include "fuzz/fuzz_target.h"
#include "tracking/trace.h"

EMBODY_FUZZ_TARGET(trace) {
  using namespace embody::tracking;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  auto trace = parseTrace(in, "fuzz.jsonl");
  if (!trace.ok()) return 0;
  const auto& samples = trace->samples;
  for (size_t i = 1; i < samples.size(); ++i) EMBODY_FUZZ_CHECK(samples[i].time >= samples[i - 1].time);
  TraceSource source(std::move(trace.value()), "fuzz");
  const double d = source.duration();
  EMBODY_FUZZ_CHECK(std::isfinite(d) && d >= 0.0);
  for (double t : {-1.0, 0.0, 0.37 * d, d, d + 1.0}) {
    const PoseSample s = source.sample(t);
    for (const auto& p : s.trackers) {
      if (!p.valid) continue;
      EMBODY_FUZZ_CHECK(std::isfinite(p.position.x + p.position.y + p.position.z));
      EMBODY_FUZZ_CHECK(std::isfinite(p.orientation.w + p.orientation.x + p.orientation.y + p.orientation.z));
    }
  }
  return 0;
}
