// loadAvatarFile: the one call applications make to get a drawable, mapped avatar.
#include "avatar/avatar_loader.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "avatar/gltf/gltf_loader.h"
#include "avatar/humanoid/first_person.h"
#include "avatar/vrm/vrm_parsers.h"

namespace embody::avatar {

namespace {

// Spring bones, expressions and look-at from the VRM extensions (nothing for other files).
void readVrmMotion(AvatarAsset& asset) {
  if (asset.rawJson.empty()) return;
  const auto doc = vrm::Json::parse(asset.rawJson, nullptr, false);
  if (doc.is_discarded()) return;
  asset.vrmWarnings.clear();
  asset.springBones = parseSpringBones(doc, asset, asset.vrmWarnings);
  asset.expressions = parseExpressions(doc, asset, asset.vrmWarnings);
  asset.lookAt = parseLookAt(doc, asset, asset.vrmWarnings);
}

}  // namespace

Status prepareAvatar(AvatarAsset& asset, const std::string& boneMapJson) {
  HumanoidInputs in;
  in.skeleton = &asset.skeleton;
  in.gltfJson = asset.rawJson;
  in.gltfNodeToJoint = asset.gltfNodeToJoint;
  in.boneMapJson = boneMapJson;
  in.jointHasWeights.assign(asset.skeleton.joints.size(), false);
  for (const auto& v : asset.mesh.vertices)
    for (int k = 0; k < 4; ++k) {
      if (v.weights0[k] > 0.0f && v.joints0[k] < in.jointHasWeights.size())
        in.jointHasWeights[v.joints0[k]] = true;
      if (v.weights1[k] > 0.0f && v.joints1[k] < in.jointHasWeights.size())
        in.jointHasWeights[v.joints1[k]] = true;
    }
  if (asset.mesh.vertices.empty()) in.jointHasWeights.clear();  // no mesh: weights say nothing
  auto map = mapHumanoid(in);
  if (!map.ok()) return Error{map.error()};
  asset.humanoid = std::move(map.value());
  buildFirstPerson(asset);
  readVrmMotion(asset);
  return {};
}

Result<std::string> readBoneMapFile(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return Error{"bone map '" + path + "': " + ec.message()};
  if (size > (1u << 20)) return Error{"bone map '" + path + "' is larger than 1 MiB"};
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  if (!in && !in.eof()) return Error{"bone map '" + path + "': cannot read"};
  return ss.str();
}

Result<AvatarAsset> loadAvatarFile(const std::string& path, const AvatarLoadOptions& options,
                                   GltfLoadReport* report) {
  std::string boneMap;
  if (!options.boneMapFile.empty()) {
    auto text = readBoneMapFile(options.boneMapFile);
    if (!text.ok()) return Error{text.error()};
    boneMap = std::move(text.value());
  }
  auto asset = loadGltfFile(path, report, options.limits);
  if (!asset.ok()) return asset;
  if (auto s = prepareAvatar(asset.value(), boneMap); !s.ok()) return Error{s.error()};
  return asset;
}

}  // namespace embody::avatar
