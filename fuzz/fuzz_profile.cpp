// User profiles (avatar/body/calibration, --profile FILE.json): every accepted number is finite
// and in its documented range.
#include <cmath>
#include <string_view>

#include "avatar/body/calibration.h"
#include "fuzz/fuzz_target.h"

EMBODY_FUZZ_TARGET(profile) {
  using namespace embody::avatar;
  auto p = parseProfile(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.json");
  if (!p.ok()) return 0;
  EMBODY_FUZZ_CHECK(p->userHeight >= 0.5 && p->userHeight <= 2.6);
  EMBODY_FUZZ_CHECK(p->scale > 0.05 && p->scale < 20.0);
  EMBODY_FUZZ_CHECK(std::isfinite(p->eyeHeight + p->armSpan + p->avatarHeight + p->avatarArmSpan + p->armScale));
  return 0;
}
