// glTF / GLB / VRM files (avatar/gltf): what `--avatar FILE` runs, from bytes: the loader, then the
// humanoid mapping (VRM 0.x / 1.0 humanBones, names, topology) and the first-person draw list.
#include <vector>

#include "avatar/avatar_loader.h"
#include "avatar/gltf/gltf_loader.h"
#include "fuzz/avatar_checks.h"

EMBODY_FUZZ_TARGET(gltf) {
  using namespace embody::avatar;
  const std::vector<uint8_t> bytes(data, data + size);
  // A base folder with nothing in it: external URIs in fuzzed files find no file.
  auto asset = loadGltfFromMemory(bytes, "/nonexistent-embody-fuzz");
  if (!asset.ok()) return 0;
  embody::fuzz::checkAvatar(asset.value());
  if (!prepareAvatar(asset.value(), "").ok()) return 0;
  embody::fuzz::checkAvatar(asset.value());
  embody::fuzz::checkSecondaryMotion(asset.value());
  return 0;
}
