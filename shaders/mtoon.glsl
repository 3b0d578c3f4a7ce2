// MToon shading, VRMC_materials_mtoon 1.0 (Lighting, Global Illumination, Rim Lighting) with this
// renderer's lights: one directional light (lightColor) and the hemisphere ambient as rawGi(n).
// Included by skinned.frag after material.glsl; not compiled on its own.

float linearstep(float a, float b, float t) { return clamp((t - a) / max(b - a, 1e-5), 0.0, 1.0); }

// base: lit colour (baseColorFactor x texture), n: unit normal, v: unit vector towards the eye.
vec3 mtoonColor(vec3 base, vec3 n, vec3 v, vec4 uvs) {
  // Lighting: shade -> lit across dot(N, L) shifted and sharpened (toony). The specification's
  // pseudocode writes lerp(base, shade, shading); its figures, UniVRM and three-vrm go from shade
  // (shading 0) to lit (1), as here.
  float shading = dot(n, scene.lightDirection.xyz) + material.shadeColor.w +
                  texture(shadingShiftTexture, textureUv(material.shadingShiftUv[0], material.shadingShiftUv[1], uvs)).r *
                      material.shading.z;
  shading = linearstep(-1.0 + material.shading.x, 1.0 - material.shading.x, shading);
  const vec3 shade =
      material.shadeColor.rgb * texture(shadeTexture, textureUv(material.shadeUv[0], material.shadeUv[1], uvs)).rgb;
  vec3 color = mix(shade, base, shading) * scene.lightColor.rgb;

  // Global illumination, equalized towards the average of up and down.
  const vec3 rawGi = mix(scene.groundColor.rgb, scene.skyColor.rgb, n.y * 0.5 + 0.5);
  const vec3 uniformGi = 0.5 * (scene.skyColor.rgb + scene.groundColor.rgb);
  const vec3 gi = mix(rawGi, uniformGi, material.shading.y);
  color += gi * base;

  // Rim: matcap by the view-space normal (v grows downwards in glTF images, so an upward normal
  // reads the top of the matcap) + parametric fresnel rim, masked, mixed with the lighting.
  vec3 viewX = vec3(v.z, 0.0, -v.x);
  viewX = dot(viewX, viewX) > 1e-10 ? normalize(viewX) : vec3(1.0, 0.0, 0.0);
  const vec3 viewY = cross(v, viewX);
  const vec2 matcapUv = vec2(0.5 + 0.495 * dot(viewX, n), 0.5 - 0.495 * dot(viewY, n));
  vec3 rim = material.matcapFactor.rgb * texture(matcapTexture, matcapUv).rgb;
  const float fresnel = pow(clamp(1.0 - dot(n, v) + material.rimColor.w, 0.0, 1.0), max(material.shading.w, 1e-5));
  rim += fresnel * material.rimColor.rgb;
  rim *= texture(rimTexture, textureUv(material.rimUv[0], material.rimUv[1], uvs)).rgb;
  rim *= mix(vec3(1.0), scene.lightColor.rgb + gi, material.mixes.x);
  return color + rim;
}
