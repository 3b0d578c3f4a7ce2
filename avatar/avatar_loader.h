#pragma once
// Turning a freshly built AvatarAsset (from the glTF loader or the procedural generator) into a
// usable avatar: humanoid mapping, vertebra assignment and the first-person draw list.
// loadAvatarFile (avatar/gltf/gltf_loader.h) and buildDefaultAvatar call it; a custom source
// would too.
#include <string>

#include "avatar/avatar_asset.h"
#include "core/result.h"

namespace embody::avatar {

// boneMapJson: the --bone-map file's contents ("" for none). Fails only on a malformed bone map;
// an avatar that cannot be mapped keeps asset.humanoid.missingRequired filled.
Status prepareAvatar(AvatarAsset& asset, const std::string& boneMapJson);

// Reads a --bone-map file (a JSON object, at most 1 MiB).
Result<std::string> readBoneMapFile(const std::string& path);

}  // namespace embody::avatar
