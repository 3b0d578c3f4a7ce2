// VRM extensions (avatar/humanoid, avatar/vrm): the glTF JSON's "VRM" (0.x) and "VRMC_vrm" /
// "VRMC_springBone" (1.0) humanoid bones, firstPerson annotations, spring bones, expressions and
// look-at, read straight from the document so the fuzzer need not get a whole loadable glTF right
// first. The skeleton is the default mannequin's. What loads is then animated for a few frames
// (a head turn, a teleport, a look target): the pose and morph weights stay finite.
#include <string>

#include "avatar/avatar_loader.h"
#include "avatar/vrm/secondary_motion.h"
#include "fuzz/avatar_checks.h"
#include "fuzz/default_avatar_fixture.h"

EMBODY_FUZZ_TARGET(vrm) {
  using namespace embody;
  avatar::AvatarAsset asset = fuzz::defaultAvatarFixture();
  asset.format = avatar::AvatarFormat::Vrm1;
  asset.rawJson.assign(reinterpret_cast<const char*>(data), size);
  if (!avatar::prepareAvatar(asset, "").ok()) return 0;
  fuzz::checkAvatar(asset);
  fuzz::checkSecondaryMotion(asset);
  return 0;
}
