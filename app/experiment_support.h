#pragma once
// What the full-body experiments of `embody experiment` (Raunhardt & Boulic 2008, §5.2) share:
// the default mannequin's body model with an experiment's own tasks, the spine read back from it,
// output files, gnuplot, and rendered postures through the project's offscreen renderer.
#include <Eigen/Core>
#include <initializer_list>
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/args.h"
#include "avatar/avatar_asset.h"
#include "avatar/body/body_model.h"
#include "core/result.h"
#include "ik/solver.h"
#include "ik/spine/spine_analysis.h"
#include "ik/spine/spine_description.h"

namespace embody::engine {
class Instance;
class Device;
class AvatarRenderer;
}  // namespace embody::engine

namespace embody::app::experiment {

namespace fs = std::filesystem;

// The body model of avatar/body with the experiment's tasks in place of the runtime's, and the
// spine sites as ik/spine sees them (so spine_analysis reads swing and torsion per site).
struct ExperimentBody {
  avatar::BodyModel body;
  ik::spine::SpineDescription spine;   // the description the sites come from
  ik::spine::SpineJoints spineJoints;  // per site: swing / revolute (coupled) or ball (uncoupled)
  bool coupled = true;
  int freeDofs = 0;  // dofs minus the rank of the equality rows
};

// Adds the experiment's tasks to a builder that already holds the body's joints and rows.
using TaskAdder = std::function<void(ik::ModelBuilder&, const avatar::BodyModel&)>;

// Sets task targets (and on/off switches) and keeps the first error the solver reports, so an
// experiment checks once after a batch of targets instead of at every call.
struct Targets {
  ik::Data& data;
  std::string error;
  template <class T>
  void set(ik::TaskId task, const T& value) {
    if (auto s = data.setTarget(task, value); !s && error.empty()) error = s.error();
  }
  void enable(ik::TaskId task, bool on) {
    if (auto s = data.setEnabled(task, on); !s && error.empty()) error = s.error();
  }
};

// Builds avatar/body's model for `asset` (addTasks off), then rebuilds it with `addTasks`' tasks.
Result<ExperimentBody> buildExperimentBody(const avatar::AvatarAsset& asset, avatar::SpineMode spine,
                                           bool coupled, const TaskAdder& addTasks);

// The IK joint that drives a humanoid bone of the asset, or -1.
ik::JointId ikJointOf(const ExperimentBody& body, const avatar::AvatarAsset& asset, avatar::HumanBone bone);

// Adds one task on `joint` at `level` (offset in the joint's frame); its id.
ik::TaskId addExperimentTask(ik::ModelBuilder& builder, const char* name, ik::TaskType type, ik::JointId joint,
                             int level, const Eigen::Vector3d& offset = Eigen::Vector3d::Zero());

// World rest frame (q = neutral) of an IK joint.
Eigen::Isometry3d restFrame(const ik::Model& model, ik::JointId joint);

// max |C q - b| over the equality rows (0 without rows).
double equalityResidual(const ik::Model& model, const Eigen::VectorXd& q);

// Spine shape read back from a solved configuration.
struct SpineShape {
  std::vector<ik::spine::SiteMotion> motion;  // per site
  double swingSpread = 0.0;
  int torsionChangesWithin = 0;
  int torsionChangesBetween = 0;
  double maxNormalisedSwing = 0.0;  // largest |swing component / its limit| over the sites
};
SpineShape spineShape(const ExperimentBody& body, const Eigen::VectorXd& q);

// Per-site CSV: index, site, region, s_x, s_y, torsion (degrees), s_x and s_y over their limits.
std::string spineCsv(const ExperimentBody& body, const SpineShape& shape);

// Per-vertebra CSV: index, vertebra, level, region, torsion (degrees; ik::spine::vertebraTorsion).
std::string vertebraCsv(const ExperimentBody& body, const SpineShape& shape);

// The JSON every experiment reports per variant about the body and its spine.
nlohmann::json bodySummary(const ExperimentBody& body, const SpineShape& shape, const Eigen::VectorXd& q);

bool writeFile(const fs::path& path, const std::string& text);

// The parts of an experiment's plots.gp that every one repeats. The header: what wrote it, CSV
// input, a PNG terminal (`terminal`: e.g. "size 1200,480").
std::string gnuplotHeader(const std::string& experiment, const std::string& terminal);
// A figure's first lines: its PNG, and a multiplot of `layout` ("rows,columns") under `title`.
std::string multiplotFigure(const std::string& png, const std::string& layout, const std::string& title);
// One `plot` of the coupled and the uncoupled run's <table>.csv (blue, red) with the same columns
// and style: runsPlot("frames", "1:2", "linespoints lw 2").
std::string runsPlot(const std::string& table, const std::string& columns, const std::string& style);
// Panels of a multiplot, each its y label and title, then runsPlot(table, columns, style).
struct RunsPanel {
  const char* ylabel;
  const char* title;
  const char* table;
  const char* columns;
  const char* style;
};
std::string runsPanels(std::initializer_list<RunsPanel> panels);
// Writes `script` as DIR/NAME and runs gnuplot on it in DIR; "" on success, else the error.
std::string runGnuplot(const fs::path& dir, const std::string& name, const std::string& script);

// Renders solved bodies of the default mannequin (offscreen, lavapipe on CI) to PNG.
class PostureRenderer {
 public:
  static Result<std::unique_ptr<PostureRenderer>> create(const avatar::AvatarAsset& asset, int width,
                                                         int height);
  ~PostureRenderer();
  // `data` must hold the configuration; kinematics is run here. yaw 0 = from the front.
  Result<avatar::Image> render(const ExperimentBody& body, ik::Data& data, float yaw, float pitch = 0.12f);

 private:
  PostureRenderer() = default;
  const avatar::AvatarAsset* asset_ = nullptr;
  std::unique_ptr<engine::Instance> instance_;
  std::unique_ptr<engine::Device> device_;
  std::unique_ptr<engine::AvatarRenderer> renderer_;
  avatar::SkeletonPose pose_;
};

// Renders each configuration of `qs` from each yaw, writes NAME_<label>_<k>.png and a contact
// sheet SHEET; returns the files written ("" error) or the error.
struct PostureShot {
  std::string file;   // PNG name in the output folder
  std::string label;  // e.g. "coupled, cycle 10"
};
Result<std::vector<PostureShot>> renderPostures(
    PostureRenderer& renderer, const fs::path& out,
    const std::vector<std::pair<const ExperimentBody*, Eigen::VectorXd>>& poses,
    const std::vector<std::string>& names, const std::vector<float>& yaws, const std::string& sheet);

// The options every full-body experiment shares, and reading them.
struct CommonOptions {
  fs::path out;
  bool plots = true;
  bool frames = true;
  int frameSize = 320;
};
void addCommonOptions(Args& args);
CommonOptions readCommonOptions(const Args& args);

// Prints the error and returns 1; creates the folder.
int fail(const std::string& message);
bool makeFolder(const fs::path& dir, std::string& error);

}  // namespace embody::app::experiment
