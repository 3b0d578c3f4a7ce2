// Frame time of the renderer on the device in use (named in the JSON context and on stdout):
//   BM_Frame/<avatar>/<WxH>/cold   first frame after creating the renderer (pipeline compilation)
//   BM_Frame/<avatar>/<WxH>/warm   steady state; each iteration is one frame, submitted and
//                                  waited for (skinning + grid + gizmos, no readback)
//   BM_Stereo/<avatar>/2x1440x1584/<multiview|twopass>/<cold|warm>
//   BM_Readback/<avatar>/<WxH>     a warm frame plus the copy to host memory
// Avatars: "default" (the built-in H-Anim mannequin `embody render --avatar default` and `make
// demo` draw, ~25k triangles), "dense20k" (the engine's procedural test mesh at ~20k triangles,
// the size style.md's lavapipe figure was measured with),
// and "cesiumman" (../shared/assets/CesiumMan.glb; skipped when absent).
// Device: EMBODY_BENCH_DEVICE (same selectors as --device), default auto.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "avatar/gltf/gltf_loader.h"
#include "avatar/procedural/default_avatar.h"
#include "engine/avatar_renderer.h"
#include "engine/device.h"
#include "engine/instance.h"
#include "tests/support/test_avatar.h"
#include "test_paths.h"

using namespace embody;

namespace {

struct Context {
  engine::Instance instance;
  std::unique_ptr<engine::Device> device;
  avatar::AvatarAsset defaultAvatar, dense, cesium;
  bool haveCesium = false;
};

Context& context() {
  static Context* c = [] {
    auto* ctx = new Context();
    engine::InstanceOptions io;
    io.validation = engine::Validation::Off;
    auto inst = engine::Instance::create(io);
    if (!inst) {
      std::fprintf(stderr, "error: %s\n", inst.error().c_str());
      std::exit(1);
    }
    ctx->instance = std::move(inst).value();
    const char* sel = std::getenv("EMBODY_BENCH_DEVICE");
    auto dev = engine::Device::create(ctx->instance, sel ? sel : "auto");
    if (!dev) {
      std::fprintf(stderr, "error: %s\n", dev.error().c_str());
      std::exit(1);
    }
    ctx->device = std::move(dev).value();
    ctx->defaultAvatar = avatar::buildDefaultAvatar();
    test::TestAvatarOptions denseOptions;
    denseOptions.rings = 200;
    denseOptions.segments = 48;
    ctx->dense = test::makeTestAvatar(denseOptions);
    if (const auto path = test::sharedAsset("CesiumMan.glb"); !path.empty()) {
      if (auto a = avatar::loadAvatarFile(path)) {
        ctx->cesium = std::move(a).value();
        ctx->haveCesium = true;
      }
    }
    return ctx;
  }();
  return *c;
}

const avatar::AvatarAsset* avatarNamed(const std::string& name) {
  Context& c = context();
  if (name == "default") return &c.defaultAvatar;
  if (name == "dense20k") return &c.dense;
  if (name == "cesiumman") return c.haveCesium ? &c.cesium : nullptr;
  return nullptr;
}

struct Setup {
  std::unique_ptr<engine::AvatarRenderer> renderer;
  avatar::SkeletonPose pose;
  std::vector<engine::Camera> cameras;
  engine::FrameOptions options;
};

bool makeSetup(benchmark::State& state, const std::string& avatarName, uint32_t w, uint32_t h, bool stereo,
               engine::StereoMode mode, Setup& s) {
  const auto* asset = avatarNamed(avatarName);
  if (!asset) {
    state.SkipWithError(("avatar '" + avatarName + "' not available").c_str());
    return false;
  }
  engine::AvatarRendererOptions o;
  o.width = w;
  o.height = h;
  o.stereo = stereo;
  o.stereoMode = mode;
  auto r = engine::AvatarRenderer::create(*context().device, *asset, o);
  if (!r) {
    state.SkipWithError(r.error().c_str());
    return false;
  }
  s.renderer = std::move(r).value();
  s.pose = avatar::SkeletonPose::rest(asset->skeleton);
  s.options.gizmos = s.renderer->trackingGizmos(s.pose);
  const engine::Camera orbit = s.renderer->orbitAround(s.pose, 0.5f, 0.15f);
  if (stereo) {
    // Headset-like per-eye fovs (asymmetric), eyes 64 mm apart at the orbit camera.
    const auto eyes = engine::stereoCameras(glm::inverse(orbit.view), 0.064f, {-0.90f, 0.75f, 0.80f, -0.85f},
                                         {-0.75f, 0.90f, 0.80f, -0.85f});
    s.cameras.assign(eyes.begin(), eyes.end());
  } else {
    s.cameras = {orbit};
  }
  return true;
}

double seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

void frame(benchmark::State& state, const std::string& avatarName, uint32_t w, uint32_t h, bool cold, bool stereo,
           engine::StereoMode mode, bool readback) {
  state.counters["triangles"] = avatarNamed(avatarName) ? double(avatarNamed(avatarName)->mesh.triangleCount()) : 0.0;
  if (cold) {
    // Each iteration: a fresh renderer (not timed), then its first frame (timed).
    for (auto _ : state) {
      Setup s;
      if (!makeSetup(state, avatarName, w, h, stereo, mode, s)) return;
      const auto t0 = std::chrono::steady_clock::now();
      auto st = s.renderer->submitFrame(s.pose, s.cameras, s.options, readback, true);
      const auto t1 = std::chrono::steady_clock::now();
      if (!st) return state.SkipWithError(st.error().c_str());
      state.SetIterationTime(seconds(t0, t1));
    }
    return;
  }
  Setup s;
  if (!makeSetup(state, avatarName, w, h, stereo, mode, s)) return;
  for (int i = 0; i < 3; ++i)  // pipelines compiled, buffers sized
    if (!s.renderer->submitFrame(s.pose, s.cameras, s.options, readback, true)) return state.SkipWithError("frame failed");
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    auto st = s.renderer->submitFrame(s.pose, s.cameras, s.options, readback, true);
    const auto t1 = std::chrono::steady_clock::now();
    if (!st) return state.SkipWithError(st.error().c_str());
    state.SetIterationTime(seconds(t0, t1));
  }
}

void registerAll() {
  const std::string device = context().device->driverString();
  benchmark::AddCustomContext("device", device);
  std::fprintf(stderr, "device: %s\n", device.c_str());  // stderr: stdout may be JSON
  struct Size {
    uint32_t w, h;
  };
  const char* avatars[] = {"default", "dense20k", "cesiumman"};
  const Size sizes[] = {{1280, 720}, {256, 256}};
  for (const char* a : avatars)
    for (const Size& sz : sizes)
      for (bool cold : {true, false}) {
        const std::string name = std::string("BM_Frame/") + a + "/" + std::to_string(sz.w) + "x" + std::to_string(sz.h) +
                                 (cold ? "/cold" : "/warm");
        auto* b = benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& st) {
          frame(st, a, sz.w, sz.h, cold, false, engine::kDefaultStereoMode, false);
        });
        b->UseManualTime()->Unit(benchmark::kMillisecond);
        if (cold) b->Iterations(3);
        else b->MinTime(1.0)->Repetitions(3)->ReportAggregatesOnly(true);
      }
  for (const char* a : {"default", "cesiumman"})
    for (auto mode : {engine::StereoMode::Multiview, engine::StereoMode::TwoPass})
      for (bool cold : {true, false}) {
        const std::string name = std::string("BM_Stereo/") + a + "/2x1440x1584/" +
                                 (mode == engine::StereoMode::Multiview ? "multiview" : "twopass") +
                                 (cold ? "/cold" : "/warm");
        auto* b = benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& st) {
          frame(st, a, 1440, 1584, cold, true, mode, false);
        });
        b->UseManualTime()->Unit(benchmark::kMillisecond);
        if (cold) b->Iterations(2);
        else b->MinTime(1.0)->Repetitions(3)->ReportAggregatesOnly(true);
      }
  auto* rb = benchmark::RegisterBenchmark("BM_Readback/cesiumman/1280x720", [](benchmark::State& st) {
    frame(st, "cesiumman", 1280, 720, false, false, engine::kDefaultStereoMode, true);
  });
  rb->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(1.0);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  registerAll();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
