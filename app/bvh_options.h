#pragma once
// The BVH import overrides, one set for every command that takes --motion FILE.bvh (render,
// mirror, motion info/record): --bvh-up, --bvh-forward, --bvh-bone-map, --bvh-mirror (docs/tracking.md).
#include <string>

#include "app/args.h"
#include "avatar/bvh/bvh_body.h"
#include "core/result.h"

namespace embody::app {

struct BvhOverrides {
  std::string up, forward;  // "" = measured on the motion
  std::string boneMapFile;  // "" = none
  bool mirror = false;      // --bvh-mirror: a left-handed file, read mirrored
};

void declareBvhOptions(Args& args);
// Throws std::invalid_argument for an axis that is not +X/-X/+Y/-Y/+Z/-Z (a usage error).
BvhOverrides readBvhOptions(const Args& args);
// Reads the bone map file: an unreadable file is a runtime error.
Result<avatar::BvhBodyOptions> bvhBodyOptions(const BvhOverrides& o);

}  // namespace embody::app
