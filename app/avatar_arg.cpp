#include "app/avatar_arg.h"

#include "avatar/avatar_loader.h"
#include "avatar/gltf/gltf_loader.h"
#include "avatar/procedural/default_avatar.h"

namespace embody::app {

Result<avatar::AvatarAsset> loadAvatarArg(const std::string& avatar, const std::string& boneMap) {
  if (avatar != "default") {
    avatar::AvatarLoadOptions lo;
    lo.boneMapFile = boneMap;
    return avatar::loadAvatarFile(avatar, lo);
  }
  avatar::AvatarAsset asset = avatar::buildDefaultAvatar();
  if (!boneMap.empty()) {  // the mannequin re-mapped by the user's bone map
    auto text = avatar::readBoneMapFile(boneMap);
    if (!text) return Error{text.error()};
    if (auto s = avatar::prepareAvatar(asset, *text); !s) return Error{s.error()};
  }
  return asset;
}

}  // namespace embody::app
