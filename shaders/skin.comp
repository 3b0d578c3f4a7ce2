#version 460
// GPU skinning into a buffer, with the same code as the vertex shader (skinning.glsl), so tests
// can compare GPU-skinned positions and normals with the CPU reference skinner.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;

// avatar::SkinnedVertex, 26 x 32-bit words: position(3) normal(3) uv(2) joints0(4) joints1(4)
// weights0(4) weights1(4) uv1(2). Read as words because std430 would pad a vec3 member to 16 bytes.
layout(set = 0, binding = 0, std430) readonly buffer Vertices { float words[]; } vertices;
layout(set = 0, binding = 1, std430) readonly buffer Palette { mat4 joints[]; } palette;
struct Skinned { vec4 position; vec4 normal; };
layout(set = 0, binding = 2, std430) writeonly buffer Output { Skinned v[]; } outputs;
layout(push_constant) uniform Push { uint vertexCount; } pc;

#include "skinning.glsl"
#include "morphing.glsl"

const uint kStride = 26u;

vec4 readVec4(uint base) {
  return vec4(vertices.words[base], vertices.words[base + 1u], vertices.words[base + 2u], vertices.words[base + 3u]);
}
uvec4 readUvec4(uint base) { return floatBitsToUint(readVec4(base)); }

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= pc.vertexCount) return;
  const uint b = i * kStride;
  vec3 p = vec3(vertices.words[b], vertices.words[b + 1u], vertices.words[b + 2u]);
  vec3 n = vec3(vertices.words[b + 3u], vertices.words[b + 4u], vertices.words[b + 5u]);
  applyMorphs(i, p, n);
  const mat4 m = skinMatrix(readUvec4(b + 8u), readUvec4(b + 12u), readVec4(b + 16u), readVec4(b + 20u));
  const vec3 sn = mat3(m) * n;
  const float len = length(sn);
  outputs.v[i].position = vec4((m * vec4(p, 1.0)).xyz, 1.0);
  outputs.v[i].normal = vec4(len > 0.0 ? sn / len : normalize(n), 0.0);
}
