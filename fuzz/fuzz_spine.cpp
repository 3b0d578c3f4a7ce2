// Spine descriptions (ik/spine/spine_description, --spine-model FILE.json): parse, then what was
// accepted must survive a round trip through toJson and give finite limits.
#include <cmath>
#include <nlohmann/json.hpp>
#include <string_view>

#include "fuzz/fuzz_target.h"
#include "ik/spine/spine_description.h"

EMBODY_FUZZ_TARGET(spine) {
  using namespace embody::ik::spine;
  auto d = parseSpineDescriptionText(std::string_view(reinterpret_cast<const char*>(data), size));
  if (!d.ok()) return 0;
  auto again = parseSpineDescription(toJson(d.value()));
  EMBODY_FUZZ_CHECK(again.ok());
  for (bool distribute : {false, true})
    for (const auto& r : siteRanges(d.value(), distribute)) EMBODY_FUZZ_CHECK(r.allFinite());
  for (const auto& c : neutralCentres(d.value(), 1.75)) EMBODY_FUZZ_CHECK(c.allFinite());
  return 0;
}
