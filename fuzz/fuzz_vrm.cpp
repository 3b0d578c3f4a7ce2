// VRM extensions (avatar/humanoid): the glTF JSON's "VRM" (0.x) and "VRMC_vrm" (1.0) humanoid
// bones and firstPerson annotations, read straight from the document so the fuzzer need not get
// a whole loadable glTF right first. The skeleton is the default mannequin's.
#include <string>

#include "avatar/avatar_loader.h"
#include "fuzz/avatar_checks.h"
#include "fuzz/default_avatar_fixture.h"

EMBODY_FUZZ_TARGET(vrm) {
  using namespace embody;
  avatar::AvatarAsset asset = fuzz::defaultAvatarFixture();
  asset.format = avatar::AvatarFormat::Vrm1;
  asset.rawJson.assign(reinterpret_cast<const char*>(data), size);
  if (avatar::prepareAvatar(asset, "").ok()) fuzz::checkAvatar(asset);
  return 0;
}
