// embody avatar: inspect avatars (mapping, spine, first person) and export the default avatar.
//   embody avatar info FILE|default [--json] [--fingers] [--bone-map FILE] [--spine full|simplified|auto]
//                     [--user-height M] [--profile FILE]
//   embody avatar calibrate FILE|default (--user-height M | --eye-height M) [--arm-span M] --profile OUT
//   embody avatar export-default FILE.glb [--fingers]
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "app/args.h"
#include "app/avatar_arg.h"
#include "app/job_options.h"
#include "avatar/avatar_loader.h"
#include "avatar/body/body_model.h"
#include "avatar/body/calibration.h"
#include "avatar/gltf/glb_writer.h"
#include "avatar/gltf/gltf_loader.h"
#include "avatar/hand/finger_retarget.h"
#include "avatar/procedural/default_avatar.h"

namespace {

using namespace embody;
using namespace embody::avatar;

// Spring bones, expressions, look-at and morph targets (docs/avatars.md "VRM motion").
nlohmann::json describeVrmMotion(const AvatarAsset& a) {
  nlohmann::json expressions = nlohmann::json::array();
  for (const auto& e : a.expressions.expressions) expressions.push_back(e.name);
  const char* lookAt[] = {"none", "bone", "expression"};
  return {{"springs", a.springBones.chains.size()},
          {"spring_joints", a.springBones.jointCount()},
          {"colliders", a.springBones.colliders.size()},
          {"expressions", expressions},
          {"look_at", lookAt[static_cast<int>(a.lookAt.type)]},
          {"morph_channels", a.mesh.morphChannels.size()},
          {"warnings", a.vrmWarnings}};
}

nlohmann::json describe(const AvatarAsset& a, const GltfLoadReport& report) {
  const HumanoidMap& h = a.humanoid;
  auto nodeName = [&](int j) {
    return j >= 0 ? a.skeleton.joints[static_cast<size_t>(j)].name : std::string();
  };
  nlohmann::json j;
  j["file"] = a.sourcePath.empty() ? "default" : a.sourcePath;
  j["format"] = avatarFormatName(a.format);
  j["mapping"] = mappingMethodName(h.method);
  j["bones"] = nlohmann::json::object();
  for (int b = 0; b < kHumanBoneCount; ++b)
    if (h.bones[static_cast<size_t>(b)] >= 0)
      j["bones"][std::string(humanBoneName(static_cast<HumanBone>(b)))] =
          nodeName(h.bones[static_cast<size_t>(b)]);
  // Finger bones: mapped per hand, and how many of them hand tracking can drive.
  const FingerRig fingers = buildFingerRig(a.skeleton, h);
  int perSide[2] = {0, 0};
  for (int f = 0; f < kFingerCount; ++f)
    for (int s = 0; s < kFingerSegments; ++s)
      for (int side = 0; side < 2; ++side) perSide[side] += h.has(fingerHumanBone(side == 0, f, s)) ? 1 : 0;
  j["finger_bones"] = {{"mapped", perSide[0] + perSide[1]},
                       {"left", perSide[0]},
                       {"right", perSide[1]},
                       {"driven", fingers.mappedBones()},
                       {"notes", fingers.notes}};
  j["unmapped_required"] = nlohmann::json::array();
  for (HumanBone b : h.missingRequired) j["unmapped_required"].push_back(humanBoneName(b));
  j["joints"] = a.skinJointCount;
  j["nodes"] = a.skeleton.joints.size();
  j["triangles"] = a.mesh.triangleCount();
  j["forward"] = {h.forward.x, h.forward.y, h.forward.z};
  j["spine"] = nlohmann::json::array();
  for (const SpineBone& s : h.spine) {
    nlohmann::json v = nlohmann::json::array();
    for (int l = s.firstLevel; l < s.endLevel; ++l) v.push_back(vertebralJointName(l));
    std::string role;
    for (int b = 0; b < kHumanBoneCount; ++b)
      if (h.bones[static_cast<size_t>(b)] == s.joint) role = humanBoneName(static_cast<HumanBone>(b));
    j["spine"].push_back({{"node", nodeName(s.joint)}, {"bone", role}, {"vertebrae", v}});
  }
  j["first_person"] = {{"mode", a.firstPerson.mode},
                       {"head", nodeName(a.firstPerson.headJoint)},
                       {"removed_triangles", a.firstPerson.removedTriangles},
                       {"triangles", a.mesh.firstPersonIndices.size() / 3},
                       {"annotations", a.firstPerson.annotations}};
  j["notes"] = h.notes;
  j["warnings"] = report.warnings;
  j["vrm_motion"] = describeVrmMotion(a);
  return j;
}

// The IK body model built on the avatar, or why it cannot be built.
nlohmann::json describeBody(const AvatarAsset& a, const BodyModelOptions& options) {
  auto body = buildBodyModel(a, options);
  if (!body.ok()) return {{"error", body.error()}};
  const ik::Model& m = body->model;
  nlohmann::json j = {{"spine_model", body->spineModel},
                      {"scale", body->scale},
                      {"dofs", m.dofs},
                      {"joints", m.joints.size()},
                      {"equalities", m.equalities.size()},
                      {"inequalities", m.inequalities.size()},
                      {"mass_kg", m.total_mass},
                      {"tasks", nlohmann::json::array()}};
  for (const auto& t : m.tasks)
    j["tasks"].push_back(t.desc.name + " (level " + std::to_string(t.desc.level) + ")");
  j["spine_sites"] = nlohmann::json::array();
  for (const SpineBone& s : body->spineSites) {
    nlohmann::json v = nlohmann::json::array();
    for (int l = s.firstLevel; l < s.endLevel; ++l) v.push_back(vertebralJointName(l));
    j["spine_sites"].push_back(
        {{"node", a.skeleton.joints[static_cast<size_t>(s.joint)].name}, {"vertebrae", v}});
  }
  return j;
}

void printText(const nlohmann::json& j) {
  auto s = [](const nlohmann::json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); };
  std::printf("%s\n  format: %s, %s skin joints, %s nodes, %s triangles\n", s(j["file"]).c_str(),
              s(j["format"]).c_str(), s(j["joints"]).c_str(), s(j["nodes"]).c_str(),
              s(j["triangles"]).c_str());
  std::printf("  humanoid mapping: %s\n", s(j["mapping"]).c_str());
  for (const auto& [bone, node] : j["bones"].items())
    std::printf("    %-24s %s\n", bone.c_str(), s(node).c_str());
  const auto& fb = j["finger_bones"];
  std::printf("  finger bones: %s of 30 mapped (left %s, right %s); %s driven by hand tracking\n",
              s(fb["mapped"]).c_str(), s(fb["left"]).c_str(), s(fb["right"]).c_str(),
              s(fb["driven"]).c_str());
  for (const auto& n : fb["notes"]) std::printf("    %s\n", s(n).c_str());
  if (j["unmapped_required"].empty())
    std::printf("  all required bones mapped\n");
  else
    std::printf("  UNMAPPED required bones: %s\n", j["unmapped_required"].dump().c_str());
  std::printf("  spine (hips -> head), vertebral joints each bone stands for:\n");
  for (const auto& b : j["spine"]) {
    std::string v;
    for (const auto& x : b["vertebrae"]) v += (v.empty() ? "" : " ") + x.get<std::string>();
    std::printf("    %-28s %-11s %s\n", s(b["node"]).c_str(), s(b["bone"]).c_str(),
                v.empty() ? "(rigid)" : v.c_str());
  }
  const auto& fp = j["first_person"];
  std::printf("  first person: %s, head '%s', %s triangles hidden, %s drawn\n", s(fp["mode"]).c_str(),
              s(fp["head"]).c_str(), s(fp["removed_triangles"]).c_str(), s(fp["triangles"]).c_str());
  for (const auto& a : fp["annotations"]) std::printf("    annotation %s\n", s(a).c_str());
  const auto& vm = j["vrm_motion"];
  std::printf("  vrm motion: %s springs (%s joints, %s colliders), %zu expressions, look-at %s, %s morph channels\n",
              s(vm["springs"]).c_str(), s(vm["spring_joints"]).c_str(), s(vm["colliders"]).c_str(),
              vm["expressions"].size(), s(vm["look_at"]).c_str(), s(vm["morph_channels"]).c_str());
  for (const auto& w : vm["warnings"]) std::printf("    %s\n", s(w).c_str());
  const auto& body = j["body_model"];
  if (body.contains("error")) {
    std::printf("  body model: not built (%s)\n", s(body["error"]).c_str());
  } else {
    std::printf("  body model: %s joints, %s dofs, spine %s (%zu sites), %.1f kg, scale %.3f\n",
                s(body["joints"]).c_str(), s(body["dofs"]).c_str(), s(body["spine_model"]).c_str(),
                body["spine_sites"].size(), body["mass_kg"].get<double>(), body["scale"].get<double>());
  }
  for (const auto& n : j["notes"]) std::printf("  note: %s\n", s(n).c_str());
  for (const auto& w : j["warnings"]) std::printf("  warning: %s\n", s(w).c_str());
}

app::Args infoArgs() {
  app::Args args("embody avatar info",
                 "Loads an avatar (.gltf, .glb, .vrm, or 'default' for the built-in mannequin) and "
                 "reports its format, humanoid bone mapping, spine vertebrae and first-person mode.");
  args.positional("FILE", "avatar file, or 'default'");
  args.flag("json", "print one JSON object instead of text");
  args.flag("fingers", "with 'default': the mannequin with finger bones (as export-default --fingers)");
  args.option("bone-map", "FILE",
              "JSON object VRM-1.0-bone-name -> node name; its entries win over every other mapping");
  args.option("spine", "MODE",
              "spine sites of the body model: full (one per vertebra bone), simplified (8 sites), "
              "auto (full when the avatar has vertebra bones, else its own spine bones)",
              "auto");
  args.option("user-height", "METRES", "scale the body model to this user height");
  args.option("profile", "FILE", "calibration profile to read (written by 'embody avatar calibrate')");
  return args;
}

// A height or span option within calibration's limits; throws std::invalid_argument naming it.
std::optional<double> metresOption(const app::Args& args, const std::string& name) {
  if (!args.has(name)) return std::nullopt;
  const double m = args.number(name);
  if (!plausibleBodyHeight(m)) throw std::invalid_argument("--" + name + " must be 0.5 .. 2.6 m");
  return m;
}

int runInfo(app::Argv argv) {
  app::Args args = infoArgs();
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);
  BodyModelOptions bodyOptions;
  if (!parseSpineMode(args.get("spine"), bodyOptions.spine)) return app::usageError("--spine must be auto, full or simplified");
  std::optional<double> userHeight;
  try {
    userHeight = metresOption(args, "user-height");
  } catch (const std::invalid_argument& e) {
    return app::usageError(e.what());
  }
  GltfLoadReport report;
  Result<AvatarAsset> asset = Error{""};
  if (args.get("FILE") == "default") {
    asset = buildDefaultAvatar(DefaultAvatarOptions{.fingers = args.has("fingers")});
    if (args.has("bone-map")) {
      auto text = readBoneMapFile(args.get("bone-map"));
      if (!text.ok()) {
        std::fprintf(stderr, "error: %s\n", text.error().c_str());
        return 1;
      }
      if (auto s = prepareAvatar(asset.value(), text.value()); !s.ok()) asset = Error{s.error()};
    }
  } else if (app::isBvhPath(args.get("FILE"))) {
    asset = app::loadAvatarArg(args.get("FILE"), args.get("bone-map"));  // the clip's skeleton
  } else {
    AvatarLoadOptions options;
    options.boneMapFile = args.get("bone-map");
    asset = loadAvatarFile(args.get("FILE"), options, &report);
  }
  if (!asset.ok()) {
    std::fprintf(stderr, "error: %s\n", asset.error().c_str());
    return 1;
  }
  auto j = describe(asset.value(), report);
  if (userHeight) {
    CalibrationInput in;
    in.userHeight = userHeight;
    auto p = calibrate(asset.value(), in);
    if (!p.ok()) {
      std::fprintf(stderr, "error: %s\n", p.error().c_str());
      return 1;
    }
    bodyOptions.scale = p->scale;
  } else if (args.has("profile")) {
    auto p = loadProfile(args.get("profile"));
    if (!p.ok()) {
      std::fprintf(stderr, "error: %s\n", p.error().c_str());
      return 1;
    }
    bodyOptions.scale = p->scale;
  }
  j["body_model"] = describeBody(asset.value(), bodyOptions);
  if (args.has("json"))
    std::printf("%s\n", j.dump(2).c_str());
  else
    printText(j);
  return 0;
}

app::Args calibrateArgs() {
  app::Args args("embody avatar calibrate",
                 "Scales the avatar to the user and writes the calibration profile (JSON).");
  args.positional("FILE", "avatar file, or 'default'");
  args.option("user-height", "METRES", "the user's height");
  args.option("eye-height", "METRES",
              "the user's eye height (e.g. the HMD at calibration), when the height is unknown");
  args.option("arm-span", "METRES", "fingertip to fingertip (stored, not applied)");
  args.option("profile", "FILE", "where to write the profile");
  args.option("bone-map", "FILE", "JSON bone map, as for info");
  return args;
}

int runCalibrate(app::Argv argv) {
  app::Args args = calibrateArgs();
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);
  if (!args.has("profile")) return app::usageError("--profile FILE is required");
  if (!args.has("user-height") && !args.has("eye-height")) return app::usageError("--user-height or --eye-height is required");
  CalibrationInput in;
  try {
    in.userHeight = metresOption(args, "user-height");
    in.armSpan = metresOption(args, "arm-span");
    if (args.has("eye-height")) {
      in.eyeHeight = args.number("eye-height");
      if (!plausibleBodyHeight(*in.eyeHeight / kEyeHeightRatio))
        throw std::invalid_argument("--eye-height must be that of a 0.5 .. 2.6 m person");
    }
  } catch (const std::invalid_argument& e) {
    return app::usageError(e.what());
  }
  Result<AvatarAsset> asset = Error{""};
  if (args.get("FILE") == "default") {
    asset = buildDefaultAvatar();
  } else {
    asset = app::loadAvatarArg(args.get("FILE"), args.get("bone-map"));
  }
  if (!asset.ok()) {
    std::fprintf(stderr, "error: %s\n", asset.error().c_str());
    return 1;
  }
  auto p = calibrate(asset.value(), in);
  if (!p.ok()) {
    std::fprintf(stderr, "error: %s\n", p.error().c_str());
    return 1;
  }
  if (auto s = saveProfile(p.value(), args.get("profile")); !s.ok()) {
    std::fprintf(stderr, "error: %s\n", s.error().c_str());
    return 1;
  }
  std::printf("user %.3f m, avatar %.3f m: scale %.4f; wrote %s\n", p->userHeight, p->avatarHeight, p->scale,
              args.get("profile").c_str());
  return 0;
}

app::Args exportDefaultArgs() {
  app::Args args("embody avatar export-default",
                 "Writes the built-in mannequin as a standard glTF 2.0 binary (GLB).");
  args.positional("FILE", "output .glb path");
  args.flag("fingers",
            "add finger bones (thumb/index/middle/ring/pinky 1..3 per hand, the 30 humanoid finger bones) "
            "and skinned fingers, for hand tracking");
  return args;
}

int runExportDefault(app::Argv argv) {
  app::Args args = exportDefaultArgs();
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);
  const AvatarAsset a = buildDefaultAvatar(DefaultAvatarOptions{.fingers = args.has("fingers")});
  if (auto s = writeGlbFile(a, args.get("FILE")); !s.ok()) {
    std::fprintf(stderr, "error: %s\n", s.error().c_str());
    return 1;
  }
  std::printf("wrote %s: %zu joints, %zu triangles\n", args.get("FILE").c_str(), a.skeleton.joints.size(),
              a.mesh.triangleCount());
  return 0;
}

int runAvatar(app::Argv argv) {
  if (argv.empty()) return app::usageError("missing action: info, calibrate or export-default (see 'embody avatar --help')");
  if (argv[0] == "--help" || argv[0] == "-h") {  // every action's usage, with its options
    std::printf("embody avatar ACTION: info, calibrate or export-default\n\n%s\n%s\n%s", infoArgs().usage().c_str(),
                calibrateArgs().usage().c_str(), exportDefaultArgs().usage().c_str());
    return 0;
  }
  if (argv[0] == "info") return runInfo(argv.subspan(1));
  if (argv[0] == "export-default") return runExportDefault(argv.subspan(1));
  if (argv[0] == "calibrate") return runCalibrate(argv.subspan(1));
  return app::usageError("unknown action '" + argv[0] + "': info, calibrate or export-default");
}

}  // namespace

EMBODY_COMMAND("avatar", "inspect an avatar (info) or write the default mannequin (export-default)",
               runAvatar);
