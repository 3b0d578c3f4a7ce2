#pragma once
// AvatarAsset: what a loader (glTF/VRM, or the procedural default avatar) produces and what the
// renderer and the body model consume. Immutable runtime data; import code lives in avatar/gltf.
//
// Skinning contract (same on CPU and GPU):
//   palette[j]  = global[j] * mesh.inverseBind[j]          for every skeleton joint j
//   skinned(v)  = sum_k weight_k(v) * palette[joint_k(v)] * vec4(position(v), 1)
//   normals use the same blend of palette matrices (upper 3x3), then renormalise.
// Joint indices in vertices refer to Skeleton joints directly (loaders remap glTF skin joint
// indices). A mesh attached rigidly to a node is expressed as weight 1 on that node with an
// identity inverse bind, so one formula draws everything. Weights are normalised to sum to 1.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "avatar/humanoid/humanoid_map.h"
#include "avatar/skeleton.h"
#include "avatar/vrm/expressions.h"
#include "avatar/vrm/look_at.h"
#include "avatar/vrm/spring_bone.h"

namespace embody::avatar {

constexpr int kMaxInfluences = 8;  // JOINTS_0/1 + WEIGHTS_0/1

struct SkinnedVertex {
  glm::vec3 position{0.0f};
  glm::vec3 normal{0.0f, 1.0f, 0.0f};
  glm::vec2 uv{0.0f};
  glm::uvec4 joints0{0}, joints1{0};
  glm::vec4 weights0{1.0f, 0.0f, 0.0f, 0.0f}, weights1{0.0f};
  glm::vec2 uv1{0.0f};  // TEXCOORD_1 (a material's texture may read it; KHR_texture_transform texCoord)
};

enum class AlphaMode { Opaque, Mask, Blend };

struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;  // 8-bit RGBA, row-major, top row first
};

// KHR_texture_transform on one textureInfo: uv' = offset + R(rotation) * (scale * uv), with
// R = [cos sin; -sin cos] (u' = cos*u + sin*v, v' = -sin*u + cos*v: the specification's example,
// "the lower left quadrant rotated clockwise 90 degrees", and three.js / cesium-native agree).
// texCoord picks TEXCOORD_0 or TEXCOORD_1 (the textureInfo's texCoord, overridden by the extension's).
struct TextureTransform {
  glm::vec2 offset{0.0f};
  float rotation = 0.0f;  // radians
  glm::vec2 scale{1.0f};
  int texCoord = 0;  // 0 or 1
  bool isIdentity() const { return offset == glm::vec2(0.0f) && rotation == 0.0f && scale == glm::vec2(1.0f); }
  glm::vec2 apply(glm::vec2 uv) const;
};

// VRM's toon material (VRMC_materials_mtoon 1.0; VRM 0.x "VRM/MToon" materialProperties are
// converted to it on load, avatar/gltf/mtoon_json.h). Colours are linear. Textures are indices
// into AvatarAsset::images (-1: none) with their KHR_texture_transform. Defaults are the 1.0
// specification's.
enum class OutlineWidthMode { None, WorldCoordinates, ScreenCoordinates };

struct MToon {
  glm::vec3 shadeColor{0.0f};  // shadeColorFactor
  int shadeImage = -1;         // shadeMultiplyTexture (sRGB)
  TextureTransform shadeTransform;
  float shadingShift = 0.0f;  // shadingShiftFactor
  int shadingShiftImage = -1;  // shadingShiftTexture (linear, R)
  TextureTransform shadingShiftTransform;
  float shadingShiftScale = 1.0f;
  float shadingToony = 0.9f;    // shadingToonyFactor, 0..1
  float giEqualization = 0.9f;  // giEqualizationFactor, 0..1
  glm::vec3 matcapFactor{1.0f};
  int matcapImage = -1;  // matcapTexture (sRGB, sampled by the view-space normal; none: no matcap)
  glm::vec3 rimColor{0.0f};     // parametricRimColorFactor
  float rimFresnelPower = 5.0f;  // parametricRimFresnelPowerFactor, >= 0
  float rimLift = 0.0f;          // parametricRimLiftFactor
  int rimImage = -1;             // rimMultiplyTexture (sRGB)
  TextureTransform rimTransform;
  float rimLightingMix = 1.0f;  // rimLightingMixFactor, 0..1
  OutlineWidthMode outlineMode = OutlineWidthMode::None;
  float outlineWidth = 0.0f;  // metres (world) or a fraction of the screen height (screen)
  int outlineWidthImage = -1;  // outlineWidthMultiplyTexture (linear, G)
  TextureTransform outlineWidthTransform;
  glm::vec3 outlineColor{0.0f};
  float outlineLightingMix = 1.0f;  // 0..1
  int renderQueueOffset = 0;        // BLEND only: -9..0, or 0..+9 with transparentWithZWrite
  bool transparentWithZWrite = false;
  // UV animation (1.0 "UV Animation"): every texture but the matcap reads
  //   uv' = R(rotation x t x mask) (uv - 0.5) + 0.5 + scroll x t x mask   (before its KHR_texture_transform)
  // with R as KHR_texture_transform's and mask = B of uvAnimationMaskTexture (1 without one). VRM
  // 0.x (`uvAnimationVrm0`) scrolls before it rotates and reads the mask's R, as its shader does.
  int uvAnimationMaskImage = -1;  // uvAnimationMaskTexture (linear)
  TextureTransform uvAnimationMaskTransform;
  glm::vec2 uvAnimationScroll{0.0f};  // uvAnimationScrollX/YSpeedFactor: UV per second, v down
  float uvAnimationRotation = 0.0f;   // uvAnimationRotationSpeedFactor: radians per second
  bool uvAnimationVrm0 = false;
  bool hasUvAnimation() const { return uvAnimationScroll != glm::vec2(0.0f) || uvAnimationRotation != 0.0f; }
  bool hasOutline() const { return outlineMode != OutlineWidthMode::None && outlineWidth > 0.0f; }
};

struct Material {
  std::string name;
  glm::vec4 baseColorFactor{1.0f};
  int baseColorImage = -1;  // index into AvatarAsset::images, -1 for none
  TextureTransform baseColorTransform;
  glm::vec3 emissiveFactor{0.0f};
  float emissiveStrength = 1.0f;  // KHR_materials_emissive_strength (multiplies emissiveFactor)
  int emissiveImage = -1;         // index into AvatarAsset::images, -1 for none
  TextureTransform emissiveTransform;
  bool unlit = false;  // KHR_materials_unlit: colour = base colour, no lighting
  AlphaMode alphaMode = AlphaMode::Opaque;
  float alphaCutoff = 0.5f;
  bool doubleSided = false;
  bool isMToon = false;  // drawn with `mtoon` (VRMC_materials_mtoon or VRM 0.x MToon)
  MToon mtoon;
};

struct Primitive {
  uint32_t firstIndex = 0;
  uint32_t indexCount = 0;
  int material = -1;    // index into AvatarAsset::materials, -1 for the default material
  int sourceNode = -1;  // glTF node and mesh the triangles came from (VRM first-person annotations)
  int sourceMesh = -1;
};

// Morph targets (glTF `targets`), applied before skinning: position' = position + sum_c w_c * delta.
// A channel is one target index of one glTF mesh instanced by one node: every primitive of that
// mesh shares the channel's weight, as glTF's `weights` do. VRM expressions bind to channels
// (1.0 by node + index, 0.x by mesh + index).
struct MorphChannel {
  int sourceNode = -1, sourceMesh = -1;
  int targetIndex = 0;
  std::string name;            // mesh.extras.targetNames[targetIndex] when present
  float defaultWeight = 0.0f;  // mesh.weights[targetIndex] (glTF default, 0 when absent)
};

// One vertex's offset in one channel (sparse: only vertices the target moves). Sorted by vertex.
struct MorphDelta {
  uint32_t vertex = 0;
  uint32_t channel = 0;
  glm::vec3 position{0.0f};
  glm::vec3 normal{0.0f};
};

struct SkinnedMesh {
  std::vector<SkinnedVertex> vertices;
  std::vector<uint32_t> indices;      // triangle list, all primitives back to back
  std::vector<Primitive> primitives;  // third-person draw list
  // First-person draw list: the same vertices, with triangles that belong to the user's own head
  // removed (VRM firstPerson annotations, or weights to the head and its descendants).
  std::vector<uint32_t> firstPersonIndices;
  std::vector<Primitive> firstPersonPrimitives;
  std::vector<glm::mat4> inverseBind;  // one per skeleton joint (identity where unused)
  std::vector<MorphChannel> morphChannels;
  std::vector<MorphDelta> morphDeltas;  // sorted by vertex
  size_t triangleCount() const { return indices.size() / 3; }
};

enum class AvatarFormat { Gltf, Vrm0, Vrm1, Procedural };
std::string_view avatarFormatName(AvatarFormat f);  // "gltf", "vrm0", "vrm1", "procedural"

// How the first-person draw list was made.
struct FirstPersonInfo {
  std::string mode;             // "vrm" (meshAnnotations), "auto" (head-weighted triangles dropped), "none"
  int headJoint = -1;           // the joint whose subtree is hidden in first person
  size_t removedTriangles = 0;  // triangles in the third-person list that first person does not draw
  std::vector<std::string> annotations;  // "node or mesh name: type" for VRM files
};

struct AvatarAsset {
  std::string sourcePath;  // "" for the procedural default
  AvatarFormat format = AvatarFormat::Gltf;
  Skeleton skeleton;
  SkinnedMesh mesh;
  std::vector<Material> materials;
  std::vector<Image> images;
  int skinJointCount = 0;  // joints of the glTF skin(s); 0 when the file has no skin
  std::string rawJson;     // the glTF JSON document, for extensions read later (VRM humanoid, firstPerson)
  std::vector<int> gltfNodeToJoint;  // glTF node index -> Skeleton joint index (empty for procedural)
  HumanoidMap humanoid;              // filled by loadAvatarFile / buildDefaultAvatar
  FirstPersonInfo firstPerson;
  // VRM motion (avatar/vrm; filled by prepareAvatar from rawJson): spring bones, expressions,
  // look-at, and what their parsers dropped or defaulted.
  SpringBoneSetup springBones;
  ExpressionSet expressions;
  LookAtSetup lookAt;
  std::vector<std::string> vrmWarnings;
};

// Makes the skeleton rigid: every joint's rest global becomes a rotation, a uniform scale and a
// translation, and whatever non-uniform scale or shear the file gave it is folded into its own
// inverse bind (inverseBind' = rigid^-1 * global * inverseBind, so the rest draws the same), where
// it shapes that joint's vertices only. glTF multiplies a node's scale into its children: a
// non-uniform scale on a bone with children (say (2, 0.5, 1) on a vertebra, the children's offsets
// compensated) drew right at rest and sheared the children once the bone turned, which no rotation
// undoes (the arms stretched to several times their length; robustness probe, session 20). Unreal
// and Unity import, Maya's segment scale compensation and ozz-animation's runtime skeleton do the
// same. The rigid rotation is the closest one (polar decomposition), the scale the cube root of
// the determinant. A joint whose global is already a similarity, mirrored ones included (the body
// model refuses those by name), keeps its rest and bind bit for bit, and its subtree too unless a
// joint above it changes. A bone hidden by a zero scale keeps its rotation and scale and only moves
// to its pivot. Needs mesh.inverseBind sized to the skeleton; returns the joints whose rest changed.
int foldBoneScaleIntoBind(AvatarAsset& asset);

// Palette for a pose: palette[j] = global[j] * inverseBind[j].
void computeSkinningPalette(const AvatarAsset& asset, const std::vector<glm::mat4>& globals,
                            std::vector<glm::mat4>& palette);

// Reference CPU skinner with the contract above: positions and normals for every vertex.
// morphWeights (one per mesh.morphChannels, may be empty: the base shape) are applied first.
void skinOnCpu(const SkinnedMesh& mesh, const std::vector<glm::mat4>& palette,
               std::vector<glm::vec3>& positions, std::vector<glm::vec3>& normals,
               std::span<const float> morphWeights = {});

// The glTF default weight of every morph channel (what a frame without expressions draws).
std::vector<float> defaultMorphWeights(const SkinnedMesh& mesh);

}  // namespace embody::avatar
