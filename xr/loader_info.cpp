#include "xr/loader_info.h"

#include "xr/xr_common.h"

#include <dlfcn.h>
#include <openxr/openxr.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <vector>

namespace embody::xr {

namespace {

std::string versionString(XrVersion v) {
  std::ostringstream o;
  o << XR_VERSION_MAJOR(v) << "." << XR_VERSION_MINOR(v) << "." << XR_VERSION_PATCH(v);
  return o.str();
}

// The loader's search order for the active runtime on Linux (OpenXR loader design, 1.0).
void findActiveRuntime(OpenXRLoaderInfo& info) {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("XR_RUNTIME_JSON"); env && *env) {
    info.runtimeManifest = env;
    info.runtimeManifestSource = "XR_RUNTIME_JSON";
    return;
  }
  std::vector<fs::path> candidates;
  if (const char* x = std::getenv("XDG_CONFIG_HOME"); x && *x)
    candidates.emplace_back(fs::path(x) / "openxr/1/active_runtime.json");
  else if (const char* h = std::getenv("HOME"); h && *h)
    candidates.emplace_back(fs::path(h) / ".config/openxr/1/active_runtime.json");
  std::string dirs = "/etc/xdg";
  if (const char* d = std::getenv("XDG_CONFIG_DIRS"); d && *d) dirs = d;
  std::stringstream ss(dirs);
  for (std::string dir; std::getline(ss, dir, ':');)
    if (!dir.empty()) candidates.emplace_back(fs::path(dir) / "openxr/1/active_runtime.json");
  candidates.emplace_back("/etc/openxr/1/active_runtime.json");
  for (const auto& c : candidates) {
    std::error_code ec;
    if (fs::exists(c, ec)) {
      info.runtimeManifest = c.string();
      info.runtimeManifestSource = c.string();
      return;
    }
  }
}

}  // namespace

OpenXRLoaderInfo probeOpenXR() {
  OpenXRLoaderInfo info;
  info.headerVersion = versionString(XR_CURRENT_API_VERSION);
  Dl_info dl{};
  if (dladdr(reinterpret_cast<void*>(&xrGetInstanceProcAddr), &dl) && dl.dli_fname) {
    std::error_code ec;
    auto real = std::filesystem::canonical(dl.dli_fname, ec);
    info.libraryPath = ec ? dl.dli_fname : real.string();
  }
  findActiveRuntime(info);
  info.runtimeName = "none";
  uint32_t n = 0;
  if (XR_SUCCEEDED(xrEnumerateApiLayerProperties(0, &n, nullptr)) && n > 0) {
    std::vector<XrApiLayerProperties> layers(n, {XR_TYPE_API_LAYER_PROPERTIES});
    if (XR_SUCCEEDED(xrEnumerateApiLayerProperties(n, &n, layers.data())))
      for (const auto& l : layers)
        info.apiLayers.push_back(std::string(l.layerName) + " " + versionString(l.specVersion));
  }
  if (info.runtimeManifest.empty()) return info;
  if (XR_SUCCEEDED(xrEnumerateInstanceExtensionProperties(nullptr, 0, &n, nullptr)) && n > 0) {
    std::vector<XrExtensionProperties> exts(n, {XR_TYPE_EXTENSION_PROPERTIES});
    if (XR_SUCCEEDED(xrEnumerateInstanceExtensionProperties(nullptr, n, &n, exts.data())))
      for (const auto& e : exts) {
        info.runtimeExtensions.push_back(e.extensionName);
        info.vulkanEnable2 = info.vulkanEnable2 || std::strcmp(e.extensionName, "XR_KHR_vulkan_enable2") == 0;
      }
  }

  XrInstanceCreateInfo ci{XR_TYPE_INSTANCE_CREATE_INFO};
  std::strncpy(ci.applicationInfo.applicationName, "embody-doctor", XR_MAX_APPLICATION_NAME_SIZE - 1);
  std::strncpy(ci.applicationInfo.engineName, "embody", XR_MAX_ENGINE_NAME_SIZE - 1);
  ci.applicationInfo.apiVersion = XR_CURRENT_API_VERSION;
  XrInstance instance = XR_NULL_HANDLE;
  XrResult r = xrCreateInstance(&ci, &instance);
  if (XR_FAILED(r)) {
    info.runtimeError = "xrCreateInstance failed (" + resultString(XR_NULL_HANDLE, r) + ")";
    info.runtimeName = "none (manifest " + info.runtimeManifest + " did not load)";
    return info;
  }
  XrInstanceProperties props{XR_TYPE_INSTANCE_PROPERTIES};
  if (XR_SUCCEEDED(xrGetInstanceProperties(instance, &props))) {
    info.runtimeName = props.runtimeName;
    info.runtimeVersion = versionString(props.runtimeVersion);
  }
  XrSystemGetInfo gi{XR_TYPE_SYSTEM_GET_INFO};
  gi.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  XrSystemId system = XR_NULL_SYSTEM_ID;
  if (XR_SUCCEEDED(xrGetSystem(instance, &gi, &system))) {
    XrSystemProperties sp{XR_TYPE_SYSTEM_PROPERTIES};
    if (XR_SUCCEEDED(xrGetSystemProperties(instance, system, &sp))) info.systemName = sp.systemName;
  }
  xrDestroyInstance(instance);
  return info;
}

}  // namespace embody::xr
