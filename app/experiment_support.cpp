// Shared pieces of the full-body experiments (see experiment_support.h).
#include "app/experiment_support.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "core/angles.h"
#include "app/render_job.h"
#include "engine/avatar_renderer.h"
#include "engine/device.h"
#include "engine/image_io.h"
#include "engine/instance.h"
#include "ik/spine/spine_model.h"

namespace embody::app::experiment {
namespace {

std::string shellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// The body's joints and rows in a fresh builder (joint-limit rows come back from the JointDescs).
ik::ModelBuilder builderFrom(const ik::Model& model) {
  ik::ModelBuilder b;
  for (const ik::Model::Joint& j : model.joints) b.addJoint(j.desc);
  for (const ik::EqualityRow& row : model.equalities) b.addEquality(row);
  for (const ik::InequalityRow& row : model.inequalities)
    if (row.kind == ik::InequalityKind::UserCoupling) b.addInequality(row);
  b.setUp(model.up);
  return b;
}

// The spine sites of a body as appendSpine would report them: per description site, the IK
// joints at that site's avatar bone (the last entry of spineSites is the head, not a site).
Result<ik::spine::SpineJoints> spineJointsOf(const avatar::BodyModel& body,
                                             const ik::spine::SpineDescription& d, bool coupled) {
  if (body.spineSites.size() != d.sites.size() + 1)
    return Error{"the body has " + std::to_string(body.spineSites.size()) + " spine sites, the " + d.name +
                 " spine " + std::to_string(d.sites.size())};
  ik::spine::SpineJoints out;
  out.coupled = coupled;
  out.ranges = ik::spine::siteRanges(d, coupled);
  out.sites.resize(d.sites.size());
  for (size_t k = 0; k < d.sites.size(); ++k)
    for (size_t j = 0; j < body.avatarJoint.size(); ++j) {
      if (body.avatarJoint[j] != body.spineSites[k].joint) continue;
      const ik::JointType type = body.model.joints[j].desc.type;
      auto& s = out.sites[k];
      (type == ik::JointType::Swing      ? s.swing
       : type == ik::JointType::Revolute ? s.revolute
                                         : s.ball) = static_cast<ik::JointId>(j);
    }
  out.equalities = body.spineEqualities;
  return out;
}

}  // namespace

Result<ExperimentBody> buildExperimentBody(const avatar::AvatarAsset& asset, avatar::SpineMode spine,
                                           bool coupled, const TaskAdder& addTasks) {
  avatar::BodyModelOptions o;
  o.spine = spine;
  o.coupledSpine = coupled;
  o.addTasks = false;
  auto built = avatar::buildBodyModel(asset, o);
  if (!built) return Error{built.error()};
  ExperimentBody out;
  out.body = std::move(*built);
  out.coupled = coupled;
  ik::ModelBuilder b = builderFrom(out.body.model);
  addTasks(b, out.body);
  auto model = b.build();
  if (!model) return Error{"experiment body: " + model.error()};
  out.body.model = std::move(*model);
  auto desc = ik::spine::loadSpineModel(out.body.spineModel == "simplified" ? "simplified" : "full");
  if (!desc) return Error{desc.error()};
  out.spine = std::move(*desc);
  auto joints = spineJointsOf(out.body, out.spine, coupled);
  if (!joints) return Error{joints.error()};
  out.spineJoints = std::move(*joints);
  const auto& m = out.body.model;
  out.freeDofs =
      m.dofs - (static_cast<int>(m.equalities.size()) - static_cast<int>(m.dependent_equalities.size()));
  return out;
}

ik::JointId ikJointOf(const ExperimentBody& body, const avatar::AvatarAsset& asset, avatar::HumanBone bone) {
  const int a = asset.humanoid.joint(bone);
  return a < 0 ? -1 : body.body.ikJointOfAvatar[static_cast<size_t>(a)];
}

ik::TaskId addExperimentTask(ik::ModelBuilder& builder, const char* name, ik::TaskType type, ik::JointId joint,
                             int level, const Eigen::Vector3d& offset) {
  ik::TaskDesc d;
  d.name = name;
  d.type = type;
  d.joint = joint;
  d.level = level;
  d.offset = offset;
  return builder.addTask(d);
}

Eigen::Isometry3d restFrame(const ik::Model& model, ik::JointId joint) {
  ik::Data data(model);
  ik::kinematics(model, data, false);
  return data.jointFrame(joint);
}

double equalityResidual(const ik::Model& model, const Eigen::VectorXd& q) {
  if (model.equality_matrix.rows() == 0) return 0.0;
  return (model.equality_matrix * q - model.equality_rhs).cwiseAbs().maxCoeff();
}

SpineShape spineShape(const ExperimentBody& body, const Eigen::VectorXd& q) {
  SpineShape s;
  s.motion = ik::spine::siteMotion(body.body.model, q, body.spineJoints);
  s.swingSpread = ik::spine::swingSpread(body.spine, body.spineJoints, s.motion);
  s.torsionChangesWithin = ik::spine::torsionSignChangesWithinRegions(body.spine, body.spineJoints, s.motion);
  s.torsionChangesBetween =
      ik::spine::torsionSignChangesBetweenRegions(body.spine, body.spineJoints, s.motion);
  s.maxNormalisedSwing = ik::spine::maxNormalisedSwing(body.spine, body.spineJoints, s.motion);
  return s;
}

std::string spineCsv(const ExperimentBody& body, const SpineShape& shape) {
  const ik::spine::SpineDescription& d = body.spine;
  std::string csv = "index,site,region,s_x_deg,s_y_deg,torsion_deg,s_x_norm,s_y_norm,carries_torsion\n";
  char line[256];
  for (size_t k = 0; k < d.sites.size(); ++k) {
    const ik::spine::SiteMotion& m = shape.motion[k];
    const Eigen::Vector3d& r = body.spineJoints.ranges[k];
    auto norm = [&](ik::spine::Component c, double v) {
      const double range = r[static_cast<int>(c)];
      if (range <= 0) return 0.0;
      return v / (v >= 0 ? ik::spine::upperLimit(d, c, range) : -ik::spine::lowerLimit(d, c, range));
    };
    const auto& sj = body.spineJoints.sites[k];
    std::snprintf(line, sizeof line, "%zu,%s,%s,%.6f,%.6f,%.6f,%.6f,%.6f,%d\n", k, d.sites[k].name.c_str(),
                  ik::spine::toString(d.sites[k].region), m.s_x / kDeg, m.s_y / kDeg, m.torsion / kDeg,
                  norm(ik::spine::Component::Flexion, m.s_x), norm(ik::spine::Component::Bending, m.s_y),
                  sj.ball >= 0 || sj.revolute >= 0 ? 1 : 0);
    csv += line;
  }
  return csv;
}

std::string vertebraCsv(const ExperimentBody& body, const SpineShape& shape) {
  const ik::spine::SpineDescription& d = body.spine;
  const std::vector<double> torsion = ik::spine::vertebraTorsion(d, body.spineJoints, shape.motion);
  std::string csv = "index,vertebra,level,region,torsion_deg\n";
  char line[160];
  for (size_t v = 0; v < d.vertebrae.size(); ++v) {
    std::snprintf(line, sizeof line, "%zu,%s,%s,%s,%.6f\n", v, d.vertebrae[v].name.c_str(), d.vertebrae[v].level.c_str(),
                  ik::spine::toString(d.vertebrae[v].region), torsion[v] / kDeg);
    csv += line;
  }
  return csv;
}

nlohmann::json bodySummary(const ExperimentBody& body, const SpineShape& shape, const Eigen::VectorXd& q) {
  nlohmann::json j;
  j["spine_model"] = body.spine.name;
  j["coupled"] = body.coupled;
  j["dofs"] = body.body.model.dofs;
  j["free_dofs"] = body.freeDofs;
  j["equality_rows"] = body.body.model.equalities.size();
  j["equality_residual_max"] = equalityResidual(body.body.model, q);
  j["swing_spread"] = shape.swingSpread;
  j["max_normalised_swing"] = shape.maxNormalisedSwing;
  j["torsion_sign_changes_within_regions"] = shape.torsionChangesWithin;
  j["torsion_sign_changes_between_regions"] = shape.torsionChangesBetween;
  nlohmann::json sites = nlohmann::json::array();
  for (size_t k = 0; k < shape.motion.size(); ++k) {
    const auto& sj = body.spineJoints.sites[k];
    sites.push_back({{"site", body.spine.sites[k].name},
                     {"region", ik::spine::toString(body.spine.sites[k].region)},
                     {"s_x_deg", shape.motion[k].s_x / kDeg},
                     {"s_y_deg", shape.motion[k].s_y / kDeg},
                     {"torsion_deg", shape.motion[k].torsion / kDeg},
                     {"carries_torsion", sj.ball >= 0 || sj.revolute >= 0}});
  }
  j["spine_sites"] = std::move(sites);
  return j;
}

bool writeFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  return static_cast<bool>(out);
}

std::string gnuplotHeader(const std::string& experiment, const std::string& terminal) {
  return "# Plots of `embody experiment " + experiment + "` (run: gnuplot plots.gp in this folder).\n" +
         "set datafile separator ','\nset terminal pngcairo " + terminal + " font 'Sans,11'\n";
}

std::string multiplotFigure(const std::string& png, const std::string& layout, const std::string& title) {
  return "set output '" + png + "'\nset multiplot layout " + layout + " title '" + title + "'\n";
}

std::string runsPlot(const std::string& table, const std::string& columns, const std::string& style) {
  const auto curve = [&](const char* run, const char* color) {
    return "'" + std::string(run) + "_" + table + ".csv' skip 1 using " + columns + " with " + style + " lc rgb '" +
           color + "' title '" + run + "'";
  };
  return "plot " + curve("coupled", "#1f77b4") + ", \\\n     " + curve("uncoupled", "#d62728") + "\n";
}

std::string runsPanels(std::initializer_list<RunsPanel> panels) {
  std::string out;
  for (const RunsPanel& p : panels)
    out += std::string("set ylabel '") + p.ylabel + "'\nset title '" + p.title + "'\n" + runsPlot(p.table, p.columns, p.style);
  return out;
}

std::string runGnuplot(const fs::path& dir, const std::string& name, const std::string& script) {
  if (!writeFile(dir / name, script)) return "cannot write " + (dir / name).string();
  if (std::system("command -v gnuplot > /dev/null 2>&1") != 0)
    return "gnuplot not found (install gnuplot-nox); the CSV files and " + name + " are in " + dir.string();
  const std::string cmd = "cd " + shellQuote(dir.string()) + " && gnuplot " + shellQuote(name);
  if (std::system(cmd.c_str()) != 0) return "gnuplot failed on " + (dir / name).string();
  return "";
}

Result<std::unique_ptr<PostureRenderer>> PostureRenderer::create(const avatar::AvatarAsset& asset, int width,
                                                                 int height) {
  std::unique_ptr<PostureRenderer> r(new PostureRenderer());
  r->asset_ = &asset;
  engine::InstanceOptions io;
  auto instance = engine::Instance::create(io);
  if (!instance) return Error{instance.error()};
  r->instance_ = std::make_unique<engine::Instance>(std::move(*instance));
  auto device = engine::Device::create(*r->instance_, "auto");
  if (!device) return Error{device.error()};
  r->device_ = std::move(*device);
  engine::AvatarRendererOptions ro;
  ro.width = static_cast<uint32_t>(width);
  ro.height = static_cast<uint32_t>(height);
  auto renderer = engine::AvatarRenderer::create(*r->device_, asset, ro);
  if (!renderer) return Error{renderer.error()};
  r->renderer_ = std::move(*renderer);
  return r;
}

PostureRenderer::~PostureRenderer() {
  renderer_.reset();  // before the device and the instance it was made from
  device_.reset();
}

Result<avatar::Image> PostureRenderer::render(const ExperimentBody& body, ik::Data& data, float yaw,
                                              float pitch) {
  ik::kinematics(body.body.model, data, false);
  avatar::retarget(body.body, *asset_, data, pose_);
  const engine::Camera camera = renderer_->orbitAround(pose_, yaw, pitch);
  engine::FrameOptions fo;
  return renderer_->render(pose_, camera, fo);
}

Result<std::vector<PostureShot>> renderPostures(
    PostureRenderer& renderer, const fs::path& out,
    const std::vector<std::pair<const ExperimentBody*, Eigen::VectorXd>>& poses,
    const std::vector<std::string>& names, const std::vector<float>& yaws, const std::string& sheet) {
  std::vector<PostureShot> shots;
  std::vector<avatar::Image> thumbs;
  for (size_t i = 0; i < poses.size(); ++i) {
    ik::Data data(poses[i].first->body.model);
    if (auto s = data.setConfiguration(poses[i].second); !s) return Error{s.error()};
    for (size_t v = 0; v < yaws.size(); ++v) {
      auto img = renderer.render(*poses[i].first, data, yaws[v]);
      if (!img) return Error{img.error()};
      const std::string file = names[i] + (yaws.size() > 1 ? "_view" + std::to_string(v) : "") + ".png";
      if (auto s = engine::writePng((out / file).string(), *img); !s) return Error{s.error()};
      shots.push_back({file, names[i]});
      thumbs.push_back(std::move(*img));
    }
  }
  if (!sheet.empty() && !thumbs.empty())
    if (auto s = engine::writePng((out / sheet).string(), contactSheet(thumbs)); !s) return Error{s.error()};
  return shots;
}

void addCommonOptions(Args& args) {
  args.option("out", "DIR", "folder for the results (created)");
  args.flag("no-plots", "write CSV and summary.json only (no gnuplot)");
  args.flag("no-frames", "do not render postures (no Vulkan device needed)");
  args.option("frame-size", "PIXELS", "size of the rendered posture frames (64 .. 2048)", "320");
}

CommonOptions readCommonOptions(const Args& args) {
  CommonOptions o;
  o.out = args.get("out");
  o.plots = !args.has("no-plots");
  o.frames = !args.has("no-frames");
  o.frameSize = args.integer("frame-size");
  if (o.frameSize < 64 || o.frameSize > 2048)
    throw std::invalid_argument("--frame-size must be in 64 .. 2048");
  return o;
}

int fail(const std::string& message) {
  std::fprintf(stderr, "error: %s\n", message.c_str());
  return 1;
}

bool makeFolder(const fs::path& dir, std::string& error) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) error = "cannot create " + dir.string() + ": " + ec.message();
  return !ec;
}

}  // namespace embody::app::experiment
