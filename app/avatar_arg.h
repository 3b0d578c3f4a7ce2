#pragma once
// The avatar a command was given: `--avatar default` (the procedural mannequin), a glTF/GLB/VRM
// file with an optional `--bone-map` file, or a BVH clip (its own skeleton with capsules,
// tracking/bvh_avatar.h). One place for the render, mirror and xr commands.
#include <string>

#include "avatar/avatar_asset.h"
#include "core/result.h"

namespace embody::app {

bool isBvhPath(const std::string& path);  // ends in .bvh (any case)

Result<avatar::AvatarAsset> loadAvatarArg(const std::string& avatar, const std::string& boneMap = "");

}  // namespace embody::app
