#pragma once
// glTF 2.0 / GLB / VRM loading into the AvatarAsset data contract (avatar/avatar_asset.h).
//
// What the loader produces:
//   - skeleton: every node of the file as a joint, parents before children (depth-first from
//     each root in node order). Node matrices are decomposed into TRS. glTF node index i maps to
//     joint nodeToJoint[i] (kept in AvatarAsset::gltfNodeToJoint). The skeleton is rigid: a
//     non-uniform scale (or shear) on a node is folded into that joint's inverse bind
//     (foldBoneScaleIntoBind, avatar_asset.h), so it shapes the node's own vertices as at rest and
//     never its children's; a file with uniform scales only keeps its rest transforms as written.
//   - mesh: every primitive of every node that has a mesh, merged into one vertex/index buffer.
//     Skinned primitives keep their JOINTS_0/1 + WEIGHTS_0/1 (up to 8 influences, normalised to
//     sum 1), with skin joint indices remapped to skeleton joints and one inverse bind matrix per
//     skeleton joint. Rigid primitives get weight 1 on their node; their vertices are pre-multiplied
//     by the inverse of that joint's inverse bind, so the one skinning formula draws both.
//     Missing normals are computed (area-weighted); missing UVs are 0. Triangle strips and fans
//     are converted to lists; points and lines are skipped with a warning. Morph targets
//     (POSITION/NORMAL deltas) become mesh.morphChannels (one per node and target, with the
//     mesh's default weights) and sparse mesh.morphDeltas.
//   - materials (base colour factor/texture, alpha mode, cutoff, double-sided) and every image
//     decoded to RGBA8 (embedded in the GLB, data URIs, or external files next to the .gltf).
//   - rawJson (the glTF JSON) and format (gltf, vrm0 from the "VRM" extension, vrm1 from
//     "VRMC_vrm").
//   - loadGltfFile leaves firstPersonIndices/firstPersonPrimitives a copy of the third-person
//     lists; loadAvatarFile (below) also maps the humanoid bones and builds the first-person draw
//     list, and is what applications call.
//
// Hostile input: every index, accessor range, stride, count and the node hierarchy (cycles, a
// node with two parents) is checked before use; sizes are capped (kLimits) so a small file cannot
// make the loader allocate without bound. Any violation returns an Error naming the offending
// element; nothing is partially returned.
#include <cstdint>
#include <string>
#include <vector>

#include "avatar/avatar_asset.h"
#include "core/result.h"

namespace embody::avatar {

struct GltfLimits {
  uint64_t maxFileBytes = 1ull << 30;      // 1 GiB
  uint64_t maxAccessorCount = 1ull << 24;  // elements in one accessor
  uint64_t maxTotalVertices = 1ull << 24;  // after merging every primitive
  uint64_t maxTotalIndices = 3ull << 24;
  int maxNodes = 1 << 16;
  int maxImageDimension = 8192;  // width or height of a decoded image
  int maxJsonDepth = 512;        // nested arrays and objects (tinygltf recurses once per level)
};

struct GltfLoadReport {
  std::vector<std::string> warnings;  // non-fatal oddities (skipped primitives, undecodable images)
};

// Loads .gltf, .glb or .vrm (a GLB). External buffers and images resolve relative to the file.
Result<AvatarAsset> loadGltfFile(const std::string& path, GltfLoadReport* report = nullptr,
                                 const GltfLimits& limits = {});

// Same from bytes in memory (GLB or JSON text); external URIs resolve relative to baseDir.
Result<AvatarAsset> loadGltfFromMemory(const std::vector<uint8_t>& bytes, const std::string& baseDir,
                                       GltfLoadReport* report = nullptr, const GltfLimits& limits = {});

struct AvatarLoadOptions {
  std::string boneMapFile;  // --bone-map: JSON {"hips": "NodeName", ...}; always wins when given
  GltfLimits limits;
};

// The application entry point: loadGltfFile + humanoid mapping + first-person draw list.
// A file whose humanoid mapping fails still loads (the renderer can draw it); the mapping result
// says what is missing.
Result<AvatarAsset> loadAvatarFile(const std::string& path, const AvatarLoadOptions& options = {},
                                   GltfLoadReport* report = nullptr);

}  // namespace embody::avatar
