#pragma once
// What the runtime suites share: the default avatar built once per process, and a pose source
// for a 1.75 m user (a source that does not open fails the test).
#include <catch2/catch.hpp>
#include <memory>
#include <string>
#include <utility>

#include "avatar/procedural/default_avatar.h"
#include "tracking/pose_source.h"

namespace embody::test {

inline const avatar::AvatarAsset& defaultAvatar() {
  static const avatar::AvatarAsset a = avatar::buildDefaultAvatar();
  return a;
}

inline std::unique_ptr<tracking::PoseSource> openSource(const std::string& spec,
                                                        tracking::TrackerMask mask = tracking::TrackerMask::all()) {
  tracking::SourceOptions o;
  o.userHeight = 1.75f;
  o.trackers = mask;
  auto src = tracking::openPoseSource(spec, o);
  REQUIRE(src.ok());
  return std::move(src).value();
}

}  // namespace embody::test
