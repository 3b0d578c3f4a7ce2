// embody doctor: what this machine offers Embody (Vulkan devices, validation, OpenXR, display).
#include <GLFW/glfw3.h>

#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "app/args.h"
#include "engine/instance.h"
#include "xr/loader_info.h"

namespace {

struct DisplayInfo {
  std::string display;  // $DISPLAY or ""
  std::string wayland;  // $WAYLAND_DISPLAY or ""
  bool windowSystemUsable = false;
};

DisplayInfo probeDisplay() {
  DisplayInfo d;
  if (const char* e = std::getenv("DISPLAY")) d.display = e;
  if (const char* e = std::getenv("WAYLAND_DISPLAY")) d.wayland = e;
  if (!d.display.empty() || !d.wayland.empty()) {
    glfwSetErrorCallback(nullptr);
    if (glfwInit() == GLFW_TRUE) {
      d.windowSystemUsable = glfwVulkanSupported() == GLFW_TRUE;
      glfwTerminate();
    }
  }
  return d;
}

int runDoctor(embody::app::Argv argv) {
  using namespace embody;
  app::Args args("embody doctor", "Lists what this machine offers Embody: Vulkan devices, the validation "
                                  "layer, the OpenXR loader and runtime, and the display.");
  args.flag("json", "print one JSON object instead of text");
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);

  nlohmann::json j;
  const bool layer = engine::Instance::validationLayerAvailable();
  engine::InstanceOptions opts;
  opts.validation = layer ? engine::Validation::Required : engine::Validation::Off;
  auto inst = engine::Instance::create(opts);
  j["vulkan"]["loader_api_version"] = std::to_string(VK_API_VERSION_MAJOR(engine::Instance::loaderApiVersion())) +
                                      "." + std::to_string(VK_API_VERSION_MINOR(engine::Instance::loaderApiVersion())) +
                                      "." + std::to_string(VK_API_VERSION_PATCH(engine::Instance::loaderApiVersion()));
  j["vulkan"]["validation_layer"] = layer && inst.ok() && inst->validationEnabled();
  j["vulkan"]["devices"] = nlohmann::json::array();
  if (inst.ok()) {
    for (const auto& d : inst->physicalDevices())
      j["vulkan"]["devices"].push_back({{"name", d.name}, {"type", d.typeName()}, {"driver", d.driverName},
                                        {"driver_info", d.driverInfo}, {"api_version", d.apiVersionString()}});
  } else {
    j["vulkan"]["error"] = inst.error();
  }
  const auto xr = xr::probeOpenXR();
  j["openxr"] = {{"header_version", xr.headerVersion}, {"loader_library", xr.libraryPath},
                 {"runtime", xr.runtimeName}, {"runtime_manifest", xr.runtimeManifest}};
  if (!xr.runtimeVersion.empty()) j["openxr"]["runtime_version"] = xr.runtimeVersion;
  if (!xr.runtimeError.empty()) j["openxr"]["runtime_error"] = xr.runtimeError;
  j["openxr"]["api_layers"] = xr.apiLayers;
  j["openxr"]["runtime_extensions"] = xr.runtimeExtensions;
  j["openxr"]["system"] = xr.systemName;
  j["openxr"]["vulkan_enable2"] = xr.vulkanEnable2;
  const auto disp = probeDisplay();
  j["display"] = {{"DISPLAY", disp.display}, {"WAYLAND_DISPLAY", disp.wayland},
                  {"window_system_usable", disp.windowSystemUsable}};

  if (args.has("json")) {
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  std::printf("Vulkan\n  loader API version: %s\n", j["vulkan"]["loader_api_version"].get<std::string>().c_str());
  std::printf("  validation layer:   %s\n", j["vulkan"]["validation_layer"].get<bool>()
                                                ? "VK_LAYER_KHRONOS_validation loads"
                                                : "not available (install vulkan-validationlayers)");
  if (j["vulkan"].contains("error")) std::printf("  error: %s\n", j["vulkan"]["error"].get<std::string>().c_str());
  if (j["vulkan"]["devices"].empty()) std::printf("  devices: none (install mesa-vulkan-drivers for lavapipe)\n");
  for (const auto& d : j["vulkan"]["devices"])
    std::printf("  device: %s (%s), driver %s %s, Vulkan %s\n", d["name"].get<std::string>().c_str(),
                d["type"].get<std::string>().c_str(), d["driver"].get<std::string>().c_str(),
                d["driver_info"].get<std::string>().c_str(), d["api_version"].get<std::string>().c_str());
  std::printf("OpenXR\n  loader: headers %s, library %s\n", xr.headerVersion.c_str(),
              xr.libraryPath.empty() ? "(not found)" : xr.libraryPath.c_str());
  std::printf("  active runtime: %s", xr.runtimeName.c_str());
  if (!xr.runtimeVersion.empty()) std::printf(" %s", xr.runtimeVersion.c_str());
  if (!xr.runtimeManifest.empty()) std::printf(" (manifest %s)", xr.runtimeManifest.c_str());
  std::printf("\n");
  if (!xr.runtimeError.empty()) std::printf("  runtime error: %s\n", xr.runtimeError.c_str());
  if (!xr.runtimeManifest.empty() && xr.runtimeError.empty()) {
    std::printf("  system: %s\n", xr.systemName.empty() ? "(no headset connected)" : xr.systemName.c_str());
    std::printf("  XR_KHR_vulkan_enable2: %s\n", xr.vulkanEnable2 ? "offered (embody xr can run)" : "missing (embody xr needs it)");
    std::printf("  runtime extensions: %zu\n", xr.runtimeExtensions.size());
  }
  std::printf("  API layers: ");
  if (xr.apiLayers.empty()) std::printf("none\n");
  for (size_t i = 0; i < xr.apiLayers.size(); ++i)
    std::printf("%s%s", xr.apiLayers[i].c_str(), i + 1 < xr.apiLayers.size() ? ", " : "\n");
  std::printf("Display\n  DISPLAY=%s WAYLAND_DISPLAY=%s: %s\n", disp.display.empty() ? "(unset)" : disp.display.c_str(),
              disp.wayland.empty() ? "(unset)" : disp.wayland.c_str(),
              disp.windowSystemUsable ? "a mirror window can open"
                                      : "no usable display; the mirror window needs X (run under Xvfb)");
  return 0;
}

}  // namespace

EMBODY_COMMAND("doctor", "list Vulkan devices, validation layer, OpenXR loader/runtime, display", runDoctor);
