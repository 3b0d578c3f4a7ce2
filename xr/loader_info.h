#pragma once
// What the OpenXR side of this machine looks like, without starting a session: the loader this
// binary links (the 1.0.20 loader has no version call, so: header version + library file) and
// the active runtime the loader would pick.
#include <string>
#include <vector>

namespace embody::xr {

struct OpenXRLoaderInfo {
  std::string headerVersion;          // XR_CURRENT_API_VERSION of the headers we built against
  std::string libraryPath;            // resolved file of libopenxr_loader in this process
  std::string runtimeManifest;        // manifest the loader would use, "" when none
  std::string runtimeManifestSource;  // "XR_RUNTIME_JSON", a config path, or ""
  std::string runtimeName;            // from xrGetInstanceProperties, "none" when no runtime
  std::string runtimeVersion;
  std::string runtimeError;                    // why creating an instance failed, if it did
  std::vector<std::string> apiLayers;          // API layers the loader can enable (name + version)
  std::vector<std::string> runtimeExtensions;  // instance extensions the runtime offers
  std::string systemName;                      // the HMD (xrGetSystem), "" when none is connected
  bool vulkanEnable2 = false;  // the runtime offers XR_KHR_vulkan_enable2 (what embody xr needs)
};

// Probes the loader; with a runtime manifest present it creates (and destroys) an XrInstance to
// read the runtime's name.
OpenXRLoaderInfo probeOpenXR();

}  // namespace embody::xr
