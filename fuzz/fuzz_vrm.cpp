// VRM extensions (avatar/humanoid, avatar/gltf/mtoon_json, avatar/vrm): the glTF JSON's "VRM"
// (0.x) and "VRMC_vrm" / "VRMC_springBone" (1.0) humanoid bones, firstPerson annotations, spring
// bones, expressions and look-at, and MToon (VRM 0.x materialProperties, VRMC_materials_mtoon on
// materials), read straight from the document so the fuzzer need not get a whole loadable glTF
// right first. The skeleton is the default mannequin's, with three materials and two decoded
// images for the MToon properties to land on. What loads is then animated for a few frames (a
// head turn, a teleport, a look target): the pose and morph weights stay finite.
#include <string>

#include "avatar/avatar_loader.h"
#include "avatar/gltf/mtoon_json.h"
#include "avatar/vrm/secondary_motion.h"
#include "fuzz/avatar_checks.h"
#include "fuzz/default_avatar_fixture.h"

EMBODY_FUZZ_TARGET(vrm) {
  using namespace embody;
  avatar::AvatarAsset asset = fuzz::defaultAvatarFixture();
  asset.format = avatar::AvatarFormat::Vrm1;
  asset.rawJson.assign(reinterpret_cast<const char*>(data), size);
  asset.materials.resize(3);
  asset.images = {avatar::Image{1, 1, {255, 255, 255, 255}}, avatar::Image{1, 1, {0, 128, 255, 255}}};
  std::vector<std::string> warnings;
  avatar::readMToonMaterials(asset, warnings);
  if (!avatar::prepareAvatar(asset, "").ok()) return 0;
  fuzz::checkAvatar(asset);
  fuzz::checkSecondaryMotion(asset);
  return 0;
}
