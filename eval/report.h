#pragma once
// What `embody eval` writes for one clip and tracker set (docs/eval.md): metrics.json, the
// per-frame and per-joint CSV files, gnuplot scripts and their PNGs, and the one-line table rows.
#include <filesystem>
#include <string>

#include "core/result.h"
#include "eval/clip_eval.h"

namespace embody::eval {

struct ReportOptions {
  std::string trackers;   // "3", "4", "6"
  int ikIterations = 0;
  bool plots = true;      // run gnuplot on the scripts (skipped with a note when it is absent)
};

// Writes metrics.json, frames.csv, joints.csv, errors.gp, joints.gp (and errors.png, joints.png
// through gnuplot) into `dir`. Returns notes (e.g. gnuplot missing) on success.
Result<std::vector<std::string>> writeReport(const ClipEval& e, const ReportOptions& o, const std::filesystem::path& dir);

// "MPJPE cm (mean / p95), hands, lower, MPJRE °, jitter" per method, for the terminal.
std::string methodTable(const ClipEval& e);

}  // namespace embody::eval
