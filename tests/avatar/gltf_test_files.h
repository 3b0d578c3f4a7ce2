#pragma once
// Small glTF/GLB files built in memory for the loader tests (hostile variants included).
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace embody::test {

inline void appendU32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

// A GLB container around JSON text and a binary chunk (both padded to 4 bytes).
inline std::vector<uint8_t> makeGlb(std::string json, std::vector<uint8_t> bin) {
  while (json.size() % 4) json.push_back(' ');
  while (bin.size() % 4) bin.push_back(0);
  std::vector<uint8_t> out;
  const uint32_t total =
      12 + 8 + static_cast<uint32_t>(json.size()) + (bin.empty() ? 0 : 8 + static_cast<uint32_t>(bin.size()));
  out.reserve(total);
  for (char c : std::string("glTF")) out.push_back(static_cast<uint8_t>(c));
  appendU32(out, 2);
  appendU32(out, total);
  appendU32(out, static_cast<uint32_t>(json.size()));
  appendU32(out, 0x4E4F534Au);
  for (char c : json) out.push_back(static_cast<uint8_t>(c));
  if (!bin.empty()) {
    appendU32(out, static_cast<uint32_t>(bin.size()));
    appendU32(out, 0x004E4942u);
    for (uint8_t b : bin) out.push_back(b);
  }
  return out;
}

// The same around a JSON document.
inline std::vector<uint8_t> makeGlb(const nlohmann::json& doc, std::vector<uint8_t> bin) {
  return makeGlb(doc.dump(), std::move(bin));
}

template <class T>
void appendRaw(std::vector<uint8_t>& out, const std::vector<T>& values) {
  const size_t at = out.size();
  out.resize(at + values.size() * sizeof(T));
  std::memcpy(out.data() + at, values.data(), values.size() * sizeof(T));
  while (out.size() % 4) out.push_back(0);
}

// One triangle on one node: positions (accessor 0), ushort indices (accessor 1). No normals, so
// the loader computes them. Tests mutate the JSON to make it hostile.
struct TriangleFile {
  nlohmann::json doc;
  std::vector<uint8_t> bin;
  TriangleFile() {
    appendRaw(bin, std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0});  // 36 bytes
    appendRaw(bin, std::vector<uint16_t>{0, 1, 2});                 // 6 bytes + 2 pad
    doc = {
        {"asset", {{"version", "2.0"}}},
        {"scene", 0},
        {"scenes", {{{"nodes", {0}}}}},
        {"nodes", {{{"name", "root"}, {"mesh", 0}, {"translation", {0, 1, 0}}}}},
        {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
        {"buffers", {{{"byteLength", bin.size()}}}},
        {"bufferViews",
         {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
          {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 6}}}},
        {"accessors",
         {{{"bufferView", 0},
           {"componentType", 5126},
           {"count", 3},
           {"type", "VEC3"},
           {"min", {0, 0, 0}},
           {"max", {1, 1, 0}}},
          {{"bufferView", 1}, {"componentType", 5123}, {"count", 3}, {"type", "SCALAR"}}}},
    };
  }
  std::vector<uint8_t> glb() const { return makeGlb(doc, bin); }
};

}  // namespace embody::test
