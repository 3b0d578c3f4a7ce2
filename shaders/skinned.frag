#version 460
// Avatar surfaces: a glTF material (base colour texture x factor, emissive, KHR_texture_transform,
// KHR_materials_unlit, alpha modes) lit by hemisphere ambient + one directional light, or an MToon
// material (mtoon.glsl). With kOutline, the MToon outline colour of the inverted hull.
// Output is linear; the sRGB colour target encodes it.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "material.glsl"
#include "mtoon.glsl"

layout(constant_id = 0) const int kAlphaMode = 0;  // 0 OPAQUE, 1 MASK, 2 BLEND (one pipeline each)
layout(constant_id = 1) const bool kOutline = false;

layout(location = 0) in vec3 inNormal;
layout(location = 1) in vec4 inUvs;
layout(location = 2) in vec3 inWorld;
layout(location = 0) out vec4 outColor;

void main() {
  const vec4 uvs = animatedUvs(inUvs);
  const vec4 base = material.baseColorFactor *
                    texture(baseColorTexture, textureUv(material.baseColorUv[0], material.baseColorUv[1], uvs));
  if (kAlphaMode == 1 && base.a < material.params.x) discard;
  const vec3 emissive =
      material.emissive.rgb * texture(emissiveTexture, textureUv(material.emissiveUv[0], material.emissiveUv[1], uvs)).rgb;
  vec3 n = normalize(inNormal);
  // Double-sided materials light their back faces too; the outline hull is seen from inside but
  // stands for the outward surface.
  if (!gl_FrontFacing && !kOutline) n = -n;
  vec3 color = base.rgb;
  if (material.params.z > 0.5) {
    color = mtoonColor(base.rgb, n, normalize(scene.views[viewIndex()].eye.xyz - inWorld), uvs);
  } else if (material.params.y < 0.5) {
    const vec3 ambient = mix(scene.groundColor.rgb, scene.skyColor.rgb, n.y * 0.5 + 0.5);
    const float diffuse = max(dot(n, scene.lightDirection.xyz), 0.0);
    color *= ambient + scene.lightColor.rgb * diffuse;
  }
  color += emissive;
  if (kOutline) color = material.outlineColor.rgb * mix(vec3(1.0), color, material.mixes.z);
  outColor = vec4(color, kAlphaMode == 2 ? base.a : 1.0);
}
