// glTF/GLB/VRM -> AvatarAsset. tinygltf parses the JSON and resolves buffers and images; every
// index and byte range it hands back is checked here before use, because tinygltf 2.7 does not
// validate accessors, node children or texture sources.
#include "avatar/gltf/gltf_loader.h"

#include <stb_image.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <limits>
#include <nlohmann/json.hpp>
#include <string_view>

#include "avatar/gltf/component_type.h"
#include "avatar/gltf/mtoon_json.h"

namespace embody::avatar {
namespace {

Error loadError(const std::string& what) {
  return Error{what};
}

// ---------------------------------------------------------------------------------------------
// Images: decoded by us (stb) so that dimensions are checked before any pixel is allocated.
struct ImageLoaderContext {
  int maxDimension = 8192;
  std::vector<std::string>* warnings = nullptr;
};

bool decodeImage(tinygltf::Image* image, const int imageIndex, std::string* /*err*/, std::string* /*warn*/,
                 int /*reqWidth*/, int /*reqHeight*/, const unsigned char* bytes, int size, void* user) {
  auto* ctx = static_cast<ImageLoaderContext*>(user);
  auto warn = [&](const std::string& w) {
    if (ctx->warnings) ctx->warnings->push_back("image " + std::to_string(imageIndex) + ": " + w);
  };
  // An image we cannot decode leaves the material untextured rather than failing the avatar.
  image->image.clear();
  image->width = image->height = 0;
  image->component = 4;
  image->bits = 8;
  image->pixel_type = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
  int w = 0, h = 0, comp = 0;
  if (!bytes || size <= 0 || !stbi_info_from_memory(bytes, size, &w, &h, &comp)) {
    warn("cannot be decoded (" + std::string(stbi_failure_reason() ? stbi_failure_reason() : "no data") +
         "); drawn untextured");
    return true;
  }
  if (w <= 0 || h <= 0 || w > ctx->maxDimension || h > ctx->maxDimension) {
    warn(std::to_string(w) + "x" + std::to_string(h) + " exceeds the " + std::to_string(ctx->maxDimension) +
         " pixel limit; drawn untextured");
    return true;
  }
  stbi_uc* pixels = stbi_load_from_memory(bytes, size, &w, &h, &comp, 4);
  if (!pixels) {
    warn("cannot be decoded; drawn untextured");
    return true;
  }
  image->width = w;
  image->height = h;
  image->image.assign(pixels, pixels + static_cast<size_t>(w) * static_cast<size_t>(h) * 4);
  stbi_image_free(pixels);
  return true;
}

// ---------------------------------------------------------------------------------------------
// External files (buffers and images next to a .gltf): only regular files within the size limit,
// so a URI naming a FIFO, a device or a huge file cannot hang the loader or exhaust memory.
bool readExternalFile(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  const uint64_t maxBytes = *static_cast<const uint64_t*>(user);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    if (err) *err += "'" + path + "' is not a regular file\n";
    return false;
  }
  const auto size = std::filesystem::file_size(path, ec);
  if (ec || size > maxBytes) {
    if (err) *err += "'" + path + "' is larger than " + std::to_string(maxBytes) + " bytes\n";
    return false;
  }
  return tinygltf::ReadWholeFile(out, err, path, nullptr);
}

// ---------------------------------------------------------------------------------------------
// GLB container: checked by hand so that the JSON chunk can be kept and a truncated file gives a
// precise reason before tinygltf sees it.
struct GlbChunks {
  std::string json;
  bool isGlb = false;
};

uint32_t readU32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 | static_cast<uint32_t>(p[2]) << 16 |
         static_cast<uint32_t>(p[3]) << 24;
}

Result<GlbChunks> splitContainer(const std::vector<uint8_t>& bytes) {
  GlbChunks out;
  if (bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0) {
    out.isGlb = true;
    if (bytes.size() < 20)
      return loadError("truncated GLB: " + std::to_string(bytes.size()) + " bytes, header needs 20");
    const uint32_t version = readU32(&bytes[4]);
    const uint32_t total = readU32(&bytes[8]);
    if (version != 2) return loadError("GLB version " + std::to_string(version) + " is not supported (need 2)");
    if (total > bytes.size())
      return loadError("truncated GLB: header says " + std::to_string(total) + " bytes, file has " +
                  std::to_string(bytes.size()));
    if (total < 20) return loadError("GLB header length " + std::to_string(total) + " is smaller than the header");
    const uint32_t jsonLength = readU32(&bytes[12]);
    const uint32_t jsonType = readU32(&bytes[16]);
    if (jsonType != 0x4E4F534Au) return loadError("GLB first chunk is not JSON");
    if (static_cast<uint64_t>(jsonLength) + 20 > total)
      return loadError("truncated GLB: JSON chunk of " + std::to_string(jsonLength) + " bytes runs past the end");
    uint64_t at = 20 + static_cast<uint64_t>(jsonLength);
    at = (at + 3) & ~uint64_t{3};
    if (at + 8 <= total) {
      const uint32_t binLength = readU32(&bytes[at]);
      if (at + 8 + binLength > total)
        return loadError("truncated GLB: BIN chunk of " + std::to_string(binLength) + " bytes runs past the end");
    }
    out.json.assign(reinterpret_cast<const char*>(&bytes[20]), jsonLength);
    while (!out.json.empty() && (out.json.back() == ' ' || out.json.back() == '\0')) out.json.pop_back();
  } else {
    // Text glTF is a JSON object: anything else (random bytes, an image, a zip) gets one readable
    // line instead of the JSON parser's message about some byte.
    size_t first = 0;
    while (first < bytes.size() && std::isspace(bytes[first])) ++first;
    if (first == bytes.size() || bytes[first] != '{')
      return loadError("not a glTF file: neither a GLB container (no 'glTF' magic) nor glTF JSON text");
    out.json.assign(bytes.begin(), bytes.end());
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// The JSON before tinygltf sees it. tinygltf converts the JSON tree to its own values recursively,
// one stack frame per level, so arrays nested 20 000 deep (40 KB of "[[[[") overflow the stack:
// the nesting is counted first, a scan of the brackets outside strings.
Status checkJsonNesting(std::string_view json, int maxDepth) {
  int depth = 0;
  bool inString = false;
  for (size_t i = 0; i < json.size(); ++i) {
    const char c = json[i];
    if (inString) {
      if (c == '\\')
        ++i;  // the escaped character cannot end the string
      else if (c == '"')
        inString = false;
    } else if (c == '"') {
      inString = true;
    } else if (c == '[' || c == '{') {
      if (++depth > maxDepth)
        return loadError("JSON nested deeper than " + std::to_string(maxDepth) +
                         " levels (arrays and objects, at byte " + std::to_string(i) + "); refused");
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return {};
}

// The extensions this loader reads (docs/avatars.md): a file that lists any other one in
// extensionsRequired cannot be drawn as its author meant (Draco or meshopt compressed geometry,
// quantized attributes ...), so it is refused naming the extension instead of failing later on
// an accessor or drawing something else.
constexpr std::string_view kSupportedExtensions[] = {
    "KHR_materials_emissive_strength", "KHR_materials_unlit", "KHR_texture_transform",
    "VRM",                             "VRMC_vrm",            "VRMC_materials_mtoon",
    "VRMC_springBone"};

Status checkRequiredExtensions(std::string_view text) {
  // Only the top-level "extensionsRequired" is kept; everything else is parsed and dropped.
  using Json = nlohmann::json;
  const Json doc = Json::parse(
      text.begin(), text.end(),
      [](int depth, Json::parse_event_t event, Json& parsed) {
        return depth != 1 || event != Json::parse_event_t::key || parsed == "extensionsRequired";
      },
      false);
  if (!doc.is_object()) return {};  // not JSON: tinygltf's parse error says where
  const auto it = doc.find("extensionsRequired");
  if (it == doc.end() || !it->is_array()) return {};
  auto supported = [](const std::string& n) {
    return std::find(std::begin(kSupportedExtensions), std::end(kSupportedExtensions), n) !=
           std::end(kSupportedExtensions);
  };
  std::vector<std::string> unsupported;
  for (const auto& name : *it)
    if (name.is_string() && !supported(name.get<std::string>()) &&
        std::find(unsupported.begin(), unsupported.end(), name.get<std::string>()) == unsupported.end())
      unsupported.push_back(name.get<std::string>());
  if (unsupported.empty()) return {};
  auto joined = [](const auto& names) {
    std::string out;
    for (const auto& n : names) out += (out.empty() ? "" : ", ") + std::string(n);
    return out;
  };
  return loadError("the file requires " + joined(unsupported) +
                   " (extensionsRequired), which embody does not support; it reads " +
                   joined(kSupportedExtensions));
}

// ---------------------------------------------------------------------------------------------
// Accessors: one bounds-checked reader for every attribute, with normalisation and sparse data.
int componentSize(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return 4;
    default:
      return 0;
  }
}

int componentCount(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR:
      return 1;
    case TINYGLTF_TYPE_VEC2:
      return 2;
    case TINYGLTF_TYPE_VEC3:
      return 3;
    case TINYGLTF_TYPE_VEC4:
      return 4;
    case TINYGLTF_TYPE_MAT4:
      return 16;
    default:
      return 0;
  }
}

double readComponent(const uint8_t* p, int type, bool normalized) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      int8_t v;
      std::memcpy(&v, p, 1);
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return normalized ? p[0] / 255.0 : p[0];
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      uint32_t v;
      std::memcpy(&v, p, 4);
      return v;
    }
    default: {
      float v;
      std::memcpy(&v, p, 4);
      return v;
    }
  }
}

constexpr size_t kMaxMorphTargets = 1024;  // per primitive
using gltf::kFloat, gltf::kUByte, gltf::kUShort, gltf::kUInt;
static_assert(kFloat == TINYGLTF_COMPONENT_TYPE_FLOAT && kUByte == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
              kUShort == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT && kUInt == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);

class AccessorReader {
 public:
  AccessorReader(const tinygltf::Model& m, const GltfLimits& l) : model_(m), limits_(l) {}

  // Reads accessor `index` as `count x components` doubles after checking type, component type
  // and every byte range. `allowed` lists the acceptable component types.
  Result<std::vector<double>> read(int index, int components, std::initializer_list<int> allowed,
                                   const std::string& what) const {
    const std::string where = what + " (accessor " + std::to_string(index) + ")";
    if (index < 0 || static_cast<size_t>(index) >= model_.accessors.size())
      return loadError(what + ": accessor index " + std::to_string(index) + " out of range");
    const tinygltf::Accessor& a = model_.accessors[index];
    if (componentCount(a.type) != components)
      return loadError(where + ": expected " + std::to_string(components) + " components per element");
    if (std::find(allowed.begin(), allowed.end(), a.componentType) == allowed.end())
      return loadError(where + ": component type " + std::to_string(a.componentType) + " not allowed here");
    if (a.count > limits_.maxAccessorCount)
      return loadError(where + ": count " + std::to_string(a.count) + " exceeds the limit of " +
                  std::to_string(limits_.maxAccessorCount));
    const size_t elemSize = static_cast<size_t>(componentSize(a.componentType)) * components;
    size_t stride = elemSize;
    auto base = denseData(a, elemSize, where, stride);
    if (!base.ok()) return Error{base.error()};
    std::vector<double> out(a.count * components, 0.0);
    if (base.value()) {
      const int cs = componentSize(a.componentType);
      for (size_t i = 0; i < a.count; ++i)
        for (int c = 0; c < components; ++c)
          out[i * components + c] =
              readComponent(base.value() + i * stride + c * cs, a.componentType, a.normalized);
    }
    if (a.sparse.isSparse)
      if (auto s = applySparse(a, components, elemSize, where, out); !s.ok()) return Error{s.error()};
    for (double v : out)
      if (!std::isfinite(v)) return loadError(where + ": contains a non-finite value");
    return out;
  }

  size_t count(int index) const { return model_.accessors[index].count; }

 private:
  // The accessor's first element in its bufferView (null without one, then it is all zeros) and its
  // stride. Every declared count is checked against the bytes the file has before anything is
  // allocated.
  Result<const uint8_t*> denseData(const tinygltf::Accessor& a, size_t elemSize, const std::string& where,
                                   size_t& stride) const {
    if (a.bufferView >= 0) {
      auto view = bufferView(a.bufferView, where);
      if (!view.ok()) return Error{view.error()};
      const tinygltf::BufferView& bv = model_.bufferViews[a.bufferView];
      stride = bv.byteStride ? bv.byteStride : elemSize;
      if (stride < elemSize)
        return loadError(where + ": byteStride " + std::to_string(stride) + " < element size");
      // Each term is bounded first, so the sum below cannot wrap around.
      if (a.byteOffset > bv.byteLength || (a.count > 1 && stride > bv.byteLength))
        return loadError(where + ": byteOffset or byteStride past the end of its " + std::to_string(bv.byteLength) +
                    "-byte bufferView");
      if (a.count > 0) {
        const uint64_t need = static_cast<uint64_t>(a.byteOffset) + (a.count - 1) * stride + elemSize;
        if (need > bv.byteLength)
          return loadError(where + ": reads " + std::to_string(need) + " bytes of a " +
                      std::to_string(bv.byteLength) + "-byte bufferView");
      }
      return view.value() + a.byteOffset;
    }
    if (a.count > std::max<uint64_t>(4096, totalBufferBytes())) {
      // All zeros (plus sparse entries): never longer than the file's binary data could back.
      return loadError(where + ": " + std::to_string(a.count) + " elements without a bufferView exceed the file's " +
                  std::to_string(totalBufferBytes()) + " bytes of buffers");
    }
    return static_cast<const uint8_t*>(nullptr);
  }

  // Overwrites the sparse entries of `out` after checking their indices and byte ranges.
  Status applySparse(const tinygltf::Accessor& a, int components, size_t elemSize, const std::string& where,
                     std::vector<double>& out) const {
    const auto& sp = a.sparse;
    if (sp.count < 0 || static_cast<size_t>(sp.count) > a.count)
      return loadError(where + ": sparse count " + std::to_string(sp.count) + " out of range");
    const int ics = componentSize(sp.indices.componentType);
    if (ics == 0 || sp.indices.componentType == TINYGLTF_COMPONENT_TYPE_BYTE ||
        sp.indices.componentType == TINYGLTF_COMPONENT_TYPE_SHORT ||
        sp.indices.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT)
      return loadError(where + ": bad sparse index component type");
    auto iv = bufferView(sp.indices.bufferView, where + " sparse indices");
    if (!iv.ok()) return Error{iv.error()};
    auto vv = bufferView(sp.values.bufferView, where + " sparse values");
    if (!vv.ok()) return Error{vv.error()};
    if (sp.indices.byteOffset < 0 || sp.values.byteOffset < 0)
      return loadError(where + ": negative sparse offset");
    const uint64_t ineed =
        static_cast<uint64_t>(sp.indices.byteOffset) + static_cast<uint64_t>(sp.count) * ics;
    const uint64_t vneed =
        static_cast<uint64_t>(sp.values.byteOffset) + static_cast<uint64_t>(sp.count) * elemSize;
    if (ineed > model_.bufferViews[sp.indices.bufferView].byteLength ||
        vneed > model_.bufferViews[sp.values.bufferView].byteLength)
      return loadError(where + ": sparse data runs past its bufferView");
    const int cs = componentSize(a.componentType);
    for (int s = 0; s < sp.count; ++s) {
      const auto target = static_cast<uint64_t>(
          readComponent(iv.value() + sp.indices.byteOffset + static_cast<size_t>(s) * ics,
                        sp.indices.componentType, false));
      if (target >= a.count)
        return loadError(where + ": sparse index " + std::to_string(target) + " out of range");
      for (int c = 0; c < components; ++c)
        out[target * components + c] = readComponent(
            vv.value() + sp.values.byteOffset + s * elemSize + c * cs, a.componentType, a.normalized);
    }
    return {};
  }

  uint64_t totalBufferBytes() const {
    uint64_t n = 0;
    for (const auto& b : model_.buffers) n += b.data.size();
    return n;
  }

  Result<const uint8_t*> bufferView(int index, const std::string& where) const {
    if (index < 0 || static_cast<size_t>(index) >= model_.bufferViews.size())
      return loadError(where + ": bufferView " + std::to_string(index) + " out of range");
    const tinygltf::BufferView& bv = model_.bufferViews[index];
    if (bv.buffer < 0 || static_cast<size_t>(bv.buffer) >= model_.buffers.size())
      return loadError(where + ": buffer " + std::to_string(bv.buffer) + " out of range");
    const auto& data = model_.buffers[bv.buffer].data;
    if (bv.byteOffset > data.size() || bv.byteLength > data.size() - bv.byteOffset)
      return loadError(where + ": bufferView " + std::to_string(index) + " runs past the end of its " +
                  std::to_string(data.size()) + "-byte buffer");
    return data.data() + bv.byteOffset;
  }

  const tinygltf::Model& model_;
  const GltfLimits& limits_;
};

// ---------------------------------------------------------------------------------------------
// Node hierarchy -> Skeleton (parents first), rejecting cycles and shared children.
Result<Transform> nodeTransform(const tinygltf::Node& n, int index) {
  Transform t;
  const std::string where = "node " + std::to_string(index) + " ('" + n.name + "')";
  auto finite = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  };
  if (!finite(n.matrix) || !finite(n.translation) || !finite(n.rotation) || !finite(n.scale))
    return loadError(where + ": non-finite transform");
  if (n.matrix.size() == 16) {
    glm::dmat4 m = glm::make_mat4(n.matrix.data());
    t.translation = glm::vec3(m[3]);
    glm::dvec3 s(glm::length(glm::dvec3(m[0])), glm::length(glm::dvec3(m[1])), glm::length(glm::dvec3(m[2])));
    if (s.x <= 0 || s.y <= 0 || s.z <= 0) return loadError(where + ": matrix has a zero scale axis");
    const glm::dvec3 c0{m[0]}, c1{m[1]}, c2{m[2]};
    glm::dmat3 r{c0 / s.x, c1 / s.y, c2 / s.z};
    if (glm::determinant(r) < 0) {  // a mirror: put it in the scale
      s.x = -s.x;
      r[0] = -r[0];
    }
    t.rotation = glm::normalize(glm::quat(glm::quat_cast(r)));
    t.scale = glm::vec3(s);
  } else if (!n.matrix.empty()) {
    return loadError(where + ": matrix must have 16 numbers");
  } else {
    if (n.translation.size() == 3)
      t.translation = glm::vec3(n.translation[0], n.translation[1], n.translation[2]);
    if (n.rotation.size() == 4) {
      glm::quat q(static_cast<float>(n.rotation[3]), static_cast<float>(n.rotation[0]),
                  static_cast<float>(n.rotation[1]), static_cast<float>(n.rotation[2]));
      const float len = glm::length(q);
      if (!(len > 1e-6f)) return loadError(where + ": zero rotation quaternion");
      t.rotation = q / len;
    }
    if (n.scale.size() == 3) t.scale = glm::vec3(n.scale[0], n.scale[1], n.scale[2]);
  }
  return t;
}

Status buildSkeleton(const tinygltf::Model& m, const GltfLimits& limits, AvatarAsset& asset) {
  const int n = static_cast<int>(m.nodes.size());
  if (n > limits.maxNodes)
    return Error{"the file has " + std::to_string(n) + " nodes, more than the limit of " +
                 std::to_string(limits.maxNodes)};
  std::vector<int> parent(n, -1);
  for (int i = 0; i < n; ++i)
    for (int c : m.nodes[i].children) {
      if (c < 0 || c >= n)
        return Error{"node " + std::to_string(i) + " has child " + std::to_string(c) + ", out of range"};
      if (c == i) return Error{"node " + std::to_string(i) + " is its own child (cycle in the hierarchy)"};
      if (parent[c] != -1)
        return Error{"node " + std::to_string(c) + " has two parents (" + std::to_string(parent[c]) +
                     " and " + std::to_string(i) + "); the hierarchy must be a tree"};
      parent[c] = i;
    }
  // Depth-first from every root; nodes never reached sit on a cycle (each has one parent, so a
  // component without a root is a ring).
  asset.gltfNodeToJoint.assign(n, -1);
  asset.skeleton.joints.clear();
  asset.skeleton.joints.reserve(n);
  std::vector<int> stack;
  for (int root = 0; root < n; ++root) {
    if (parent[root] != -1) continue;
    stack.push_back(root);
    while (!stack.empty()) {
      const int node = stack.back();
      stack.pop_back();
      auto t = nodeTransform(m.nodes[node], node);
      if (!t.ok()) return Error{t.error()};
      Joint j;
      j.name = m.nodes[node].name.empty() ? "node" + std::to_string(node) : m.nodes[node].name;
      j.parent = parent[node] < 0 ? -1 : asset.gltfNodeToJoint[parent[node]];
      j.rest = t.value();
      asset.gltfNodeToJoint[node] = static_cast<int>(asset.skeleton.joints.size());
      asset.skeleton.joints.push_back(std::move(j));
      const auto& ch = m.nodes[node].children;
      for (auto it = ch.rbegin(); it != ch.rend(); ++it) stack.push_back(*it);
    }
  }
  for (int i = 0; i < n; ++i)
    if (asset.gltfNodeToJoint[i] < 0)
      return Error{"node " + std::to_string(i) + " is part of a cycle in the hierarchy"};
  if (auto why = asset.skeleton.validate(); !why.empty()) return Error{why};
  return {};
}

// ---------------------------------------------------------------------------------------------
// Meshes.
std::vector<uint32_t> triangulate(int mode, const std::vector<uint32_t>& idx) {
  std::vector<uint32_t> tris;
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    tris.assign(idx.begin(), idx.begin() + static_cast<std::ptrdiff_t>(idx.size() / 3 * 3));
  } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (size_t i = 2; i < idx.size(); ++i) {
      if (i % 2 == 0)
        tris.insert(tris.end(), {idx[i - 2], idx[i - 1], idx[i]});
      else
        tris.insert(tris.end(), {idx[i - 1], idx[i - 2], idx[i]});
    }
  } else if (mode == TINYGLTF_MODE_TRIANGLE_FAN) {
    for (size_t i = 2; i < idx.size(); ++i) tris.insert(tris.end(), {idx[0], idx[i - 1], idx[i]});
  }
  return tris;
}

void computeNormals(std::vector<SkinnedVertex>& verts, size_t firstVertex,
                    const std::vector<uint32_t>& localTris) {
  std::vector<glm::vec3> acc(verts.size() - firstVertex, glm::vec3(0.0f));
  for (size_t t = 0; t + 2 < localTris.size(); t += 3) {
    const glm::vec3& a = verts[firstVertex + localTris[t]].position;
    const glm::vec3& b = verts[firstVertex + localTris[t + 1]].position;
    const glm::vec3& c = verts[firstVertex + localTris[t + 2]].position;
    const glm::vec3 n = glm::cross(b - a, c - a);  // length = 2 * area: area weighting for free
    for (int k = 0; k < 3; ++k) acc[localTris[t + k]] += n;
  }
  for (size_t i = 0; i < acc.size(); ++i) {
    const float len = glm::length(acc[i]);
    verts[firstVertex + i].normal = len > 1e-20f ? acc[i] / len : glm::vec3(0.0f, 1.0f, 0.0f);
  }
}

struct MeshBuilder {
  const tinygltf::Model& m;
  const GltfLimits& limits;
  AvatarAsset& asset;
  std::vector<std::string>& warnings;
  std::vector<bool> inverseBindSet;

  Status addSkins() {
    asset.mesh.inverseBind.assign(asset.skeleton.joints.size(), glm::mat4(1.0f));
    inverseBindSet.assign(asset.skeleton.joints.size(), false);
    AccessorReader reader(m, limits);
    std::vector<bool> isSkinJoint(asset.skeleton.joints.size(), false);
    for (size_t s = 0; s < m.skins.size(); ++s) {
      const tinygltf::Skin& skin = m.skins[s];
      const std::string where = "skin " + std::to_string(s);
      std::vector<double> ibm;
      if (skin.inverseBindMatrices >= 0) {
        auto r = reader.read(skin.inverseBindMatrices, 16, {TINYGLTF_COMPONENT_TYPE_FLOAT},
                             where + " inverseBindMatrices");
        if (!r.ok()) return Error{r.error()};
        ibm = std::move(r.value());
        if (ibm.size() / 16 < skin.joints.size())
          return Error{where + ": " + std::to_string(ibm.size() / 16) + " inverse bind matrices for " +
                       std::to_string(skin.joints.size()) + " joints"};
      }
      for (size_t k = 0; k < skin.joints.size(); ++k) {
        const int node = skin.joints[k];
        if (node < 0 || static_cast<size_t>(node) >= m.nodes.size())
          return Error{where + ": joint node " + std::to_string(node) + " out of range"};
        const int joint = asset.gltfNodeToJoint[node];
        isSkinJoint[joint] = true;
        glm::mat4 inv(1.0f);
        if (!ibm.empty())
          for (int c = 0; c < 16; ++c) glm::value_ptr(inv)[c] = static_cast<float>(ibm[k * 16 + c]);
        if (inverseBindSet[joint]) {
          float diff = 0.0f;
          for (int c = 0; c < 4; ++c)
            diff = std::max(diff, glm::length(inv[c] - asset.mesh.inverseBind[joint][c]));
          if (diff > 1e-4f)
            warnings.push_back(
                where + ": joint '" + asset.skeleton.joints[joint].name +
                "' has a different inverse bind matrix than in an earlier skin; the first is used");
          continue;
        }
        asset.mesh.inverseBind[joint] = inv;
        inverseBindSet[joint] = true;
      }
    }
    asset.skinJointCount = static_cast<int>(std::count(isSkinJoint.begin(), isSkinJoint.end(), true));
    return {};
  }

  // A primitive's vertex attributes as read from the file (empty when absent), each already checked
  // against the POSITION count.
  struct VertexAttributes {
    std::vector<double> position, normal, uv0, uv1, joints[2], weights[2];
    const tinygltf::Skin* skin = nullptr;  // null: drawn rigidly on its node
    size_t count() const { return position.size() / 3; }
  };

  static int attributeAccessor(const tinygltf::Primitive& p, const char* name) {
    auto it = p.attributes.find(name);
    return it == p.attributes.end() ? -1 : it->second;
  }

  // An optional per-vertex attribute: empty when absent, an error when its count is not `vcount`.
  Result<std::vector<double>> optionalAttribute(const tinygltf::Primitive& p, const char* name, int comps,
                                                std::initializer_list<int> types, size_t vcount,
                                                const std::string& where) const {
    const int acc = attributeAccessor(p, name);
    if (acc < 0) return std::vector<double>{};
    auto r = AccessorReader(m, limits).read(acc, comps, types, where + " " + name);
    if (!r.ok()) return r;
    if (r->size() / comps != vcount)
      return loadError(where + " " + name + ": " + std::to_string(r->size() / comps) + " elements for " +
                  std::to_string(vcount) + " vertices");
    return r;
  }

  Status readVertexAttributes(int node, const tinygltf::Primitive& p, int posAcc, const std::string& where,
                              VertexAttributes& va) const {
    auto pos = AccessorReader(m, limits).read(posAcc, 3, {kFloat}, where + " POSITION");
    if (!pos.ok()) return Error{pos.error()};
    va.position = std::move(pos.value());
    const size_t vcount = va.count();
    if (asset.mesh.vertices.size() + vcount > limits.maxTotalVertices)
      return Error{where + ": more than " + std::to_string(limits.maxTotalVertices) + " vertices in total"};
    auto normal = optionalAttribute(p, "NORMAL", 3, {kFloat}, vcount, where);
    if (!normal.ok()) return Error{normal.error()};
    auto uv0 = optionalAttribute(p, "TEXCOORD_0", 2, {kFloat, kUByte, kUShort}, vcount, where);
    if (!uv0.ok()) return Error{uv0.error()};
    auto uv1 = optionalAttribute(p, "TEXCOORD_1", 2, {kFloat, kUByte, kUShort}, vcount, where);
    if (!uv1.ok()) return Error{uv1.error()};
    va.normal = std::move(normal.value());
    va.uv0 = std::move(uv0.value());
    va.uv1 = std::move(uv1.value());
    return readSkinAttributes(node, p, where, va);
  }

  // JOINTS_n / WEIGHTS_n (two sets) when the node has a skin; without JOINTS_0 the primitive is
  // drawn rigidly.
  Status readSkinAttributes(int node, const tinygltf::Primitive& p, const std::string& where,
                            VertexAttributes& va) const {
    const int skinIndex = m.nodes[node].skin;
    if (skinIndex < 0) return {};
    if (static_cast<size_t>(skinIndex) >= m.skins.size())
      return Error{where + ": skin " + std::to_string(skinIndex) + " out of range"};
    va.skin = &m.skins[skinIndex];
    for (int set = 0; set < 2; ++set) {
      const std::string j = "JOINTS_" + std::to_string(set), w = "WEIGHTS_" + std::to_string(set);
      if ((attributeAccessor(p, j.c_str()) < 0) != (attributeAccessor(p, w.c_str()) < 0))
        return Error{where + ": " + j + " and " + w + " must come together"};
      auto jr = optionalAttribute(p, j.c_str(), 4, {kUByte, kUShort}, va.count(), where);
      if (!jr.ok()) return Error{jr.error()};
      auto wr = optionalAttribute(p, w.c_str(), 4, {kFloat, kUByte, kUShort}, va.count(), where);
      if (!wr.ok()) return Error{wr.error()};
      va.joints[set] = std::move(jr.value());
      va.weights[set] = std::move(wr.value());
    }
    if (va.joints[0].empty()) {
      warnings.push_back(where + ": node has a skin but the mesh has no JOINTS_0; drawn rigidly on its node");
      va.skin = nullptr;
    }
    if (attributeAccessor(p, "JOINTS_2") >= 0)
      warnings.push_back(where + ": JOINTS_2 and beyond ignored (8 influences max)");
    return {};
  }

  // The primitive's triangles as indices local to its vertices (strips and fans triangulated).
  Result<std::vector<uint32_t>> readTriangles(const tinygltf::Primitive& p, size_t vcount,
                                              const std::string& where) {
    std::vector<uint32_t> local;
    if (p.indices >= 0) {
      auto ir = AccessorReader(m, limits).read(p.indices, 1, {kUByte, kUShort, kUInt}, where + " indices");
      if (!ir.ok()) return Error{ir.error()};
      local.reserve(ir->size());
      for (double v : ir.value()) {
        if (v >= static_cast<double>(vcount))
          return loadError(where + ": index " + std::to_string(static_cast<uint64_t>(v)) + " out of range (" +
                      std::to_string(vcount) + " vertices)");
        local.push_back(static_cast<uint32_t>(v));
      }
    } else {
      local.resize(vcount);
      for (size_t i = 0; i < vcount; ++i) local[i] = static_cast<uint32_t>(i);
    }
    if (p.mode == TINYGLTF_MODE_TRIANGLES && local.size() % 3 != 0)
      warnings.push_back(where + ": index count not a multiple of 3; the last partial triangle is dropped");
    std::vector<uint32_t> tris = triangulate(p.mode, local);
    if (asset.mesh.indices.size() + tris.size() > limits.maxTotalIndices)
      return loadError(where + ": more than " + std::to_string(limits.maxTotalIndices) + " indices in total");
    return tris;
  }

  // Vertex i's up to eight influences, normalised; with no influence at all it follows the skin's
  // first joint rather than collapsing to the origin.
  Status setSkinWeights(SkinnedVertex& v, const VertexAttributes& va, size_t i, int nodeJoint,
                        const std::string& where) const {
    const tinygltf::Skin* skin = va.skin;
    float w[8] = {};
    uint32_t jt[8] = {};
    float sum = 0.0f;
    for (int set = 0; set < 2; ++set) {
      if (va.joints[set].empty()) continue;
      for (int k = 0; k < 4; ++k) {
        const double ji = va.joints[set][i * 4 + k];
        const float wk = static_cast<float>(va.weights[set][i * 4 + k]);
        if (!(wk >= 0.0f)) return Error{where + ": negative skin weight at vertex " + std::to_string(i)};
        if (wk == 0.0f) continue;
        if (ji >= static_cast<double>(skin->joints.size()))
          return Error{where + ": JOINTS_" + std::to_string(set) + " index " +
                       std::to_string(static_cast<uint64_t>(ji)) + " out of range (skin has " +
                       std::to_string(skin->joints.size()) + " joints)"};
        w[set * 4 + k] = wk;
        jt[set * 4 + k] = static_cast<uint32_t>(asset.gltfNodeToJoint[skin->joints[static_cast<size_t>(ji)]]);
        sum += wk;
      }
    }
    if (!(sum > 1e-8f)) {
      const int fallback = skin->joints.empty() ? nodeJoint : asset.gltfNodeToJoint[skin->joints[0]];
      v.joints0 = glm::uvec4(static_cast<uint32_t>(fallback), 0, 0, 0);
      v.weights0 = glm::vec4(1.0f, 0.0f, 0.0f, 0.0f);
      return {};
    }
    for (int k = 0; k < 4; ++k) {
      v.joints0[k] = jt[k];
      v.weights0[k] = w[k] / sum;
      v.joints1[k] = jt[4 + k];
      v.weights1[k] = w[4 + k] / sum;
    }
    return {};
  }

  // Appends the primitive's vertices from `first` on. Rigid vertices are stored in the space where
  // palette[nodeJoint] = global * inverseBind maps them like global alone would.
  Status appendVertices(const VertexAttributes& va, size_t first, int nodeJoint, const glm::mat4& rigidToBind,
                        const glm::mat3& rigidNormal, const std::string& where) {
    const size_t vcount = va.count();
    asset.mesh.vertices.resize(first + vcount);
    for (size_t i = 0; i < vcount; ++i) {
      SkinnedVertex& v = asset.mesh.vertices[first + i];
      v.position = glm::vec3(va.position[i * 3], va.position[i * 3 + 1], va.position[i * 3 + 2]);
      if (!va.normal.empty()) {
        glm::vec3 n(va.normal[i * 3], va.normal[i * 3 + 1], va.normal[i * 3 + 2]);
        const float len = glm::length(n);
        v.normal = len > 1e-12f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
      }
      if (!va.uv0.empty()) v.uv = glm::vec2(va.uv0[i * 2], va.uv0[i * 2 + 1]);
      if (!va.uv1.empty()) v.uv1 = glm::vec2(va.uv1[i * 2], va.uv1[i * 2 + 1]);
      if (!va.skin) {
        v.joints0 = glm::uvec4(static_cast<uint32_t>(nodeJoint), 0, 0, 0);
        v.weights0 = glm::vec4(1.0f, 0.0f, 0.0f, 0.0f);
        v.position = glm::vec3(rigidToBind * glm::vec4(v.position, 1.0f));
        v.normal = glm::normalize(rigidNormal * v.normal);
        continue;
      }
      if (auto s = setSkinWeights(v, va, i, nodeJoint, where); !s.ok()) return s;
    }
    return {};
  }

  Status addPrimitive(int node, const tinygltf::Primitive& p, const std::string& where) {
    if (p.mode != TINYGLTF_MODE_TRIANGLES && p.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
        p.mode != TINYGLTF_MODE_TRIANGLE_FAN) {
      warnings.push_back(where + ": mode " + std::to_string(p.mode) + " is not triangles; skipped");
      return {};
    }
    const int posAcc = attributeAccessor(p, "POSITION");
    if (posAcc < 0) {
      warnings.push_back(where + ": no POSITION; skipped");
      return {};
    }
    VertexAttributes va;
    if (auto s = readVertexAttributes(node, p, posAcc, where, va); !s.ok()) return s;
    const size_t vcount = va.count();
    auto tris = readTriangles(p, vcount, where);
    if (!tris.ok()) return Error{tris.error()};

    const size_t first = asset.mesh.vertices.size();
    const int nodeJoint = asset.gltfNodeToJoint[node];
    // Rigid vertices are pre-multiplied by inverse(inverseBind[nodeJoint]).
    const glm::mat4 rigidToBind = glm::inverse(asset.mesh.inverseBind[nodeJoint]);
    const glm::mat3 rigidNormal = glm::inverseTranspose(glm::mat3(rigidToBind));
    if (auto s = appendVertices(va, first, nodeJoint, rigidToBind, rigidNormal, where); !s.ok()) return s;
    if (va.normal.empty()) computeNormals(asset.mesh.vertices, first, tris.value());
    if (auto s = checkFinite(first, where); !s.ok()) return s;
    const glm::mat3 deltaToBind = va.skin ? glm::mat3(1.0f) : glm::mat3(rigidToBind);
    const glm::mat3 normalDeltaToBind = va.skin ? glm::mat3(1.0f) : rigidNormal;
    if (auto s = addMorphTargets(node, p, first, vcount, deltaToBind, normalDeltaToBind, where); !s.ok()) return s;
    appendPrimitive(node, p, first, tris.value(), where);
    return {};
  }

  void appendPrimitive(int node, const tinygltf::Primitive& p, size_t first,
                       const std::vector<uint32_t>& tris, const std::string& where) {
    Primitive prim;
    prim.firstIndex = static_cast<uint32_t>(asset.mesh.indices.size());
    prim.indexCount = static_cast<uint32_t>(tris.size());
    prim.material = p.material >= 0 && static_cast<size_t>(p.material) < m.materials.size() ? p.material : -1;
    prim.sourceNode = node;
    prim.sourceMesh = m.nodes[node].mesh;
    if (p.material >= 0 && prim.material < 0)
      warnings.push_back(where + ": material " + std::to_string(p.material) +
                         " out of range; default material used");
    for (uint32_t i : tris) asset.mesh.indices.push_back(static_cast<uint32_t>(first) + i);
    if (prim.indexCount > 0) asset.mesh.primitives.push_back(prim);
  }

  // The channel for (node, target), created with the mesh's default weight and target name.
  uint32_t morphChannel(int node, int target) {
    auto& channels = asset.mesh.morphChannels;
    for (size_t c = 0; c < channels.size(); ++c)
      if (channels[c].sourceNode == node && channels[c].targetIndex == target) return static_cast<uint32_t>(c);
    MorphChannel ch;
    ch.sourceNode = node;
    ch.sourceMesh = m.nodes[node].mesh;
    ch.targetIndex = target;
    const auto& mesh = m.meshes[static_cast<size_t>(ch.sourceMesh)];
    if (static_cast<size_t>(target) < mesh.weights.size() && std::isfinite(mesh.weights[target]))
      ch.defaultWeight = static_cast<float>(mesh.weights[target]);
    const auto& names = mesh.extras.Get("targetNames");
    if (names.IsArray() && static_cast<size_t>(target) < names.ArrayLen() && names.Get(target).IsString())
      ch.name = names.Get(target).Get<std::string>();
    channels.push_back(std::move(ch));
    return static_cast<uint32_t>(channels.size() - 1);
  }

  // glTF morph targets of one primitive (POSITION and NORMAL deltas; TANGENT is not used) as
  // sparse deltas of vertices [first, first + vcount), in the space the vertices were stored in.
  Status addMorphTargets(int node, const tinygltf::Primitive& p, size_t first, size_t vcount, const glm::mat3& toBind,
                         const glm::mat3& normalToBind, const std::string& where) {
    if (p.targets.empty()) return {};
    if (p.targets.size() > kMaxMorphTargets)
      return Error{where + ": " + std::to_string(p.targets.size()) + " morph targets (at most " +
                   std::to_string(kMaxMorphTargets) + ")"};
    AccessorReader reader(m, limits);
    auto& deltas = asset.mesh.morphDeltas;
    const size_t before = deltas.size();
    for (size_t t = 0; t < p.targets.size(); ++t) {
      const std::string what = where + " target " + std::to_string(t);
      std::vector<double> data[2];
      const char* names[2] = {"POSITION", "NORMAL"};
      for (int a = 0; a < 2; ++a) {
        const auto it = p.targets[t].find(names[a]);
        if (it == p.targets[t].end()) continue;
        auto r = reader.read(it->second, 3, {TINYGLTF_COMPONENT_TYPE_FLOAT}, what + " " + names[a]);
        if (!r.ok()) return Error{r.error()};
        if (r->size() != vcount * 3)
          return Error{what + " " + names[a] + ": " + std::to_string(r->size() / 3) + " elements for " +
                       std::to_string(vcount) + " vertices"};
        data[a] = std::move(r.value());
      }
      if (data[0].empty() && data[1].empty()) continue;
      const uint32_t channel = morphChannel(node, static_cast<int>(t));
      for (size_t i = 0; i < vcount; ++i) {
        glm::vec3 dp(0.0f), dn(0.0f);
        if (!data[0].empty()) dp = glm::vec3(data[0][i * 3], data[0][i * 3 + 1], data[0][i * 3 + 2]);
        if (!data[1].empty()) dn = glm::vec3(data[1][i * 3], data[1][i * 3 + 1], data[1][i * 3 + 2]);
        if (dp == glm::vec3(0.0f) && dn == glm::vec3(0.0f)) continue;
        MorphDelta d{static_cast<uint32_t>(first + i), channel, toBind * dp, normalToBind * dn};
        if (!std::isfinite(d.position.x + d.position.y + d.position.z + d.normal.x + d.normal.y + d.normal.z))
          return Error{what + ": vertex " + std::to_string(i) + " has a non-finite delta"};
        if (deltas.size() >= limits.maxTotalVertices)
          return Error{what + ": more than " + std::to_string(limits.maxTotalVertices) + " morph deltas in total"};
        deltas.push_back(d);
      }
    }
    // This primitive's vertices come after every earlier one: sorting its own deltas keeps the whole list sorted.
    std::stable_sort(deltas.begin() + static_cast<std::ptrdiff_t>(before), deltas.end(),
                     [](const MorphDelta& a, const MorphDelta& b) { return a.vertex < b.vertex; });
    return {};
  }

  // Finite inputs can still overflow (3e38 times a bind matrix) or come out of a singular inverse
  // bind matrix as NaN: a vertex position that is not finite is an error, a normal falls back to +Y.
  Status checkFinite(size_t first, const std::string& where) {
    for (size_t i = first; i < asset.mesh.vertices.size(); ++i) {
      SkinnedVertex& v = asset.mesh.vertices[i];
      if (!std::isfinite(v.position.x + v.position.y + v.position.z))
        return Error{where + ": vertex " + std::to_string(i - first) +
                     " is not finite after its node's bind transform (singular or huge matrices)"};
      if (!std::isfinite(v.normal.x + v.normal.y + v.normal.z)) v.normal = glm::vec3(0.0f, 1.0f, 0.0f);
    }
    return {};
  }

  Status addMeshes() {
    for (size_t node = 0; node < m.nodes.size(); ++node) {
      const int mesh = m.nodes[node].mesh;
      if (mesh < 0) continue;
      if (static_cast<size_t>(mesh) >= m.meshes.size())
        return Error{"node " + std::to_string(node) + ": mesh " + std::to_string(mesh) + " out of range"};
      const auto& prims = m.meshes[mesh].primitives;
      for (size_t pi = 0; pi < prims.size(); ++pi) {
        const std::string where = "mesh " + std::to_string(mesh) + " ('" + m.meshes[mesh].name +
                                  "') primitive " + std::to_string(pi);
        if (auto s = addPrimitive(static_cast<int>(node), prims[pi], where); !s.ok()) return s;
      }
    }
    return {};
  }
};

// A finite number from a tinygltf JSON value, or `fallback`.
double numberOr(const tinygltf::Value& v, double fallback) {
  if (!v.IsNumber()) return fallback;
  const double x = v.GetNumberAsDouble();
  return std::isfinite(x) ? x : fallback;
}

glm::vec2 vec2Or(const tinygltf::Value& v, glm::vec2 fallback) {
  if (!v.IsArray() || v.ArrayLen() != 2 || !v.Get(0).IsNumber() || !v.Get(1).IsNumber()) return fallback;
  const glm::vec2 r(numberOr(v.Get(0), fallback.x), numberOr(v.Get(1), fallback.y));
  return r;
}

// The image a textureInfo refers to (-1 when absent or broken, with a warning) and its
// KHR_texture_transform. Texture coordinate sets beyond TEXCOORD_1 are not read: such a
// texture falls back to TEXCOORD_0 with a warning.
int textureImage(const tinygltf::Model& m, const AvatarAsset& asset, int tex, int texCoord,
                 const tinygltf::ExtensionMap& extensions, TextureTransform& transform, const std::string& what,
                 std::vector<std::string>& warnings) {
  transform = {};
  transform.texCoord = texCoord;
  if (auto it = extensions.find("KHR_texture_transform"); it != extensions.end() && it->second.IsObject()) {
    const auto& t = it->second;
    transform.offset = vec2Or(t.Get("offset"), glm::vec2(0.0f));
    transform.scale = vec2Or(t.Get("scale"), glm::vec2(1.0f));
    transform.rotation = static_cast<float>(numberOr(t.Get("rotation"), 0.0));
    if (t.Has("texCoord")) transform.texCoord = static_cast<int>(numberOr(t.Get("texCoord"), texCoord));
  }
  if (transform.texCoord != 0 && transform.texCoord != 1) {
    warnings.push_back(what + ": TEXCOORD_" + std::to_string(transform.texCoord) + " is not read; TEXCOORD_0 used");
    transform.texCoord = 0;
  }
  if (tex < 0) return -1;
  if (static_cast<size_t>(tex) < m.textures.size() && m.textures[tex].source >= 0 &&
      static_cast<size_t>(m.textures[tex].source) < m.images.size()) {
    const int img = m.textures[tex].source;
    return asset.images[img].rgba.empty() ? -1 : img;
  }
  warnings.push_back(what + ": texture " + std::to_string(tex) + " or its image is out of range; untextured");
  return -1;
}

void addMaterialsAndImages(const tinygltf::Model& m, AvatarAsset& asset, std::vector<std::string>& warnings) {
  asset.images.resize(m.images.size());
  for (size_t i = 0; i < m.images.size(); ++i) {
    const auto& src = m.images[i];
    if (src.width > 0 && src.height > 0 &&
        src.image.size() == static_cast<size_t>(src.width) * static_cast<size_t>(src.height) * 4) {
      asset.images[i].width = src.width;
      asset.images[i].height = src.height;
      asset.images[i].rgba = src.image;
    }
  }
  for (size_t i = 0; i < m.materials.size(); ++i) {
    const auto& src = m.materials[i];
    const std::string what = "material " + std::to_string(i);
    Material mat;
    mat.name = src.name;
    const auto& f = src.pbrMetallicRoughness.baseColorFactor;
    if (f.size() == 4 && std::all_of(f.begin(), f.end(), [](double x) { return std::isfinite(x); }))
      mat.baseColorFactor = glm::vec4(f[0], f[1], f[2], f[3]);
    const auto& base = src.pbrMetallicRoughness.baseColorTexture;
    mat.baseColorImage = textureImage(m, asset, base.index, base.texCoord, base.extensions, mat.baseColorTransform,
                                      what + " base colour", warnings);
    const auto& e = src.emissiveFactor;
    if (e.size() == 3 && std::all_of(e.begin(), e.end(), [](double x) { return std::isfinite(x) && x >= 0.0; }))
      mat.emissiveFactor = glm::vec3(e[0], e[1], e[2]);
    mat.emissiveImage = textureImage(m, asset, src.emissiveTexture.index, src.emissiveTexture.texCoord,
                                     src.emissiveTexture.extensions, mat.emissiveTransform, what + " emissive",
                                     warnings);
    if (auto it = src.extensions.find("KHR_materials_emissive_strength"); it != src.extensions.end())
      mat.emissiveStrength = static_cast<float>(std::max(0.0, numberOr(it->second.Get("emissiveStrength"), 1.0)));
    mat.unlit = src.extensions.count("KHR_materials_unlit") > 0;
    if (src.alphaMode == "MASK")
      mat.alphaMode = AlphaMode::Mask;
    else if (src.alphaMode == "BLEND")
      mat.alphaMode = AlphaMode::Blend;
    mat.alphaCutoff = std::isfinite(src.alphaCutoff) ? static_cast<float>(src.alphaCutoff) : 0.5f;
    mat.doubleSided = src.doubleSided;
    asset.materials.push_back(std::move(mat));
  }
}

AvatarFormat detectFormat(const tinygltf::Model& m) {
  auto uses = [&](const std::string& ext) {
    return m.extensions.count(ext) > 0 ||
           std::find(m.extensionsUsed.begin(), m.extensionsUsed.end(), ext) != m.extensionsUsed.end();
  };
  if (uses("VRMC_vrm")) return AvatarFormat::Vrm1;
  if (uses("VRM")) return AvatarFormat::Vrm0;
  return AvatarFormat::Gltf;
}

}  // namespace

Result<AvatarAsset> loadGltfFromMemory(const std::vector<uint8_t>& bytes, const std::string& baseDir,
                                       GltfLoadReport* report, const GltfLimits& limits) {
  GltfLoadReport localReport;
  std::vector<std::string>& warnings = report ? report->warnings : localReport.warnings;
  if (bytes.empty()) return loadError("empty file");
  if (bytes.size() > limits.maxFileBytes)
    return loadError("file larger than " + std::to_string(limits.maxFileBytes) + " bytes");
  auto container = splitContainer(bytes);
  if (!container.ok()) return Error{container.error()};
  if (auto s = checkJsonNesting(container->json, limits.maxJsonDepth); !s.ok()) return Error{s.error()};
  if (auto s = checkRequiredExtensions(container->json); !s.ok()) return Error{s.error()};

  tinygltf::TinyGLTF parser;
  ImageLoaderContext imageContext{limits.maxImageDimension, &warnings};
  parser.SetImageLoader(decodeImage, &imageContext);
  parser.SetStoreOriginalJSONForExtrasAndExtensions(true);
  uint64_t maxExternalBytes = limits.maxFileBytes;
  parser.SetFsCallbacks({&tinygltf::FileExists, &tinygltf::ExpandFilePath, &readExternalFile,
                         &tinygltf::WriteWholeFile, &maxExternalBytes});
  tinygltf::Model model;
  std::string err, warn;
  bool ok = false;
  try {
    if (container->isGlb)
      ok = parser.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(),
                                       static_cast<unsigned int>(bytes.size()), baseDir);
    else
      ok = parser.LoadASCIIFromString(&model, &err, &warn, container->json.data(),
                                      static_cast<unsigned int>(container->json.size()), baseDir);
  } catch (const std::exception& e) {
    return loadError(std::string("glTF parse error: ") + e.what());
  }
  if (!ok) {
    while (!err.empty() && err.back() == '\n') err.pop_back();
    return loadError("glTF parse error: " + (err.empty() ? std::string("unknown") : err));
  }
  if (!warn.empty()) warnings.push_back(warn);

  AvatarAsset asset;
  asset.rawJson = std::move(container->json);
  asset.format = detectFormat(model);
  if (auto s = buildSkeleton(model, limits, asset); !s.ok()) return Error{s.error()};
  MeshBuilder builder{model, limits, asset, warnings, {}};
  if (auto s = builder.addSkins(); !s.ok()) return Error{s.error()};
  if (auto s = builder.addMeshes(); !s.ok()) return Error{s.error()};
  // After the meshes: rigid vertices were stored against the file's binds, which the fold adjusts.
  foldBoneScaleIntoBind(asset);
  addMaterialsAndImages(model, asset, warnings);
  readMToonMaterials(asset, warnings);  // VRMC_materials_mtoon, VRM 0.x materialProperties
  asset.mesh.firstPersonIndices = asset.mesh.indices;
  asset.mesh.firstPersonPrimitives = asset.mesh.primitives;
  return asset;
}

Result<AvatarAsset> loadGltfFile(const std::string& path, GltfLoadReport* report, const GltfLimits& limits) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return loadError("cannot open '" + path + "': " + ec.message());
  if (size > limits.maxFileBytes)
    return loadError("'" + path + "' is larger than " + std::to_string(limits.maxFileBytes) + " bytes");
  std::ifstream in(path, std::ios::binary);
  if (!in) return loadError("cannot open '" + path + "'");
  std::vector<uint8_t> bytes(size);
  if (size > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size)))
    return loadError("cannot read '" + path + "'");
  std::string baseDir = std::filesystem::path(path).parent_path().string();
  if (baseDir.empty()) baseDir = ".";
  auto r = loadGltfFromMemory(bytes, baseDir, report, limits);
  if (!r.ok()) return loadError("'" + path + "': " + r.error());
  r->sourcePath = path;
  return r;
}

}  // namespace embody::avatar
