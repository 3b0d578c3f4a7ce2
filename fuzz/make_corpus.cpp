// Writes the seed corpus (fuzz/corpus/<target>/) from the project's own fixtures: the test glTF
// builders (tests/avatar), the default mannequin, the embedded spine models, the synthetic
// motions. Nothing third-party. Run after a format changes: embody_fuzz_corpus fuzz/corpus
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include "avatar/body/calibration.h"
#include "avatar/gltf/glb_writer.h"
#include "avatar/procedural/default_avatar.h"
#include "avatar/humanoid_test_files.h"
#include "support/vrm_test_avatar.h"
#include "ik/spine/spine_description.h"
#include "tests/support/mtoon_test_avatar.h"
#include "tracking/pose_source.h"
#include "tracking/trace.h"

namespace fs = std::filesystem;
using nlohmann::json;
using namespace embody;

namespace {

fs::path gRoot;

const char* const kInvalidTrackersTrace =
    "{\"t\": 0, \"head\": {\"p\": [0, 1.6, 0], \"q\": [0, 0, 0, 1], \"valid\": true}, \"left\": {\"valid\": false}}\n"
    "{\"t\": 0.1, \"head\": {\"p\": [0, 1.6, null], \"q\": [0, 0, 0, 1]}, \"right\": {\"p\": [0.3, 1, -0.3], "
    "\"q\": [0, 0, 0, 1], \"trigger\": 0.5}}\n";

void write(const std::string& rel, const std::string& bytes) {
  const fs::path p = gRoot / rel;
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << bytes;
  std::printf("%s (%zu bytes)\n", p.c_str(), bytes.size());
}
void write(const std::string& rel, const std::vector<uint8_t>& bytes) {
  write(rel, std::string(bytes.begin(), bytes.end()));
}

std::string base64(const std::vector<uint8_t>& in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < in.size(); i += 3) {
    const uint32_t v = (in[i] << 16) | (i + 1 < in.size() ? in[i + 1] << 8 : 0) | (i + 2 < in.size() ? in[i + 2] : 0);
    out += k[(v >> 18) & 63];
    out += k[(v >> 12) & 63];
    out += i + 1 < in.size() ? k[(v >> 6) & 63] : '=';
    out += i + 2 < in.size() ? k[v & 63] : '=';
  }
  return out;
}

void gltfSeeds() {
  test::TriangleFile tri;
  write("gltf/triangle.glb", tri.glb());
  json doc = tri.doc;
  doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(tri.bin);
  write("gltf/triangle.gltf", doc.dump());
  test::HumanoidFile human;
  write("gltf/humanoid.glb", human.glb());
  test::HumanoidFile vrm1;
  json bones = json::object();
  for (const auto& [bone, node] : vrm1.nodeOfBone) bones[bone] = {{"node", node}};
  vrm1.doc["extensionsUsed"] = {"VRMC_vrm"};
  vrm1.doc["extensions"]["VRMC_vrm"] = {
      {"specVersion", "1.0"},
      {"humanoid", {{"humanBones", bones}}},
      {"firstPerson", {{"meshAnnotations", {{{"node", vrm1.hairNode}, {"type", "thirdPersonOnly"}},
                                            {{"node", vrm1.innerNode}, {"type", "firstPersonOnly"}}}}}}};
  write("gltf/humanoid_vrm1.vrm", vrm1.glb());
  // The VRM test bust: morph targets, spring bones, expressions, look-at (1.0 and 0.x).
  for (bool vrm0 : {false, true}) {
    const test::VrmTestAvatar bust = test::buildVrmTestAvatar({.vrm0 = vrm0});
    auto bytes = avatar::encodeGlb(bust.asset, nullptr, bust.extensionsJson);
    if (bytes) write(vrm0 ? "gltf/vrm0_bust.vrm" : "gltf/vrm1_bust.vrm", *bytes);
  }
}

// Spring bones, expressions and look-at over the mannequin (its left and right arms as spring
// chains, colliders on the chest and spine), VRM 1.0 and 0.x.
void vrmMotionSeeds(const avatar::AvatarAsset& a, const json& v1, const json& v0) {
  using B = avatar::HumanBone;
  auto joint = [&](B b) { return a.humanoid.joint(b); };
  json chain = json::array();
  chain.push_back({{"node", joint(B::leftUpperArm)}, {"stiffness", 1.0}, {"dragForce", 0.4}, {"gravityPower", 0.5},
                   {"gravityDir", {0, -1, 0}}, {"hitRadius", 0.02}});
  chain.push_back({{"node", joint(B::leftLowerArm)}, {"stiffness", 2.0}});
  chain.push_back({{"node", joint(B::leftHand)}});
  json spring = {{"name", "arm"}, {"joints", chain}, {"colliderGroups", {0}}, {"center", joint(B::hips)}};
  json sphere = {{"node", joint(B::chest)}, {"shape", {{"sphere", {{"offset", {0, 0.1, 0}}, {"radius", 0.15}}}}}};
  json capsule = {{"node", joint(B::spine)},
                  {"shape", {{"capsule", {{"offset", {0, 0, 0}}, {"tail", {0, 0.3, 0}}, {"radius", 0.1}}}}}};
  json group = {{"colliders", {0, 1}}};
  json springBone = {{"specVersion", "1.0"},
                     {"colliders", json::array({sphere, capsule})},
                     {"colliderGroups", json::array({group})},
                     {"springs", json::array({spring})}};
  json blinkBind = {{"node", 0}, {"index", 0}, {"weight", 1}};
  json expressions = {{"preset", {{"blink", {{"morphTargetBinds", json::array({blinkBind})}}},
                                  {"happy", {{"overrideBlink", "block"}, {"isBinary", true}}}}},
                      {"custom", {{"wink", {{"overrideMouth", "blend"}}}}}};
  json range = {{"inputMaxValue", 90}, {"outputScale", 10}};
  json lookAt = {{"type", "expression"}, {"offsetFromHeadBone", {0, 0.06, 0.08}}, {"rangeMapHorizontalOuter", range}};
  json vrm1 = {{"specVersion", "1.0"}, {"humanoid", {{"humanBones", v1}}}, {"lookAt", lookAt}, {"expressions", expressions}};
  json ext1 = {{"VRMC_vrm", vrm1}, {"VRMC_springBone", springBone}};
  write("vrm/vrm1_springs.json", json{{"extensions", ext1}}.dump(1));

  json collider0 = {{"offset", {{"x", 0}, {"y", 0.1}, {"z", 0}}}, {"radius", 0.15}};
  json group0 = {{"node", joint(B::chest)}, {"colliders", json::array({collider0})}};
  json boneGroup = {{"stiffiness", 1.0}, {"gravityPower", 0.3}, {"gravityDir", {{"x", 0}, {"y", -1}, {"z", 0}}},
                    {"dragForce", 0.4}, {"center", -1}, {"hitRadius", 0.02},
                    {"bones", {joint(B::rightUpperArm)}}, {"colliderGroups", {0}}};
  json blink0 = {{"presetName", "blink"}, {"binds", json::array({json{{"mesh", 0}, {"index", 0}, {"weight", 100}}})}};
  json joy0 = {{"presetName", "joy"}, {"isBinary", true}};
  json firstPerson = {{"firstPersonBone", joint(B::head)}, {"lookAtTypeName", "Bone"},
                      {"firstPersonBoneOffset", {{"x", 0}, {"y", 0.06}, {"z", 0}}},
                      {"lookAtHorizontalOuter", {{"xRange", 90}, {"yRange", 10}}}};
  json vrm0 = {{"humanoid", {{"humanBones", v0}}},
               {"firstPerson", firstPerson},
               {"blendShapeMaster", {{"blendShapeGroups", json::array({blink0, joy0})}}},
               {"secondaryAnimation", {{"boneGroups", json::array({boneGroup})}, {"colliderGroups", json::array({group0})}}}};
  write("vrm/vrm0_springs.json", json{{"extensions", {{"VRM", vrm0}}}}.dump(1));
}

// Extensions alone, over the default mannequin's joints (the vrm target's skeleton).
void vrmSeeds() {
  const avatar::AvatarAsset a = avatar::buildDefaultAvatar();
  json v1 = json::object(), v0 = json::array();
  for (int b = 0; b < avatar::kHumanBoneCount; ++b) {
    const int j = a.humanoid.bones[static_cast<size_t>(b)];
    if (j < 0) continue;
    const std::string name(avatar::humanBoneName(static_cast<avatar::HumanBone>(b)));
    v1[name] = {{"node", j}};
    v0.push_back({{"bone", name}, {"node", j}});
  }
  const int head = a.humanoid.joint(avatar::HumanBone::head);
  write("vrm/vrm1.json",
        json{{"extensionsUsed", {"VRMC_vrm"}},
             {"extensions",
              {{"VRMC_vrm",
                {{"specVersion", "1.0"},
                 {"humanoid", {{"humanBones", v1}}},
                 {"firstPerson", {{"meshAnnotations", {{{"node", head}, {"type", "thirdPersonOnly"}}}}}}}}}}}
            .dump(1));
  write("vrm/vrm0.json",
        json{{"extensions",
              {{"VRM",
                {{"humanoid", {{"humanBones", v0}}},
                 {"firstPerson",
                  {{"firstPersonBone", head},
                   {"meshAnnotations", {{{"mesh", 0}, {"firstPersonFlag", "ThirdPersonOnly"}}}}}}}}}}}
            .dump(1));
  vrmMotionSeeds(a, v1, v0);
  json byName = json::object(), byIndex = json::object();
  for (int b = 0; b < avatar::kHumanBoneCount; ++b) {
    const int j = a.humanoid.bones[static_cast<size_t>(b)];
    if (j < 0) continue;
    const std::string name(avatar::humanBoneName(static_cast<avatar::HumanBone>(b)));
    byName[name] = a.skeleton.joints[static_cast<size_t>(j)].name;
    byIndex[name] = j;
  }
  write("bone_map/by_name.json", byName.dump(1));
  write("bone_map/by_index.json", byIndex.dump(1));
  write("bone_map/partial.json", json{{"hips", a.skeleton.joints[0].name}, {"head", head}}.dump());
}

// MToon: the JSON of the project's VRM 1.0 and 0.x MToon test avatars (materials, textures and
// extensions; the vrm target does not read buffers), and a 1.0 material with hostile values.
void mtoonSeeds() {
  auto keep = [](const Result<std::vector<uint8_t>>& glb, const char* name) {
    if (!glb.ok()) return;
    (void)test::editGlbJson(glb.value(), [&](json& doc) {
      json seed = json::object();
      for (const char* key : {"extensionsUsed", "extensions", "materials", "textures"})
        if (doc.contains(key)) seed[key] = doc[key];
      write(std::string("vrm/") + name, seed.dump(1));
    });
  };
  keep(test::mtoonVrm1File(), "mtoon1.json");
  keep(test::mtoonVrm0File(), "mtoon0.json");
  write("vrm/mtoon1_hostile.json",
        json{{"textures", {{{"source", 1}}, {{"source", 7}}}},
             {"materials",
              {{{"extensions",
                 {{"VRMC_materials_mtoon",
                   {{"shadingToonyFactor", "high"}, {"giEqualizationFactor", 7}, {"shadeColorFactor", {0.5, "x"}},
                    {"outlineWidthMode", "screenCoordinates"}, {"outlineWidthFactor", 1e30},
                    {"shadeMultiplyTexture", {{"index", 1}}}, {"rimMultiplyTexture", {{"index", 0}, {"texCoord", 3}}},
                    {"renderQueueOffsetNumber", -42}}}}}}}}}
            .dump(1));
}

// A BVH of the default mannequin's skeleton (offsets in centimetres), three frames.
void bvhSeeds() {
  const avatar::AvatarAsset a = avatar::buildDefaultAvatar();
  const auto& joints = a.skeleton.joints;
  std::string out = "HIERARCHY\n";
  std::vector<int> open;
  int channels = 0;
  auto close = [&](int untilParent) {
    while (!open.empty() && open.back() != untilParent) {
      out += std::string(2 * open.size() - 2, ' ') + "}\n";
      open.pop_back();
    }
  };
  for (size_t j = 0; j < joints.size(); ++j) {
    close(joints[j].parent);
    const std::string pad(2 * open.size(), ' ');
    const glm::vec3 t = joints[j].rest.translation * 100.0f;
    out += pad + (joints[j].parent < 0 ? "ROOT " : "JOINT ") + joints[j].name + "\n" + pad + "{\n";
    char line[160];
    std::snprintf(line, sizeof line, "%s  OFFSET %.3f %.3f %.3f\n", pad.c_str(), t.x, t.y, t.z);
    out += line;
    out += pad + (joints[j].parent < 0 ? "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
                                       : "  CHANNELS 3 Zrotation Xrotation Yrotation\n");
    channels += joints[j].parent < 0 ? 6 : 3;
    open.push_back(static_cast<int>(j));
  }
  close(-2);
  out += "MOTION\nFrames: 3\nFrame Time: 0.0333333\n";
  for (int f = 0; f < 3; ++f) {
    for (int c = 0; c < channels; ++c) out += (c == 1 ? "95.0" : std::to_string(2.5 * f * ((c % 3) - 1))) + " ";
    out += "\n";
  }
  write("bvh/mannequin.bvh", out);
  write("bvh/end_site.bvh",
        "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation "
        "Xrotation\n  JOINT Head\n  {\n    OFFSET 0 60 0\n    CHANNELS 3 Zrotation Yrotation Xrotation\n    End Site\n"
        "    {\n      OFFSET 0 10 0\n    }\n  }\n}\nMOTION\nFrames: 2\nFrame Time: 0.1\n0 90 0 0 0 0 0 0 0\n"
        "1 90 0 10 0 0 5 0 0\n");
}

// Traces in the JSON Lines format both tracking/trace and the headless runtime read.
void traceSeeds() {
  for (const char* motion : {"synthetic:idle", "synthetic:reach"}) {
    auto src = tracking::openPoseSource(motion);
    if (!src.ok()) continue;
    std::string out = json{{"embody_trace", 1}, {"source", motion}, {"user_height", 1.75}}.dump() + "\n";
    for (int i = 0; i < 8; ++i)
      out += tracking::formatTraceLine(src.value()->sample(i / 30.0), tracking::TrackerMask::all()) + "\n";
    write(std::string("trace/") + (motion + 10) + ".jsonl", out);
  }
  write("trace/invalid_trackers.jsonl", kInvalidTrackersTrace);
}

// The headless runtime's EMBODY_XR_POSES: its trace lines ({"t", "head", "left", "right"} with a
// per-hand trigger; header lines such as embody_trace's are not samples there) and BVH clips
// with Head/LeftHand/RightHand joints: a minimal one and the CMU-convention fixture of
// tests/tracking/fixtures (written for this project).
void xrPosesSeeds() {
  auto src = tracking::openPoseSource("synthetic:figure8");
  if (src.ok()) {
    std::string out;
    for (int i = 0; i < 8; ++i) {
      json line = json::parse(tracking::formatTraceLine(src.value()->sample(i / 30.0), tracking::TrackerMask::all()));
      if (line.contains("left")) line["left"]["trigger"] = 0.125 * i;
      out += line.dump() + "\n";
    }
    write("xr_poses/figure8.jsonl", out);
  }
  write("xr_poses/invalid_trackers.jsonl", kInvalidTrackersTrace);
  write("xr_poses/three_point.bvh",
        "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation "
        "Xrotation\n  JOINT Head\n  {\n    OFFSET 0 70 0\n    CHANNELS 3 Zrotation Yrotation Xrotation\n"
        "    End Site\n    {\n      OFFSET 0 10 0\n    }\n  }\n  JOINT LeftHand\n  {\n    OFFSET 30 40 20\n"
        "    CHANNELS 3 Zrotation Xrotation Yrotation\n  }\n  JOINT RightHand\n  {\n    OFFSET -30 40 20\n"
        "    CHANNELS 3 Zrotation Xrotation Yrotation\n  }\n}\nMOTION\nFrames: 2\nFrame Time: 0.1\n"
        "0 95 0 0 0 0 0 0 0 0 0 0 0 0 0\n1 95 0 10 0 0 5 0 0 0 20 0 0 -20 0\n");
  std::ifstream fixture(fs::path(EMBODY_SOURCE_DIR) / "tests/tracking/fixtures/cmu.bvh", std::ios::binary);
  if (fixture) write("xr_poses/cmu_fixture.bvh", std::string(std::istreambuf_iterator<char>(fixture), {}));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: embody_fuzz_corpus OUT_DIR (fuzz/corpus)\n");
    return 2;
  }
  gRoot = argv[1];
  gltfSeeds();
  vrmSeeds();
  mtoonSeeds();
  bvhSeeds();
  traceSeeds();
  xrPosesSeeds();
  write("spine/full.json", ik::spine::toJson(ik::spine::defaultFullSpine()).dump(1));
  write("spine/simplified.json", ik::spine::toJson(ik::spine::defaultSimplifiedSpine()).dump(1));
  avatar::CalibrationInput in;
  in.userHeight = 1.8;
  in.armSpan = 1.82;
  auto profile = avatar::calibrate(avatar::buildDefaultAvatar(), in);
  if (profile.ok()) {
    const fs::path p = gRoot / "profile/calibrated.json";
    fs::create_directories(p.parent_path());
    if (!avatar::saveProfile(profile.value(), p.string()).ok()) return 1;
  }
  write("profile/minimal.json", json{{"user_height_m", 1.7}, {"scale", 1.0}}.dump());
  return 0;
}
