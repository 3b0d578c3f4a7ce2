#include "app/eval_sheet.h"

#include <algorithm>
#include <cmath>

#include "app/render_job.h"
#include "engine/avatar_renderer.h"
#include "engine/device.h"
#include "engine/image_io.h"
#include "engine/instance.h"

namespace embody::app {

namespace {

constexpr int kThumb = 280;

void plot(avatar::Image& img, int x, int y, const glm::u8vec3& c) {
  for (int dy = 0; dy < 2; ++dy)
    for (int dx = 0; dx < 2; ++dx) {
      const int px = x + dx, py = y + dy;
      if (px < 0 || py < 0 || px >= img.width || py >= img.height) continue;
      uint8_t* p = &img.rgba[(size_t(py) * size_t(img.width) + size_t(px)) * 4];
      p[0] = c.r, p[1] = c.g, p[2] = c.b, p[3] = 255;
    }
}

void line(avatar::Image& img, glm::vec2 a, glm::vec2 b, const glm::u8vec3& c) {
  const int steps = std::max(1, int(std::ceil(glm::length(b - a))));
  for (int i = 0; i <= steps; ++i) {
    const glm::vec2 p = glm::mix(a, b, float(i) / float(steps));
    plot(img, int(p.x), int(p.y), c);
  }
}

// The clip's joints at `frame`, projected with the camera, joined parent to child.
void drawGhost(avatar::Image& img, const engine::Camera& camera, const tracking::BvhAvatar& avatar, const eval::JointTrack& truth,
               int frame) {
  const glm::mat4 vp = camera.viewProjection();
  std::vector<glm::vec2> px(size_t(truth.joints));
  std::vector<bool> visible(size_t(truth.joints));
  for (int j = 0; j < truth.joints; ++j) {
    const glm::vec4 c = vp * glm::vec4(glm::vec3(truth.p(frame, j)), 1.0f);
    visible[size_t(j)] = c.w > 1e-4f;
    px[size_t(j)] = glm::vec2((c.x / c.w * 0.5f + 0.5f) * float(img.width), (c.y / c.w * 0.5f + 0.5f) * float(img.height));
  }
  const glm::u8vec3 orange(255, 140, 30);
  for (int j = 0; j < truth.joints; ++j) {
    const int p = avatar.clip.joints[size_t(j)].parent;
    if (p >= 0 && visible[size_t(j)] && visible[size_t(p)]) line(img, px[size_t(p)], px[size_t(j)], orange);
  }
}

}  // namespace

Status writeEvalSheet(const tracking::BvhAvatar& avatar, const eval::ClipEval& e, const std::filesystem::path& file,
                      const std::string& device) {
  if (e.runs.empty() || e.runs[0].kept.empty()) return Error{"no poses kept for the contact sheet"};
  engine::InstanceOptions io;
  io.validation = engine::Validation::Off;
  auto instance = engine::Instance::create(io);
  if (!instance) return Error{instance.error()};
  auto dev = engine::Device::create(*instance, device);
  if (!dev) return Error{dev.error()};
  engine::AvatarRendererOptions ro;
  ro.width = ro.height = uint32_t(kThumb);
  auto renderer = engine::AvatarRenderer::create(**dev, avatar.asset, ro);
  if (!renderer) return Error{renderer.error()};
  std::vector<avatar::Image> thumbs;
  engine::FrameOptions fo;
  for (const auto& [frame, pose] : e.runs[0].kept) {
    const engine::Camera camera = (*renderer)->orbitAround(pose, 0.5f, 0.15f);
    auto image = (*renderer)->render(pose, camera, fo);
    if (!image) return Error{image.error()};
    drawGhost(*image, camera, avatar, e.truth, frame);
    thumbs.push_back(std::move(image).value());
  }
  return engine::writePng(file.string(), contactSheet(thumbs));
}

}  // namespace embody::app
