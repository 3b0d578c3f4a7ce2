// embody experiment NAME --out DIR: reproducible experiments that write CSV, summary.json and
// PNG plots (rendered by gnuplot from the CSV with a script written next to them, so a person can
// re-plot or restyle them) and, where the paper shows postures, rendered frames. Experiments
// (Raunhardt & Boulic 2008; app/experiments.h):
//   isolated-spine  §5.1: the 24-vertebra spine alone, coupled vs uncoupled
//   balance         §5.2.1: standing on one foot, right leg back, hands forward
//   periodic        §5.2.2: a figure-eight with both hands for many cycles
//   mocap           §5.2.3: BVH markers drive the mannequin
//   all             all four (§5.1 on the default and the paper's layout) and report.md
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "app/args.h"
#include "app/bvh_options.h"
#include "app/cli.h"
#include "app/experiments.h"

namespace {

using namespace embody;
using namespace embody::app::experiment;
namespace fs = std::filesystem;

// The clip `mocap` uses without --motion: a 4-frame walk written for the BVH tests (no third-party data).
constexpr const char* kDefaultMotion = "tests/tracking/fixtures/cmu.bvh";

int intOption(const app::Args& args, const char* name, int fallback, int lo, int hi) {
  if (!args.has(name)) return fallback;
  const int v = args.integer(name);
  if (v < lo || v > hi)
    throw std::invalid_argument("--" + std::string(name) + " must be in " + std::to_string(lo) + " .. " +
                                std::to_string(hi));
  return v;
}

std::string spineOption(const app::Args& args, const char* fallback) {
  if (!args.has("spine")) return fallback;
  const std::string s = args.get("spine");
  avatar::SpineMode mode;
  if (!spineModeOf(s, mode)) throw std::invalid_argument("--spine must be full or simplified");
  return s;
}

// Every experiment's options from the command line; throws std::invalid_argument on bad values.
struct AllOptions {
  IsolatedOptions isolated;
  BalanceOptions balance;
  PeriodicOptions periodic;
  MocapOptions mocap;
};

AllOptions readOptions(const app::Args& args, std::string& loadError) {
  AllOptions a;
  const CommonOptions common = readCommonOptions(args);
  a.isolated.common = a.balance.common = a.periodic.common = a.mocap.common = common;
  a.isolated.experiment.iterations = intOption(args, "iterations", 100, 1, 100000);
  a.isolated.experiment.pull = args.number("pull");
  a.isolated.experiment.axis_coupling = args.has("axis-coupling");
  a.balance.iterations = intOption(args, "iterations", 300, 1, 100000);
  a.balance.spine = spineOption(args, "simplified");
  a.periodic.cycles = intOption(args, "cycles", 2000, 1, 1000000);
  a.periodic.stepsPerCycle = intOption(args, "steps", 32, 4, 10000);
  a.periodic.iterationsPerStep = intOption(args, "iterations-per-step", 3, 1, 1000);
  a.periodic.spine = spineOption(args, "simplified");
  a.mocap.motion = args.has("motion") ? args.get("motion") : kDefaultMotion;
  a.mocap.iterationsPerFrame = intOption(args, "iterations-per-frame", 20, 1, 10000);
  a.mocap.maxFrames = intOption(args, "frames", 0, 0, 1000000);
  a.mocap.spine = spineOption(args, "full");
  auto bvh = app::bvhBodyOptions(app::readBvhOptions(args));
  if (!bvh) loadError = bvh.error();
  else a.mocap.bvh = std::move(*bvh);
  auto model = ik::spine::loadSpineModel(args.get("model"));
  if (!model)
    loadError = model.error();
  else
    a.isolated.model = std::move(*model);
  return a;
}

// `all`: every experiment into its own folder under --out, then report.md.
int runAll(AllOptions a) {
  const fs::path out = a.isolated.common.out;
  nlohmann::json isolated, paper, balance, periodic, mocap;
  a.isolated.common.out = out / "isolated-spine";
  if (int rc = runIsolatedSpine(a.isolated, isolated); rc != 0) return rc;
  a.isolated.common.out = out / "isolated-spine-paper";
  a.isolated.model = ik::spine::paperSpine();
  if (int rc = runIsolatedSpine(a.isolated, paper); rc != 0) return rc;
  a.balance.common.out = out / "balance";
  if (int rc = runBalance(a.balance, balance); rc != 0) return rc;
  a.periodic.common.out = out / "periodic";
  if (int rc = runPeriodic(a.periodic, periodic); rc != 0) return rc;
  a.mocap.common.out = out / "mocap";
  if (int rc = runMocap(a.mocap, mocap); rc != 0) return rc;
  if (!writeFile(out / "report.md", reportMarkdown(isolated, paper, balance, periodic, mocap)))
    return fail("cannot write " + (out / "report.md").string());
  std::printf("wrote %s\n", (out / "report.md").string().c_str());
  return 0;
}

int runExperiment(app::Argv argv) {
  app::Args args(
      "embody experiment",
      "Runs a reproducible experiment of Raunhardt & Boulic 2008, coupled vs uncoupled spine, and writes "
      "CSV, summary.json, gnuplot figures and rendered postures.\n"
      "  isolated-spine (§5.1): the spine alone; the head's orientation kept while the neck is pulled "
      "sideways.\n"
      "  balance (§5.2.1): the mannequin on its left foot, right toes back, hands forward, head level.\n"
      "  periodic (§5.2.2): both hands on a figure-eight, feet and centre of mass held, for --cycles "
      "cycles.\n"
      "  mocap (§5.2.3): marker positions from a BVH clip drive the mannequin.\n"
      "  all: the four (§5.1 on the default and the paper's layout) and report.md.");
  args.positional("name", "isolated-spine | balance | periodic | mocap | all");
  addCommonOptions(args);
  args.option("model", "full|simplified|paper|FILE", "isolated-spine: spine model", "full");
  args.option("iterations", "N", "isolated-spine (100) and balance (300): solver iterations per run");
  args.option("pull", "METRES", "isolated-spine: how far the neck target moves to the character's left",
              "0.12");
  args.flag("axis-coupling", "isolated-spine: add the cross-axis rows to the coupled model");
  args.option("spine", "full|simplified",
              "balance, periodic (simplified) and mocap (full): the mannequin's spine");
  args.option("cycles", "N", "periodic: figure-eight cycles (2000)");
  args.option("steps", "N", "periodic: targets per cycle (32)");
  args.option("iterations-per-step", "N", "periodic: solver iterations per target (3)");
  args.option("motion", "FILE.bvh",
              std::string("mocap: the clip (") + kDefaultMotion + ", run from the source tree)");
  args.option("iterations-per-frame", "N", "mocap: solver iterations per clip frame (20)");
  app::declareBvhOptions(args);  // mocap: the clip's import overrides
  args.option("frames", "N", "mocap: at most this many clip frames (0 = all)");
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);
  const std::string name = args.get("name");
  if (name != "isolated-spine" && name != "balance" && name != "periodic" && name != "mocap" && name != "all")
    return app::usageError("unknown experiment '" + name +
                           "' (expected: isolated-spine, balance, periodic, mocap, all)");
  if (args.get("out").empty()) return app::usageError("--out DIR is required");
  AllOptions a;
  std::string loadError;
  try {
    a = readOptions(args, loadError);
  } catch (const std::invalid_argument& e) {
    return app::usageError(e.what());
  }
  if (!loadError.empty()) return fail(loadError);
  nlohmann::json summary;
  if (name == "isolated-spine") return runIsolatedSpine(a.isolated, summary);
  if (name == "balance") return runBalance(a.balance, summary);
  if (name == "periodic") return runPeriodic(a.periodic, summary);
  if (name == "mocap") return runMocap(a.mocap, summary);
  return runAll(std::move(a));
}

}  // namespace

EMBODY_COMMAND(
    "experiment",
    "run a paper experiment (isolated-spine, balance, periodic, mocap, all): CSV, summary.json, figures",
    runExperiment);
