#include "app/avatar_arg.h"

#include "avatar/avatar_loader.h"
#include "avatar/gltf/gltf_loader.h"
#include "avatar/procedural/default_avatar.h"
#include "tracking/bvh_avatar.h"

#include <cctype>

namespace embody::app {

bool isBvhPath(const std::string& path) {
  if (path.size() < 4) return false;
  std::string ext = path.substr(path.size() - 4);
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".bvh";
}

Result<avatar::AvatarAsset> loadAvatarArg(const std::string& avatar, const std::string& boneMap) {
  if (isBvhPath(avatar)) {  // the clip's own skeleton (tracking/bvh_avatar.h)
    if (!boneMap.empty()) return Error{"--bone-map applies to glTF/VRM avatars, not to a BVH clip"};
    auto bvh = tracking::loadBvhAvatar(avatar, {});
    if (!bvh) return Error{bvh.error()};
    return std::move(bvh->asset);
  }
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
