#pragma once
// The avatar a command was given: `--avatar default` (the procedural mannequin) or a glTF/GLB/VRM
// file, with an optional `--bone-map` file. One place for the render, mirror and xr commands.
#include <string>

#include "avatar/avatar_asset.h"
#include "core/result.h"

namespace embody::app {

Result<avatar::AvatarAsset> loadAvatarArg(const std::string& avatar, const std::string& boneMap = "");

}  // namespace embody::app
