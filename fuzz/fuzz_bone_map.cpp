// Bone maps (--bone-map FILE.json, avatar/humanoid): {"hips": "NodeName" or node index, ...}
// applied over the default mannequin's skeleton.
#include <string>

#include "avatar/avatar_loader.h"
#include "fuzz/avatar_checks.h"
#include "fuzz/default_avatar_fixture.h"

EMBODY_FUZZ_TARGET(bone_map) {
  using namespace embody;
  avatar::AvatarAsset asset = fuzz::defaultAvatarFixture();
  if (avatar::prepareAvatar(asset, std::string(reinterpret_cast<const char*>(data), size)).ok())
    fuzz::checkAvatar(asset);
  return 0;
}
