#pragma once
// The spine suites' one way to build an isolated spine: a failed build fails the test with the
// reason.
#include <catch2/catch.hpp>
#include <string>
#include <utility>

#include "ik/spine/spine_model.h"

namespace embody::test {

inline ik::spine::IsolatedSpine buildSpineOrFail(const ik::spine::SpineDescription& d, ik::spine::SpineOptions o = {}) {
  auto s = ik::spine::buildIsolatedSpine(d, o);
  INFO((s ? std::string() : s.error()));
  REQUIRE(s.ok());
  return std::move(*s);
}

}  // namespace embody::test
