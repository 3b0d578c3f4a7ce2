#pragma once
// MToon from the glTF JSON: VRM 1.0 `VRMC_materials_mtoon` on each material, and VRM 0.x
// `extensions.VRM.materialProperties` ("VRM/MToon", "VRM/Unlit*"), converted to the 1.0 model
// (avatar::MToon) with UniVRM's migration formulas. Read from AvatarAsset::rawJson after the
// loader has filled materials and images, so the VRM fuzz target can drive it from JSON alone.
//
// Hostile input never fails the load: a value of the wrong type, a non-finite or out-of-range
// number, a texture index that names no decoded image, an unknown enum string each give one
// warning naming the material and the property, and the specification's default (or the value
// clamped into its range) is used.
#include <string>
#include <vector>

#include "avatar/avatar_asset.h"

namespace embody::avatar {

// Fills asset.materials[i].mtoon / isMToon (and, for VRM 0.x, the glTF fields the 0.x
// properties override: base colour, emissive, alpha mode, cutoff, double-sided, unlit).
void readMToonMaterials(AvatarAsset& asset, std::vector<std::string>& warnings);

// sRGB-encoded colour component to linear (VRM 0.x stores Unity colours gamma-encoded).
float srgbToLinear(float c);

}  // namespace embody::avatar
