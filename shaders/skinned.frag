#version 460
// Base colour (texture x factor), glTF alpha modes, hemisphere ambient + one directional light.
// Output is linear; the sRGB colour target encodes it.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(constant_id = 0) const int kAlphaMode = 0;  // 0 OPAQUE, 1 MASK, 2 BLEND (one pipeline each)
layout(set = 1, binding = 0) uniform sampler2D baseColorTexture;

layout(location = 0) in vec3 inNormal;
layout(location = 1) in vec2 inUv;
layout(location = 0) out vec4 outColor;

void main() {
  const vec4 base = pc.baseColorFactor * texture(baseColorTexture, inUv);
  if (kAlphaMode == 1 && base.a < pc.alphaCutoff) discard;
  vec3 n = normalize(inNormal);
  if (!gl_FrontFacing) n = -n;  // double-sided materials light their back faces too
  const vec3 ambient = mix(scene.groundColor.rgb, scene.skyColor.rgb, n.y * 0.5 + 0.5);
  const float diffuse = max(dot(n, scene.lightDirection.xyz), 0.0);
  const vec3 color = base.rgb * (ambient + scene.lightColor.rgb * diffuse);
  outColor = vec4(color, kAlphaMode == 2 ? base.a : 1.0);
}
