#pragma once
// smoothstep: the cubic ease 3t^2 - 2t^3 of t clamped to [0, 1] (flat at both ends), the one ease
// for fades, foot swings, synthetic motions and procedural shapes.
#include <algorithm>

namespace embody {

template <class T>
constexpr T smoothstep(T t) {
  t = std::clamp(t, T(0), T(1));
  return t * t * (T(3) - T(2) * t);
}

// 0 at or below `edge0`, 1 at or above `edge1`, eased between (GLSL's smoothstep).
template <class T>
constexpr T smoothstep(T edge0, T edge1, T x) {
  return smoothstep((x - edge0) / (edge1 - edge0));
}

}  // namespace embody
