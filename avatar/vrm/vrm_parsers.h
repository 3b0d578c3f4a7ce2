#pragma once
// The VRM motion parsers (internal to embody_avatar: nlohmann::json stays out of public headers).
// Each reads one part of the glTF JSON `doc` (AvatarAsset::rawJson parsed once) for VRM 1.0 or,
// when that is absent, VRM 0.x. Bad values take the specification's default and bad references
// drop the element, each with a warning; they never fail on content.
#include <string>
#include <vector>

#include "avatar/vrm/expressions.h"
#include "avatar/vrm/look_at.h"
#include "avatar/vrm/spring_bone.h"
#include "avatar/vrm/vrm_json.h"

namespace embody::avatar {

struct AvatarAsset;

// VRMC_springBone or secondaryAnimation; a joint claimed by two chains stays in the first.
SpringBoneSetup parseSpringBones(const vrm::Json& doc, const AvatarAsset& asset, std::vector<std::string>& warnings);
// VRMC_vrm.expressions or VRM.blendShapeMaster (binds to missing morph targets are dropped).
ExpressionSet parseExpressions(const vrm::Json& doc, const AvatarAsset& asset, std::vector<std::string>& warnings);
// VRMC_vrm.lookAt or VRM.firstPerson's look-at settings (needs asset.humanoid).
LookAtSetup parseLookAt(const vrm::Json& doc, const AvatarAsset& asset, std::vector<std::string>& warnings);

}  // namespace embody::avatar
