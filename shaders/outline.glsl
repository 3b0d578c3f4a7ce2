// MToon outline: the inverted hull's vertex, pushed out along the skinned normal (front faces are
// culled by the pipeline, so only the hull's inside, around the silhouette, is seen). Width is
// outlineWidthFactor x the G channel of outlineWidthMultiplyTexture:
//   world:  metres along the world normal;
//   screen: a share of the target's height, along the normal's direction on screen (the offset is
//           scaled by clip w so that it keeps its size in pixels at any distance).
// Included by skinned.vert after common.glsl and material.glsl.
vec4 outlineClipPosition(vec3 world, vec3 normal, vec4 uvs) {
  const mat4 viewProj = scene.views[viewIndex()].viewProj;
  const float width =
      material.mixes.y * textureLod(outlineWidthTexture, textureUv(material.outlineWidthUv[0], material.outlineWidthUv[1], animatedUvs(uvs)), 0.0).g;
  const float len = length(normal);
  if (len < 1e-8) return viewProj * vec4(world, 1.0);
  const vec3 n = normal / len;
  if (material.params.w < 1.5) return viewProj * vec4(world + n * width, 1.0);
  vec4 clip = viewProj * vec4(world, 1.0);
  const vec2 onScreen = (viewProj * vec4(n, 0.0)).xy * vec2(pc.aspect, 1.0);  // pixel-proportional
  const float l = length(onScreen);
  if (l > 1e-8) clip.xy += (onScreen / l) * vec2(1.0 / pc.aspect, 1.0) * (2.0 * width * clip.w);
  return clip;
}
