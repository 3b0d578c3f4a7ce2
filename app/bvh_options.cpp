#include "app/bvh_options.h"

#include <stdexcept>

#include "avatar/avatar_loader.h"

namespace embody::app {

void declareBvhOptions(Args& args) {
  args.option("bvh-up", "AXIS", "the BVH file's up axis, +X..-Z (default: measured on the motion, feet below the head)");
  args.option("bvh-forward", "AXIS", "the way the BVH performer faces at the start, +X..-Z (default: from the hips and shoulders)");
  args.option("bvh-bone-map", "FILE", "JSON object VRM-1.0-bone-name -> BVH joint name, e.g. {\"head\": \"Head\"}");
  args.flag("bvh-mirror", "read the BVH file mirrored across its X axis (a left-handed file, whose toes point behind it)");
}

BvhOverrides readBvhOptions(const Args& args) {
  BvhOverrides o;
  for (auto [name, value] : {std::pair{"bvh-up", &o.up}, std::pair{"bvh-forward", &o.forward}}) {
    if (!args.has(name)) continue;
    *value = args.get(name);
    if (auto a = avatar::parseBvhAxis(*value); !a) throw std::invalid_argument(std::string("--") + name + ": " + a.error());
  }
  o.boneMapFile = args.get("bvh-bone-map");
  o.mirror = args.has("bvh-mirror");
  return o;
}

Result<avatar::BvhBodyOptions> bvhBodyOptions(const BvhOverrides& o) {
  avatar::BvhBodyOptions b;
  b.up = o.up;
  b.forward = o.forward;
  b.mirror = o.mirror;
  if (!o.boneMapFile.empty()) {
    auto text = avatar::readBoneMapFile(o.boneMapFile);
    if (!text) return Error{"--bvh-bone-map: " + text.error()};
    b.boneMapJson = std::move(*text);
  }
  return b;
}

}  // namespace embody::app
