#pragma once
// One degree in radians. The one copy of the constant: a file-local copy in each file that
// needed it clashed when a unity build (cmake/EmbodyCompilerOptions.cmake) put two in one scope.
#include <numbers>

namespace embody {

inline constexpr double kDeg = std::numbers::pi / 180.0;

}  // namespace embody
