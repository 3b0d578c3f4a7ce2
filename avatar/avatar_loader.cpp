// loadAvatarFile: the one call applications make to get a drawable, mapped avatar.
#include "avatar/gltf/gltf_loader.h"

namespace embody::avatar {

Result<AvatarAsset> loadAvatarFile(const std::string& path, const AvatarLoadOptions& options,
                                   GltfLoadReport* report) {
  auto asset = loadGltfFile(path, report, options.limits);
  if (!asset.ok()) return asset;
  return asset;
}

}  // namespace embody::avatar
