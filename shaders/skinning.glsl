// Linear blend skinning, the contract of avatar/avatar_asset.h (also what skinOnCpu does):
//   M(v) = sum_k weight_k * palette[joint_k];  position' = M * (p, 1);  normal' = normalize(mat3(M) * n)
// The including shader declares `palette` (a std430 buffer with `mat4 joints[]`).
mat4 skinMatrix(uvec4 j0, uvec4 j1, vec4 w0, vec4 w1) {
  mat4 m = w0.x * palette.joints[j0.x] + w0.y * palette.joints[j0.y] + w0.z * palette.joints[j0.z] +
           w0.w * palette.joints[j0.w];
  // Most vertices have at most four influences: skip the second set when it is empty.
  if (w1 != vec4(0.0))
    m += w1.x * palette.joints[j1.x] + w1.y * palette.joints[j1.y] + w1.z * palette.joints[j1.z] +
         w1.w * palette.joints[j1.w];
  return m;
}
