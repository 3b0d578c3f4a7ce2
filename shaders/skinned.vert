#version 460
// Skinned avatar: LBS with up to 8 influences from the joint palette (std430 storage buffer).
// With kOutline, the MToon outline's inverted hull (outline.glsl) from the same skinned vertex.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(set = 0, binding = 1, std430) readonly buffer Palette { mat4 joints[]; } palette;
#include "skinning.glsl"
#include "morphing.glsl"
#include "material.glsl"
#include "outline.glsl"

layout(constant_id = 1) const bool kOutline = false;

layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec3 inNormal;
layout(location = 2) in vec2 inUv;
layout(location = 3) in uvec4 inJoints0;
layout(location = 4) in uvec4 inJoints1;
layout(location = 5) in vec4 inWeights0;
layout(location = 6) in vec4 inWeights1;
layout(location = 7) in vec2 inUv1;

layout(location = 0) out vec3 outNormal;
layout(location = 1) out vec4 outUvs;  // xy: TEXCOORD_0, zw: TEXCOORD_1
layout(location = 2) out vec3 outWorld;

void main() {
  vec3 position = inPosition, normal = inNormal;
  applyMorphs(uint(gl_VertexIndex), position, normal);  // morph targets first, then skinning
  const mat4 m = skinMatrix(inJoints0, inJoints1, inWeights0, inWeights1);
  const vec4 world = m * vec4(position, 1.0);
  outNormal = mat3(m) * normal;  // normalised per fragment
  outUvs = vec4(inUv, inUv1);
  outWorld = world.xyz;
  gl_Position = kOutline ? outlineClipPosition(world.xyz, outNormal, outUvs) : scene.views[viewIndex()].viewProj * world;
}
