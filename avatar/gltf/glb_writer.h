#pragma once
// Writes an AvatarAsset as a standard glTF 2.0 binary (GLB): one node per skeleton joint (TRS),
// one skinned mesh node at the scene root, one skin over every joint with the asset's inverse
// bind matrices, POSITION/NORMAL/TEXCOORD_0/JOINTS_0/WEIGHTS_0 (+ JOINTS_1/WEIGHTS_1 when some
// vertex has more than four influences; TEXCOORD_1 when a material or vertex uses it), one
// primitive per draw-list primitive, materials with base colour (factor, texture,
// KHR_texture_transform), emissive (+ KHR_materials_emissive_strength), KHR_materials_unlit, alpha
// mode, double-sidedness and VRMC_materials_mtoon (avatar::MToon, every property), morph targets
// (mesh.morphChannels as dense targets, with default weights and extras.targetNames). Images are
// embedded as PNG. The skeleton must have a single root
// (glTF requires the joints of a skin to share one).
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "avatar/avatar_asset.h"
#include "core/result.h"

namespace embody::avatar {

// Motion to store with the avatar: one glTF animation ("name"), a sample every frameTime seconds,
// LINEAR: every joint's rotation, and the translation of every joint whose translation moves
// (the hips), from each frame's local transforms.
struct GlbAnimation {
  std::string name = "motion";
  double frameTime = 1.0 / 90.0;
  std::vector<SkeletonPose> frames;  // each sized to the skeleton
};

// extensionsJson: a JSON object of top-level extensions to write as given (e.g. VRMC_vrm,
// VRMC_springBone), each also listed in extensionsUsed. Node i is skeleton joint i; the mesh
// node, when there is a mesh, is node skeleton.joints.size().
Result<std::vector<uint8_t>> encodeGlb(const AvatarAsset& asset, const GlbAnimation* animation = nullptr,
                                       std::string_view extensionsJson = {});
Status writeGlbFile(const AvatarAsset& asset, const std::string& path, const GlbAnimation* animation = nullptr,
                    std::string_view extensionsJson = {});

}  // namespace embody::avatar
