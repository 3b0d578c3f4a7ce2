#pragma once
// PNG files (stb) and image comparison with a per-channel tolerance, for golden-image tests and
// the CLI's frames.
#include <string>

#include "avatar/avatar_asset.h"
#include "core/result.h"

namespace embody::engine {

Status writePng(const std::string& path, const avatar::Image& image);
Result<avatar::Image> readPng(const std::string& path);

struct ImageDifference {
  bool sameSize = false;
  size_t failingPixels = 0;  // pixels with any channel off by more than the tolerance
  size_t totalPixels = 0;
  int maxChannelDelta = 0;
  double failingFraction() const { return totalPixels ? double(failingPixels) / double(totalPixels) : 1.0; }
  // Failing pixels in red over a dimmed copy of the expected image.
  avatar::Image diff;
};

ImageDifference compareImages(const avatar::Image& actual, const avatar::Image& expected, int tolerance);

}  // namespace embody::engine
