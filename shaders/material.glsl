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
  vec4 uvAnimation;     // xy: uvAnimationScrollX/YSpeedFactor, z: uvAnimationRotationSpeedFactor, w: 0 none, 1 VRM 1.0, 2 VRM 0.x
  vec4 uvAnimationMaskUv[2];
} material;
layout(set = 1, binding = 1) uniform sampler2D baseColorTexture;
layout(set = 1, binding = 2) uniform sampler2D emissiveTexture;
layout(set = 1, binding = 3) uniform sampler2D shadeTexture;         // sRGB
layout(set = 1, binding = 4) uniform sampler2D shadingShiftTexture;  // linear, R
layout(set = 1, binding = 5) uniform sampler2D rimTexture;           // sRGB
layout(set = 1, binding = 6) uniform sampler2D matcapTexture;        // sRGB
layout(set = 1, binding = 7) uniform sampler2D outlineWidthTexture;  // linear, G (vertex stage)
layout(set = 1, binding = 8) uniform sampler2D uvAnimationMaskTexture;  // linear, B (VRM 0.x: R)

// The texture coordinate a textureInfo reads: its set (TEXCOORD_0 in uvs.xy, TEXCOORD_1 in
// uvs.zw) through its transform.
vec2 textureUv(vec4 row0, vec4 row1, vec4 uvs) {
  const vec3 uv = vec3(row0.w > 0.5 ? uvs.zw : uvs.xy, 1.0);
  return vec2(dot(row0.xyz, uv), dot(row1.xyz, uv));
}

// MToon UV animation (VRMC_materials_mtoon "UV Animation"), applied to both texture coordinate
// sets before each texture's KHR_texture_transform: rotation about (0.5, 0.5) by speed x time x
// mask with KHR_texture_transform's matrix, then scroll by speed x time x mask. The mask is read at
// the un-animated coordinate through its own transform, at mip level 0 (the vertex stage reads it
// too, for the outline width). VRM 0.x scrolls first, then rotates, and masks with R.
vec4 animatedUvs(vec4 uvs) {
  const float mode = material.uvAnimation.w;
  if (mode < 0.5) return uvs;
  const vec4 m = textureLod(uvAnimationMaskTexture, textureUv(material.uvAnimationMaskUv[0], material.uvAnimationMaskUv[1], uvs), 0.0);
  const float t = scene.clock.x * (mode > 1.5 ? m.r : m.b);
  const float a = material.uvAnimation.z * t, c = cos(a), s = sin(a);
  const mat2 r = mat2(c, -s, s, c);  // columns: u' = c u + s v, v' = -s u + c v
  const vec2 scroll = material.uvAnimation.xy * t;
  if (mode > 1.5) return vec4(r * (uvs.xy + scroll - 0.5) + 0.5, r * (uvs.zw + scroll - 0.5) + 0.5);
  return vec4(r * (uvs.xy - 0.5) + 0.5 + scroll, r * (uvs.zw - 0.5) + 0.5 + scroll);
}
