// Morph targets, applied before skinning (the contract of avatar::skinOnCpu):
//   position += sum_c weight[c] * delta_c.position;  normal += sum_c weight[c] * delta_c.normal
// Deltas are sparse (avatar::MorphDelta): each vertex has a range [first, first + count) of
// deltas; a delta's position.w holds its channel index (uint bits). Weights are per frame, one
// per morph channel. Every read is bounds-checked against the buffers' lengths, so an avatar
// without morph targets binds one-element placeholder buffers and nothing moves.
// Bindings 3..5 of set 0 (skinned.vert's 0..1 and skin.comp's 0..2 stay as they are).
struct MorphDelta {
  vec4 position;  // xyz: offset, w: channel (floatBitsToUint)
  vec4 normal;
};
layout(set = 0, binding = 3, std430) readonly buffer MorphRanges { uvec2 ranges[]; } morphRanges;
layout(set = 0, binding = 4, std430) readonly buffer MorphDeltas { MorphDelta deltas[]; } morphDeltas;
layout(set = 0, binding = 5, std430) readonly buffer MorphWeights { float weights[]; } morphWeights;

void applyMorphs(uint vertex, inout vec3 position, inout vec3 normal) {
  if (vertex >= uint(morphRanges.ranges.length())) return;
  const uvec2 r = morphRanges.ranges[vertex];
  const uint end = min(r.x + r.y, uint(morphDeltas.deltas.length()));
  const uint channels = uint(morphWeights.weights.length());
  for (uint i = r.x; i < end; ++i) {
    const MorphDelta d = morphDeltas.deltas[i];
    const uint c = floatBitsToUint(d.position.w);
    if (c >= channels) continue;
    const float w = morphWeights.weights[c];
    position += w * d.position.xyz;
    normal += w * d.normal.xyz;
  }
}
