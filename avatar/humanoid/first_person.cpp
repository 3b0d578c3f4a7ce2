#include "avatar/humanoid/first_person.h"

#include <map>
#include <nlohmann/json.hpp>

namespace embody::avatar {
namespace {

enum class Annotation { Auto, Both, ThirdPersonOnly, FirstPersonOnly };

bool parseAnnotation(std::string s, Annotation& out) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (s == "auto")
    out = Annotation::Auto;
  else if (s == "both")
    out = Annotation::Both;
  else if (s == "thirdpersononly")
    out = Annotation::ThirdPersonOnly;
  else if (s == "firstpersononly")
    out = Annotation::FirstPersonOnly;
  else
    return false;
  return true;
}

bool vertexTouches(const SkinnedVertex& v, const std::vector<bool>& hidden) {
  for (int k = 0; k < 4; ++k) {
    if (v.weights0[k] > 0.0f && v.joints0[k] < hidden.size() && hidden[v.joints0[k]]) return true;
    if (v.weights1[k] > 0.0f && v.joints1[k] < hidden.size() && hidden[v.joints1[k]]) return true;
  }
  return false;
}

}  // namespace

bool triangleTouches(const SkinnedMesh& mesh, const std::vector<uint32_t>& indices, size_t triangle,
                     const std::vector<bool>& hidden) {
  for (int k = 0; k < 3; ++k)
    if (vertexTouches(mesh.vertices[indices[triangle * 3 + k]], hidden)) return true;
  return false;
}

namespace {

// The VRM file's first-person annotations: VRM 1.0 by node, VRM 0.x by mesh (and its head bone).
struct Annotations {
  std::map<int, Annotation> byNode, byMesh;
  int headNode = -1;  // VRM 0.x firstPersonBone
};

Annotations readAnnotations(const AvatarAsset& asset, FirstPersonInfo& info) {
  Annotations r;
  if (asset.rawJson.empty() || (asset.format != AvatarFormat::Vrm0 && asset.format != AvatarFormat::Vrm1)) return r;
  const auto doc = nlohmann::json::parse(asset.rawJson, nullptr, false);
  const auto ext = doc.is_object() ? doc.value("extensions", nlohmann::json::object()) : nlohmann::json::object();
  const bool v1 = asset.format == AvatarFormat::Vrm1;
  const auto vrm = ext.is_object() ? ext.value(v1 ? "VRMC_vrm" : "VRM", nlohmann::json::object()) : nlohmann::json();
  const auto fp = vrm.is_object() ? vrm.value("firstPerson", nlohmann::json::object()) : nlohmann::json();
  const auto annotations = fp.is_object() ? fp.value("meshAnnotations", nlohmann::json::array()) : nlohmann::json();
  if (annotations.is_array())
    for (const auto& a : annotations) {
      if (!a.is_object()) continue;
      const char* key = v1 ? "node" : "mesh";
      const char* typeKey = v1 ? "type" : "firstPersonFlag";
      if (!a.contains(key) || !a[key].is_number_integer() || !a.contains(typeKey) || !a[typeKey].is_string())
        continue;
      Annotation t;
      if (!parseAnnotation(a[typeKey].get<std::string>(), t)) continue;
      (v1 ? r.byNode : r.byMesh)[a[key].get<int>()] = t;
      info.annotations.push_back(std::string(key) + " " + std::to_string(a[key].get<int>()) + ": " +
                                 a[typeKey].get<std::string>());
    }
  if (!v1 && fp.is_object() && fp.contains("firstPersonBone") && fp["firstPersonBone"].is_number_integer())
    r.headNode = fp["firstPersonBone"].get<int>();
  return r;
}

// The head joint's whole subtree (parents come before children: one pass).
std::vector<bool> headSubtree(const Skeleton& skeleton, int headJoint) {
  std::vector<bool> hidden(skeleton.joints.size(), false);
  if (headJoint >= 0)
    for (size_t j = 0; j < hidden.size(); ++j) {
      const int p = skeleton.joints[j].parent;
      hidden[j] = static_cast<int>(j) == headJoint || (p >= 0 && hidden[static_cast<size_t>(p)]);
    }
  return hidden;
}

Annotation annotationOf(const Annotations& a, const Primitive& p) {
  if (auto it = a.byNode.find(p.sourceNode); it != a.byNode.end()) return it->second;
  if (auto im = a.byMesh.find(p.sourceMesh); im != a.byMesh.end()) return im->second;
  return Annotation::Auto;
}

}  // namespace

void buildFirstPerson(AvatarAsset& asset) {
  SkinnedMesh& mesh = asset.mesh;
  FirstPersonInfo& info = asset.firstPerson;
  info = {};
  const Annotations annotations = readAnnotations(asset, info);
  info.headJoint = asset.humanoid.joint(HumanBone::head);
  if (annotations.headNode >= 0 && static_cast<size_t>(annotations.headNode) < asset.gltfNodeToJoint.size())
    info.headJoint = asset.gltfNodeToJoint[static_cast<size_t>(annotations.headNode)];
  const std::vector<bool> hidden = headSubtree(asset.skeleton, info.headJoint);
  info.mode = !annotations.byNode.empty() || !annotations.byMesh.empty() ? "vrm"
              : info.headJoint >= 0                                      ? "auto"
                                                                         : "none";

  // Both lists are rebuilt from every primitive the loader produced (the current third-person list).
  const std::vector<Primitive> all = mesh.primitives;
  const std::vector<uint32_t> indices = mesh.indices;
  std::vector<uint32_t> thirdIdx, firstIdx;
  std::vector<Primitive> third, first;
  for (const Primitive& p : all) {
    const Annotation a = annotationOf(annotations, p);
    if (a != Annotation::FirstPersonOnly) {
      Primitive q = p;
      q.firstIndex = static_cast<uint32_t>(thirdIdx.size());
      thirdIdx.insert(thirdIdx.end(), indices.begin() + p.firstIndex, indices.begin() + p.firstIndex + p.indexCount);
      third.push_back(q);
    }
    if (a == Annotation::ThirdPersonOnly) {
      info.removedTriangles += p.indexCount / 3;
      continue;
    }
    Primitive q = p;
    q.firstIndex = static_cast<uint32_t>(firstIdx.size());
    for (uint32_t t = 0; t < p.indexCount / 3; ++t) {
      const size_t tri = p.firstIndex / 3 + t;
      if (a == Annotation::Auto && info.headJoint >= 0 && triangleTouches(mesh, indices, tri, hidden)) {
        ++info.removedTriangles;
        continue;
      }
      firstIdx.insert(firstIdx.end(), indices.begin() + tri * 3, indices.begin() + tri * 3 + 3);
    }
    q.indexCount = static_cast<uint32_t>(firstIdx.size()) - q.firstIndex;
    if (q.indexCount > 0) first.push_back(q);
  }
  mesh.indices = std::move(thirdIdx);
  mesh.primitives = std::move(third);
  mesh.firstPersonIndices = std::move(firstIdx);
  mesh.firstPersonPrimitives = std::move(first);
}

}  // namespace embody::avatar
