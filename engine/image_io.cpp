#include "engine/image_io.h"

#include <stb_image.h>
#include <stb_image_write.h>

#include <algorithm>
#include <cstdlib>

namespace embody::engine {

Status writePng(const std::string& path, const avatar::Image& image) {
  if (image.width <= 0 || image.height <= 0 || image.rgba.size() != size_t(image.width) * image.height * 4)
    return Error{"writePng: image has no pixels or inconsistent size"};
  if (!stbi_write_png(path.c_str(), image.width, image.height, 4, image.rgba.data(), image.width * 4))
    return Error{"could not write " + path};
  return {};
}

Result<avatar::Image> readPng(const std::string& path) {
  int w = 0, h = 0, n = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &n, 4);
  if (!data) return Error{"could not read image " + path + ": " + (stbi_failure_reason() ? stbi_failure_reason() : "?")};
  avatar::Image img;
  img.width = w;
  img.height = h;
  img.rgba.assign(data, data + size_t(w) * h * 4);
  stbi_image_free(data);
  return img;
}

ImageDifference compareImages(const avatar::Image& actual, const avatar::Image& expected, int tolerance) {
  ImageDifference d;
  d.sameSize = actual.width == expected.width && actual.height == expected.height &&
               actual.rgba.size() == expected.rgba.size();
  d.totalPixels = size_t(std::max(expected.width, 0)) * size_t(std::max(expected.height, 0));
  if (!d.sameSize) {
    d.failingPixels = d.totalPixels;
    return d;
  }
  d.diff = expected;
  for (size_t p = 0; p < d.totalPixels; ++p) {
    int worst = 0;
    for (int c = 0; c < 4; ++c) worst = std::max(worst, std::abs(int(actual.rgba[p * 4 + c]) - int(expected.rgba[p * 4 + c])));
    d.maxChannelDelta = std::max(d.maxChannelDelta, worst);
    uint8_t* out = &d.diff.rgba[p * 4];
    if (worst > tolerance) {
      ++d.failingPixels;
      out[0] = 255;
      out[1] = out[2] = 0;
    } else {
      for (int c = 0; c < 3; ++c) out[c] = uint8_t(out[c] / 4);
    }
    out[3] = 255;
  }
  return d;
}

}  // namespace embody::engine
