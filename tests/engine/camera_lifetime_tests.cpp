// Camera maths (OpenXR-style asymmetric frusta into Vulkan clip space) and resource lifetime
// (things retired during a frame live until that frame has finished).
#include <catch2/catch.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <memory>

#include "engine/camera.h"
#include "engine/renderer.h"
#include "engine_test_support.h"

using namespace embody;

namespace {

glm::vec3 ndc(const glm::mat4& m, const glm::vec3& p) {
  const glm::vec4 c = m * glm::vec4(p, 1.0f);
  return glm::vec3(c) / c.w;
}

}  // namespace

TEST_CASE("projectionFromFov maps the asymmetric frustum edges to the Vulkan clip square", "[unit][camera]") {
  const engine::FovAngles fov{-0.9f, 0.6f, 0.7f, -0.8f};
  const float n = 0.1f, f = 50.0f;
  const glm::mat4 p = engine::projectionFromFov(fov, n, f);
  for (float z : {n, 1.0f, f}) {
    // Points on the left/right/up/down frustum planes at depth z (view looks down -Z).
    CHECK(ndc(p, {std::tan(fov.angleLeft) * z, 0.0f, -z}).x == Approx(-1.0f).margin(1e-5));
    CHECK(ndc(p, {std::tan(fov.angleRight) * z, 0.0f, -z}).x == Approx(1.0f).margin(1e-5));
    CHECK(ndc(p, {0.0f, std::tan(fov.angleUp) * z, -z}).y == Approx(-1.0f).margin(1e-5));  // Vulkan: up is -y
    CHECK(ndc(p, {0.0f, std::tan(fov.angleDown) * z, -z}).y == Approx(1.0f).margin(1e-5));
  }
  CHECK(ndc(p, {0.0f, 0.0f, -n}).z == Approx(0.0f).margin(1e-6));
  CHECK(ndc(p, {0.0f, 0.0f, -f}).z == Approx(1.0f).margin(1e-5));

  const auto sym = engine::FovAngles::symmetric(glm::radians(60.0f), 2.0f);
  CHECK(sym.angleUp == Approx(glm::radians(30.0f)));
  CHECK(std::tan(sym.angleRight) == Approx(2.0f * std::tan(sym.angleUp)));
}

TEST_CASE("orbit and stereo cameras sit where they should", "[unit][camera]") {
  const engine::FovAngles fov = engine::FovAngles::symmetric(1.0f, 1.0f);
  const engine::Camera front = engine::orbitCamera({0.0f, 1.0f, 0.0f}, 3.0f, 0.0f, 0.0f, fov);
  CHECK(glm::length(front.position() - glm::vec3(0.0f, 1.0f, 3.0f)) < 1e-5f);  // yaw 0: from +Z
  const glm::vec3 target = ndc(front.viewProjection(), {0.0f, 1.0f, 0.0f});
  CHECK(std::abs(target.x) < 1e-5f);
  CHECK(std::abs(target.y) < 1e-5f);
  const engine::Camera above = engine::orbitCamera({0.0f, 0.0f, 0.0f}, 2.0f, 0.0f, 0.5f, fov);
  CHECK(above.position().y > 0.9f);  // positive pitch looks down from above

  const glm::mat4 head = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 1.6f, 0.0f));
  const auto eyes = engine::stereoCameras(head, 0.064f, fov, fov);
  CHECK(eyes[0].position().x == Approx(-0.032f));
  CHECK(eyes[1].position().x == Approx(0.032f));
  CHECK(eyes[0].position().y == Approx(1.6f));
  // A point straight ahead of the head is right of centre for the left eye, left for the right eye.
  CHECK(ndc(eyes[0].viewProjection(), {0.0f, 1.6f, -2.0f}).x > 0.0f);
  CHECK(ndc(eyes[1].viewProjection(), {0.0f, 1.6f, -2.0f}).x < 0.0f);
}

TEST_CASE("retired objects live until their frame has retired", "[gpu][lifetime]") {
  struct Tracked {
    std::shared_ptr<int> alive;
  };
  test::GpuContext ctx;
  auto renderer = engine::Renderer::create(*ctx.device);
  REQUIRE(renderer);
  engine::Renderer& r = **renderer;
  auto alive = std::make_shared<int>(1);
  std::weak_ptr<int> watch = alive;

  REQUIRE(r.beginFrame());  // frame 0, slot 0
  r.retire(Tracked{std::move(alive)});
  REQUIRE(r.endFrame());
  CHECK_FALSE(watch.expired());  // frame 0 may still be executing
  REQUIRE(r.beginFrame());       // frame 1, slot 1
  REQUIRE(r.endFrame());
  CHECK_FALSE(watch.expired());  // slot 0 has not been reused yet
  REQUIRE(r.beginFrame());       // frame 2 reuses slot 0: waits for frame 0, releases its objects
  CHECK(watch.expired());
  REQUIRE(r.endFrame());

  // Retired outside a frame: attached to the last submitted frame.
  auto late = std::make_shared<int>(2);
  std::weak_ptr<int> watchLate = late;
  r.retire(Tracked{std::move(late)});
  CHECK_FALSE(watchLate.expired());
  r.waitIdle();
  CHECK(watchLate.expired());

  // Misuse is an error, not a crash.
  CHECK_FALSE(r.endFrame());
  CHECK_FALSE(r.setScene({}));
  REQUIRE(r.beginFrame());
  CHECK_FALSE(r.beginFrame());
  REQUIRE(r.endFrame());
}
