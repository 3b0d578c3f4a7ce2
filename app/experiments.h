#pragma once
// The experiments of `embody experiment` (Raunhardt & Boulic 2008): each runs coupled vs
// uncoupled with fixed iteration counts, writes CSV, summary.json, gnuplot figures and (where
// the paper shows postures) rendered frames into its folder, and returns its summary.
//   isolated-spine  §5.1: the spine alone (app/cmd_experiment.cpp, ik/spine/isolated_experiment.h)
//   balance         §5.2.1: standing on the left foot, right leg back, hands forward, head level
//   periodic        §5.2.2: both hands on a figure-eight for many cycles; drift per cycle
//   mocap           §5.2.3: markers from a BVH clip drive the body
#include <nlohmann/json.hpp>
#include <string>

#include "app/experiment_support.h"
#include "avatar/bvh/bvh_body.h"
#include "ik/spine/isolated_experiment.h"

namespace embody::app::experiment {

struct IsolatedOptions {
  CommonOptions common;
  ik::spine::SpineDescription model;  // full, simplified, paper or a file
  ik::spine::ExperimentOptions experiment;
};

struct BalanceOptions {
  CommonOptions common;
  int iterations = 300;
  std::string spine = "simplified";  // full | simplified
};

struct PeriodicOptions {
  CommonOptions common;
  int cycles = 2000;
  int stepsPerCycle = 32;      // targets per figure-eight
  int iterationsPerStep = 3;   // solver iterations per target (warm start from the last)
  int settleIterations = 100;  // before cycle 1, on the first target
  std::string spine = "simplified";
};

struct MocapOptions {
  CommonOptions common;
  std::string motion;  // BVH file ("" = the project fixture tests/tracking/fixtures/cmu.bvh)
  int iterationsPerFrame = 20;
  int settleIterations = 100;  // on the first frame
  int maxFrames = 0;           // 0 = every frame of the clip
  std::string spine = "full";
  avatar::BvhBodyOptions bvh;  // --bvh-up, --bvh-forward, --bvh-bone-map
};

// Each returns the process exit code (0, 1 runtime error) and fills `summary`.
int runIsolatedSpine(const IsolatedOptions& options, nlohmann::json& summary);
int runBalance(const BalanceOptions& options, nlohmann::json& summary);
int runPeriodic(const PeriodicOptions& options, nlohmann::json& summary);
int runMocap(const MocapOptions& options, nlohmann::json& summary);

// `embody experiment all`: the report of every experiment's results beside the paper's claims.
// `isolated` and `paperIsolated`: §5.1 on the default and on the paper's layout.
std::string reportMarkdown(const nlohmann::json& isolated, const nlohmann::json& paperIsolated,
                           const nlohmann::json& balance, const nlohmann::json& periodic,
                           const nlohmann::json& mocap);

// avatar/body's spine mode for "full" / "simplified"; false for anything else.
bool spineModeOf(const std::string& name, avatar::SpineMode& mode);

}  // namespace embody::app::experiment
