#pragma once
// The project's own MToon test avatars (no third-party file): the default mannequin split into a
// "skin" primitive (head, neck, hands) and a "cloth" primitive (the rest), each with an MToon
// material, written with the project's GLB writer and completed with the VRM extension:
//   - VRM 1.0: VRMC_vrm (specVersion, meta, humanoid) + VRMC_materials_mtoon on both materials
//     (cloth: world-space outline, parametric rim; skin: screen-space outline, matcap).
//   - VRM 0.x: the "VRM" extension (humanoid, meta, materialProperties with shader "VRM/MToon"),
//     its glTF materials the KHR_materials_unlit fallback UniVRM writes.
// Used by the engine tests (goldens, Khronos validator) and the fuzz corpus generator.
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "avatar/avatar_asset.h"
#include "core/result.h"

namespace embody::test {

// The mannequin with the two MToon materials (and a 64x64 matcap image), humanoid mapped.
avatar::AvatarAsset mtoonMannequin();

// Rewrites the JSON chunk of a GLB (the binary chunk is kept as is).
Result<std::vector<uint8_t>> editGlbJson(const std::vector<uint8_t>& glb, const std::function<void(nlohmann::json&)>& edit);

Result<std::vector<uint8_t>> mtoonVrm1File();
Result<std::vector<uint8_t>> mtoonVrm0File();

// The VRM 0.x materialProperties entries the 0.x file carries (also a fuzz seed).
nlohmann::json mtoonVrm0MaterialProperties();

}  // namespace embody::test
