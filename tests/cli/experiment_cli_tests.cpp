// `embody experiment balance | periodic | mocap | all` and isolated-spine --model paper end to end,
// with short settings: each writes summary.json whose numbers satisfy the invariants the paper's
// claims rest on (strict priority of the centre of mass, equalities to round-off, one torsion
// direction per region for the coupled spine), its CSV and its figures.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/cli_support.h"

using embody::test::outDir;
using embody::test::pngSize;
using embody::test::readJson;
using embody::test::runEmbody;
using embody::test::tumblingClip;
namespace fs = std::filesystem;

namespace {

int csvRows(const fs::path& p) {
  std::ifstream in(p);
  int rows = -1;  // the header
  for (std::string line; std::getline(in, line);) ++rows;
  return rows;
}

// Column `col` of every data row of a CSV.
std::vector<double> csvColumn(const fs::path& p, int col) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  std::vector<double> out;
  while (std::getline(in, line)) {
    size_t start = 0;
    for (int c = 0; c < col; ++c) start = line.find(',', start) + 1;
    out.push_back(std::stod(line.substr(start, line.find(',', start) - start)));
  }
  return out;
}

void checkCoupledSpine(const nlohmann::json& c) {
  CHECK(c["coupled"] == true);
  CHECK(c["equality_rows"].get<int>() > 0);
  CHECK(c["equality_residual_max"].get<double>() < 1e-9);
  CHECK(c["swing_spread"].get<double>() < 1e-9);
  CHECK(c["torsion_sign_changes_within_regions"] == 0);
}

}  // namespace

TEST_CASE("embody experiment balance: CoM over the left foot, coupled torsion one way per region",
          "[cli][experiment]") {
  const fs::path dir = outDir("experiment_balance");
  auto r = runEmbody("experiment balance --iterations 150 --frame-size 96 --out " + dir.string(), true);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  const auto s = readJson(dir / "summary.json");
  const auto& c = s["coupled"];
  const auto& u = s["uncoupled"];
  checkCoupledSpine(c);
  CHECK(c["spine_model"] == "simplified");
  CHECK(c["equality_rows"] == 12);  // 8 swing + 5 revolute joints, 3 free dofs per region
  CHECK(u["equality_rows"] == 0);
  for (const auto* v : {&c, &u}) {
    CHECK((*v)["com_error_m"].get<double>() < 1e-3);        // priority 0
    CHECK((*v)["left_foot_error_m"].get<double>() < 1e-3);  // priority 1
    CHECK((*v)["spine_sites"].size() == 8);
  }
  // The attractions are within reach once the body leans over its foot: every level is met.
  CHECK(c["right_toes_distance_m"].get<double>() < 0.01);
  CHECK(c["hand_distance_m"].get<double>() < 0.01);
  CHECK(c["head_orientation_error_deg"].get<double>() < 0.5);
  // The uncoupled spine twists both ways inside a region (fig. 10), the coupled one does not.
  CHECK(u["torsion_sign_changes_within_regions"].get<int>() > 0);
  CHECK(csvRows(dir / "coupled_iterations.csv") == 150);
  CHECK(csvRows(dir / "uncoupled_spine.csv") == 8);
  CHECK(csvRows(dir / "coupled_vertebrae.csv") == 24);  // fig. 10 per vertebra
  for (const char* png : {"fig10_torsion.png", "fig_balance_convergence.png", "fig9_coupled_view0.png",
                          "fig9_uncoupled_view1.png"})
    CHECK(pngSize(dir / png).first > 0);
  CHECK(pngSize(dir / "fig9_coupled_view0.png") == std::make_pair(96u, 96u));
}

TEST_CASE("embody experiment periodic: per-cycle drift from cycle 1, equalities hold every cycle",
          "[cli][experiment]") {
  const fs::path dir = outDir("experiment_periodic");
  auto r =
      runEmbody("experiment periodic --cycles 12 --steps 16 --frame-size 64 --out " + dir.string(), true);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  const auto s = readJson(dir / "summary.json");
  checkCoupledSpine(s["coupled"]);
  CHECK(s["setup"]["cycles"] == 12);
  CHECK(s["coupled"]["iterations"] == 12 * 16 * 3);  // 3 iterations per target by default
  for (const char* v : {"coupled", "uncoupled"}) {
    const fs::path csv = dir / (std::string(v) + "_cycles.csv");
    REQUIRE(csvRows(csv) == 12);
    CHECK(csvColumn(csv, 1).front() == 0.0);  // drift of cycle 1 from itself
    for (double com : csvColumn(csv, 5)) CHECK(com < 1e-3);
    CHECK(s[v]["final_drift_rad"].get<double>() == Approx(csvColumn(csv, 1).back()));
  }
  for (double e : csvColumn(dir / "coupled_cycles.csv", 10)) CHECK(e < 1e-9);
  for (double t : csvColumn(dir / "coupled_cycles.csv", 8)) CHECK(t == 0.0);
  for (const char* png :
       {"fig11_drift.png", "fig_periodic_spine.png", "fig11_coupled_cycle0001.png",
        "fig11_coupled_cycle0010.png", "fig11_uncoupled_cycle0012.png", "fig11_coupled.png"})
    CHECK(pngSize(dir / png).first > 0);
}

TEST_CASE("embody experiment mocap: BVH markers drive the body, the coupled spine stays proportional",
          "[cli][experiment]") {
  const fs::path dir = outDir("experiment_mocap");
  const std::string clip = std::string(embody::test::kSourceDir) + "/tests/tracking/fixtures/cmu.bvh";
  auto r = runEmbody("experiment mocap --motion " + clip + " --frame-size 64 --out " + dir.string(), true);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  const auto s = readJson(dir / "summary.json");
  const auto& c = s["coupled"];
  checkCoupledSpine(c);
  CHECK(c["equality_residual_max_over_frames"].get<double>() < 1e-9);
  CHECK(c["torsion_sign_changes_within_regions_max"] == 0);
  CHECK(c["swing_spread_mean"].get<double>() < 1e-9);
  CHECK(c["markers"].get<int>() >= 15);
  CHECK(c["orientation_groups"].get<int>() >= 3);
  const int frames = s["setup"]["frames"].get<int>();
  CHECK(frames >= 3);
  for (const char* v : {"coupled", "uncoupled"}) {
    CHECK(csvRows(dir / (std::string(v) + "_frames.csv")) == frames);
    // The clip is scaled to the mannequin's height but keeps its own proportions: centimetres, not metres.
    CHECK(s[v]["marker_error_mean_m"].get<double>() < 0.08);
  }
  CHECK(pngSize(dir / "fig_mocap.png").first > 0);
  CHECK(pngSize(dir / "fig_mocap_postures.png").first > 0);
}

TEST_CASE("embody experiment isolated-spine --model paper: 32 equality rows, the same coupled invariants",
          "[cli][experiment]") {
  const fs::path dir = outDir("experiment_isolated_paper");
  auto r = runEmbody(
      "experiment isolated-spine --model paper --iterations 40 --no-plots --out " + dir.string(), true);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  const auto s = readJson(dir / "summary.json");
  CHECK(s["setup"]["model"] == "paper");
  CHECK(s["coupled"]["equality_rows"] == 32);
  CHECK(s["coupled"]["swing_spread"].get<double>() < 1e-9);
  CHECK(s["coupled"]["torsion_sign_changes_within_regions"] == 0);
  CHECK(s["coupled"]["final_orientation_error_deg"].get<double>() < 1e-6);
}

TEST_CASE("embody experiment all: every experiment and report.md with the claims table",
          "[cli][experiment]") {
  const fs::path dir = outDir("experiment_all");
  const std::string clip = std::string(embody::test::kSourceDir) + "/tests/tracking/fixtures/cmu.bvh";
  auto r = runEmbody(
      "experiment all --iterations 40 --cycles 3 --steps 8 --iterations-per-frame 5 --no-frames "
      "--motion " +
          clip + " --out " + dir.string(),
      true);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  for (const char* sub : {"isolated-spine", "isolated-spine-paper", "balance", "periodic", "mocap"})
    CHECK(fs::exists(dir / sub / "summary.json"));
  std::ifstream in(dir / "report.md");
  const std::string md((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  CHECK(md.find("| the paper's claim |") != std::string::npos);
  CHECK(md.find("5.2.1") != std::string::npos);
  CHECK(md.find("5.2.3") != std::string::npos);
  CHECK(md.find("balance/fig10_torsion.png") != std::string::npos);
  // The equalities row is measured, not asserted: it must agree.
  CHECK(md.find("the coupling equalities hold exactly (infinite priority) | largest abs(Cq - b)") !=
        std::string::npos);
  CHECK(md.find("rad | agree | the equalities are folded") != std::string::npos);
}

TEST_CASE("embody experiment: bad options and files fail with one clear line", "[cli][experiment]") {
  const fs::path dir = outDir("experiment_bad");
  CHECK(runEmbody("experiment walk --out " + dir.string()).exitCode == 2);
  CHECK(runEmbody("experiment balance").exitCode == 2);  // no --out
  CHECK(runEmbody("experiment periodic --cycles 0 --out " + dir.string()).exitCode == 2);
  CHECK(runEmbody("experiment balance --spine twisted --out " + dir.string()).exitCode == 2);
  CHECK(runEmbody("experiment balance --frame-size 8 --out " + dir.string()).exitCode == 2);
  auto missing = runEmbody("experiment mocap --motion /nonexistent.bvh --out " + dir.string(), true);
  CHECK(missing.exitCode == 1);
  CHECK(missing.output.find("error:") != std::string::npos);
}

TEST_CASE("embody experiment mocap takes the --bvh-* overrides: a clip whose axes must be given", "[cli][experiment]") {
  // The CMU fixture spun about one root axis over 48 frames: no direction keeps the head above
  // the feet. Without the axes the import stops and names --bvh-up; given them, the run scores.
  const fs::path dir = outDir("experiment_mocap_overrides");
  fs::create_directories(dir);
  const std::string clip = tumblingClip("cmu.bvh", dir / "tumble.bvh");
  const std::string common = " --frames 4 --iterations-per-frame 5 --no-frames --no-plots --out ";
  auto r = runEmbody("experiment mocap --motion " + clip + common + (dir / "measured").string(), true);
  CHECK(r.exitCode == 1);
  CHECK(r.output.find("--bvh-up") != std::string::npos);
  r = runEmbody("experiment mocap --motion " + clip + " --bvh-up +Y --bvh-forward +Z" + common + (dir / "given").string(), true);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  CHECK(readJson(dir / "given" / "summary.json")["setup"]["frames"] == 4);
  r = runEmbody("experiment mocap --motion " + clip + " --bvh-up sideways" + common + (dir / "bad").string(), true);
  CHECK(r.exitCode == 2);
}
