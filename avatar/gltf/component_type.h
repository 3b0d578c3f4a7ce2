#pragma once
// glTF 2.0 accessor component types (the specification's codes; tinygltf names them
// TINYGLTF_COMPONENT_TYPE_*): one set for the loader and the writer.
namespace embody::avatar::gltf {

inline constexpr int kUByte = 5121, kUShort = 5123, kUInt = 5125, kFloat = 5126;

}  // namespace embody::avatar::gltf
