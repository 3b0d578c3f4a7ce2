// A material (set 1): factors, texture transforms and flags in a uniform block (std140 mirror:
// MaterialBlock in engine/gpu_avatar.cpp) beside its textures. glTF materials use the first two
// textures; MToon materials (VRMC_materials_mtoon, VRM 0.x MToon) all of them. Included by
// skinned.frag and, for the outline width, skinned.vert; not compiled on its own.

layout(set = 1, binding = 0, std140) uniform Material {
  vec4 baseColorFactor;
  vec4 emissive;        // rgb: emissiveFactor x KHR_materials_emissive_strength
  vec4 baseColorUv[2];  // KHR_texture_transform as two rows of a 2x3 matrix; [0].w: texCoord set (0/1)
  vec4 emissiveUv[2];
  vec4 params;          // x: alphaCutoff, y: 1 = KHR_materials_unlit, z: 1 = MToon, w: outline mode (0 none, 1 world, 2 screen)
  // MToon (VRMC_materials_mtoon names)
  vec4 shadeColor;      // rgb: shadeColorFactor, w: shadingShiftFactor
  vec4 shading;         // x: shadingToonyFactor, y: giEqualizationFactor, z: shadingShiftTexture.scale (0 without one), w: parametricRimFresnelPowerFactor
  vec4 rimColor;        // rgb: parametricRimColorFactor, w: parametricRimLiftFactor
  vec4 mixes;           // x: rimLightingMixFactor, y: outlineWidthFactor, z: outlineLightingMixFactor
  vec4 matcapFactor;    // rgb (0 without a matcap texture)
  vec4 outlineColor;    // rgb: outlineColorFactor
  vec4 shadeUv[2];
  vec4 shadingShiftUv[2];
  vec4 rimUv[2];
  vec4 outlineWidthUv[2];
} material;
layout(set = 1, binding = 1) uniform sampler2D baseColorTexture;
layout(set = 1, binding = 2) uniform sampler2D emissiveTexture;
layout(set = 1, binding = 3) uniform sampler2D shadeTexture;         // sRGB
layout(set = 1, binding = 4) uniform sampler2D shadingShiftTexture;  // linear, R
layout(set = 1, binding = 5) uniform sampler2D rimTexture;           // sRGB
layout(set = 1, binding = 6) uniform sampler2D matcapTexture;        // sRGB
layout(set = 1, binding = 7) uniform sampler2D outlineWidthTexture;  // linear, G (vertex stage)

// The texture coordinate a textureInfo reads: its set (TEXCOORD_0 in uvs.xy, TEXCOORD_1 in
// uvs.zw) through its transform.
vec2 textureUv(vec4 row0, vec4 row1, vec4 uvs) {
  const vec3 uv = vec3(row0.w > 0.5 ? uvs.zw : uvs.xy, 1.0);
  return vec2(dot(row0.xyz, uv), dot(row1.xyz, uv));
}
