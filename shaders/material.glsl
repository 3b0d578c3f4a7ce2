// A glTF material (set 1): factors, texture transforms and flags in a uniform block (std140 mirror:
// MaterialBlock in engine/gpu_avatar.cpp) beside its base-colour and emissive textures.
// Included by skinned.frag; not compiled on its own.

layout(set = 1, binding = 0, std140) uniform Material {
  vec4 baseColorFactor;
  vec4 emissive;        // rgb: emissiveFactor x KHR_materials_emissive_strength
  vec4 baseColorUv[2];  // KHR_texture_transform as two rows of a 2x3 matrix; [0].w: texCoord set (0/1)
  vec4 emissiveUv[2];
  vec4 params;          // x: alphaCutoff, y: 1 = KHR_materials_unlit
} material;
layout(set = 1, binding = 1) uniform sampler2D baseColorTexture;
layout(set = 1, binding = 2) uniform sampler2D emissiveTexture;

// The texture coordinate a textureInfo reads: its set (TEXCOORD_0 in uvs.xy, TEXCOORD_1 in
// uvs.zw) through its transform.
vec2 textureUv(vec4 row0, vec4 row1, vec4 uvs) {
  const vec3 uv = vec3(row0.w > 0.5 ? uvs.zw : uvs.xy, 1.0);
  return vec2(dot(row0.xyz, uv), dot(row1.xyz, uv));
}
