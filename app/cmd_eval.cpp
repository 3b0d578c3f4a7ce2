// embody eval: the body scored against real motion capture (eval/, docs/eval.md). The avatar is
// the clip's own skeleton; only the chosen trackers reach the runtime; every joint of the solved
// body is set beside the clip's. One clip: a method table and the report files in --out. A
// folder, or several rates: every clip at every tracker set and rate, one table with a mean row
// per tracker set.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/args.h"
#include "app/bvh_options.h"
#include "app/eval_sheet.h"
#include "core/frame_rate.h"
#include "eval/clip_eval.h"
#include "eval/report.h"
#include "tracking/bvh_avatar.h"
#include "tracking/bvh_export.h"

namespace {

using namespace embody;
namespace fs = std::filesystem;

struct EvalJob {
  std::vector<fs::path> clips;
  bool folder = false;
  std::vector<eval::TrackerSet> sets;
  std::vector<double> rates{0.0};  // evaluation rates (0: the clip's own)
  bool tabled() const { return folder || rates.size() > 1; }
  eval::EvalOptions options;
  double bvhScale = 0.0;
  avatar::BvhBodyOptions bvhBody;  // --bvh-up, --bvh-forward, --bvh-bone-map
  fs::path out;
  bool plots = true;
  bool sheet = true;
  std::string device = "auto";
};

// One table row per (clip, tracker set, rate): MPJPE of each method and the coupled body's
// figures that issue #15's bars name, or why the clip was not scored.
struct Row {
  std::string clip, trackers, error;
  double fps = 0.0;
  std::array<double, 3> mpjpe{};
  std::array<double, eval::kGroupCount> coupled{};  // cm, per group
  double jitterRatio = 0.0, skating = 0.0, seconds = 0.0;
  int kneeReversed = 0, elbowReversed = 0, collapsed = 0;
};

// Runs one clip at one tracker set and rate (0: its own), writes its report into `dir`, fills `row`.
bool evaluateOne(const tracking::BvhAvatar& avatar, const EvalJob& job, eval::TrackerSet set, double fps, const fs::path& dir,
                 Row& row, bool verbose) {
  row.trackers = eval::trackerSetName(set);
  eval::EvalOptions o = job.options;
  o.trackers = set;
  o.fps = fps;
  o.keepPoses = job.sheet ? 12 : 0;
  const auto started = std::chrono::steady_clock::now();
  auto solved = tracking::SolvedMotionBvh::forBvhAvatar(avatar);
  auto e = eval::evaluateClip(avatar, o, &solved);
  if (!e) return row.error = e.error(), false;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return row.error = "cannot create " + dir.string() + ": " + ec.message(), false;
  if (o.fps > 0.0) solved.setFrameTime(1.0 / o.fps);
  if (auto s = solved.write((dir / "solved.bvh").string()); !s) return row.error = s.error(), false;
  eval::ReportOptions ro;
  ro.trackers = row.trackers;
  ro.ikIterations = o.ikIterations;
  ro.plots = job.plots;
  auto notes = eval::writeReport(*e, ro, dir);
  if (!notes) return row.error = notes.error(), false;
  if (job.sheet)
    if (auto s = app::writeEvalSheet(avatar, *e, dir / "contact_sheet.png", job.device); !s)
      notes->push_back("contact sheet not drawn: " + s.error());
  row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  row.fps = e->fps;
  for (size_t k = 0; k < e->runs.size() && k < row.mpjpe.size(); ++k) row.mpjpe[k] = 100.0 * e->runs[k].metrics.mpjpe[eval::kAll].mean;
  const eval::Metrics& m = e->runs[0].metrics;  // the coupled spine
  for (int g = 0; g < eval::kGroupCount; ++g) row.coupled[size_t(g)] = 100.0 * m.mpjpe[size_t(g)].mean;
  row.jitterRatio = m.clipJitter > 0.0 ? m.jitter / m.clipJitter : 0.0;
  row.skating = 100.0 * m.footSkating;
  row.kneeReversed = m.kneeReverseFrames;
  row.elbowReversed = m.elbowReverseFrames;
  row.collapsed = m.collapsedFrames;
  if (verbose) {
    std::printf("%s: %d frames at %.6g Hz, trackers %s, %d IK iterations a frame, %zu joints scored\n", e->clip.c_str(),
                e->frames, e->fps, row.trackers.c_str(), o.ikIterations, e->skeleton.groups[eval::kAll].size());
    std::printf("%s", eval::methodTable(*e).c_str());
    for (const auto& n : *notes) std::printf("note: %s\n", n.c_str());
    std::string wrote;  // what is there: the plots need gnuplot, the sheet can be turned off
    for (const char* f : {"metrics.json", "solved.bvh", "frames.csv", "joints.csv", "errors.png", "joints.png", "contact_sheet.png"})
      if (fs::exists(dir / f)) wrote += (wrote.empty() ? "" : ", ") + std::string(f);
    std::printf("wrote %s to %s (%.1f s)\n", wrote.c_str(), dir.c_str(), row.seconds);
  }
  return true;
}

void progressBar(size_t done, size_t total, const std::string& what) {
  const size_t width = 30, filled = total ? done * width / total : width;
  std::printf("\r[%s%s] %zu/%zu %-40.40s", std::string(filled, '#').c_str(), std::string(width - filled, ' ').c_str(), done,
              total, what.c_str());
  std::fflush(stdout);
}

std::string rateName(double fps) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", fps);
  return buf;
}

// The rows, then per tracker set the mean over its scored rows (every clip and rate): the
// figures docs/eval.md reports (jitter as a multiple of the clip's own; reversed and collapsed
// frames summed).
std::string table(const std::vector<Row>& rows, const std::vector<eval::TrackerSet>& sets) {
  std::string out =
      "| clip | trackers | fps | MPJPE cm coupled | uncoupled | naive | hands | head | upper | lower | root | "
      "jitter × clip | skating cm/s | reversed knee/elbow | collapsed |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  char buf[512];
  auto line = [&](const std::string& clip, const std::string& trackers, const std::string& fps, const Row& r) {
    std::snprintf(buf, sizeof buf, "| %s | %s | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.1f | %d/%d | %d |\n",
                  clip.c_str(), trackers.c_str(), fps.c_str(), r.mpjpe[0], r.mpjpe[1], r.mpjpe[2], r.coupled[eval::kHands],
                  r.coupled[eval::kHead], r.coupled[eval::kUpper], r.coupled[eval::kLower], r.coupled[eval::kRoot], r.jitterRatio,
                  r.skating, r.kneeReversed, r.elbowReversed, r.collapsed);
    out += buf;
  };
  for (const auto& r : rows) {
    if (!r.error.empty()) out += "| " + r.clip + " | " + r.trackers + " | | not scored: " + r.error + " | | | | | | | | | | | |\n";
    else line(r.clip, r.trackers, rateName(r.fps), r);
  }
  for (eval::TrackerSet set : sets) {
    Row mean;
    std::vector<double> rates;
    int n = 0;
    for (const auto& r : rows) {
      if (!r.error.empty() || r.trackers != eval::trackerSetName(set)) continue;
      ++n;
      for (size_t k = 0; k < mean.mpjpe.size(); ++k) mean.mpjpe[k] += r.mpjpe[k];
      for (size_t g = 0; g < mean.coupled.size(); ++g) mean.coupled[g] += r.coupled[g];
      mean.jitterRatio += r.jitterRatio, mean.skating += r.skating;
      mean.kneeReversed += r.kneeReversed, mean.elbowReversed += r.elbowReversed, mean.collapsed += r.collapsed;
      if (std::find(rates.begin(), rates.end(), r.fps) == rates.end()) rates.push_back(r.fps);
    }
    if (n < 2) continue;
    for (auto& v : mean.mpjpe) v /= n;
    for (auto& v : mean.coupled) v /= n;
    mean.jitterRatio /= n, mean.skating /= n;
    std::string fps;
    for (double f : rates) fps += (fps.empty() ? "" : ", ") + rateName(f);
    line("**mean of " + std::to_string(n) + "**", eval::trackerSetName(set), fps, mean);
  }
  return out;
}

int runJob(const EvalJob& job) {
  std::vector<Row> rows;
  const bool bar = job.tabled() && isatty(STDOUT_FILENO);
  const size_t total = job.clips.size() * job.sets.size() * job.rates.size();
  size_t done = 0;
  int failures = 0;
  for (const auto& clip : job.clips) {
    tracking::BvhTrackerOptions bo;
    bo.scale = job.bvhScale;
    bo.body = job.bvhBody;
    auto avatar = tracking::loadBvhAvatar(clip.string(), bo);
    // What the import repaired or doubted (root glitches, missing frames): on the terminal, as
    // well as in each metrics.json's notes.
    if (avatar)
      for (const auto& w : avatar->clip.warnings)  // the parser's name the file already
        std::fprintf(stderr, "warning: %s\n", (w.rfind(clip.string(), 0) == 0 ? w : clip.string() + ": " + w).c_str());
    for (eval::TrackerSet set : job.sets)
      for (double fps : job.rates) {
        Row row;
        row.clip = clip.filename().string();
        if (bar) progressBar(done, total, row.clip + " @" + eval::trackerSetName(set));
        fs::path dir = job.out;
        if (job.tabled()) {
          dir = job.out / clip.stem() / (std::string("trackers_") + eval::trackerSetName(set));
          if (job.rates.size() > 1) dir /= "fps_" + rateName(fps);
        }
        if (!avatar) row.error = avatar.error(), row.trackers = eval::trackerSetName(set);
        else evaluateOne(*avatar, job, set, fps, dir, row, !job.tabled());
        if (!row.error.empty()) {
          ++failures;
          if (!job.tabled()) return app::runtimeError(row.error);
        }
        rows.push_back(std::move(row));
        ++done;
      }
  }
  if (bar) progressBar(done, total, "done"), std::printf("\n");
  if (!job.tabled()) return 0;
  const std::string t = table(rows, job.sets);
  std::printf("%s", t.c_str());
  std::ofstream(job.out / "summary.md") << t;
  std::printf("wrote %s (and one folder of metrics per clip, tracker set%s)\n", (job.out / "summary.md").c_str(),
              job.rates.size() > 1 ? " and rate" : "");
  if (failures) std::fprintf(stderr, "error: %d of %zu clip runs were not scored (see the table)\n", failures, total);
  return failures ? 1 : 0;
}

// The rates of --fps ("90" or "60,90,120"): each 1 .. 1000 Hz, none twice.
std::vector<double> ratesOf(const app::Args& args) {
  const std::vector<double> rates = args.numbers("fps");
  for (size_t k = 0; k < rates.size(); ++k) {
    if (!(rates[k] >= kMinFps && rates[k] <= kMaxFps)) throw std::invalid_argument("--fps must be 1 .. 1000 Hz (got " + rateName(rates[k]) + ")");
    if (std::find(rates.begin(), rates.begin() + long(k), rates[k]) != rates.begin() + long(k))
      throw std::invalid_argument("--fps names " + rateName(rates[k]) + " Hz twice");
  }
  return rates;
}

int runEval(app::Argv argv) {
  app::Args args("embody eval",
                 "Scores the body against motion capture: the clip's own skeleton is the avatar, only the chosen trackers "
                 "reach the runtime (filter, loss guard, stepping, IK at a fixed iteration count), every joint is compared "
                 "with the clip's. Coupled spine, uncoupled spine and a naive baseline side by side. Writes metrics.json, "
                 "solved.bvh, frames.csv, joints.csv and gnuplot PNGs into --out; a folder gives one table.");
  args.option("motion", "CLIP.bvh|DIR", "a BVH clip, or a folder: every *.bvh in it");
  args.option("trackers", "SET", "3 (HMD + controllers), 4 (+ pelvis), 6 (+ feet), full (+ a marker on every joint); "
              "a folder runs 3, 4, 6 and full unless given", "3");
  args.option("fps", "HZ[,HZ...]", "evaluation rate (default: the clip's own); several (60,90,120) score each and "
              "average them in one table: a step starts on another frame at another rate, and the mean over rates judges "
              "a change to the stepping more steadily than one rate");
  args.option("ik-iterations", "N", "IK iterations per frame (fixed: the score repeats to the bit)", "10");
  args.option("bvh-scale", "M_PER_UNIT", "metres per BVH unit (default: fit the clip to 1.75 m)");
  app::declareBvhOptions(args);
  args.option("out", "DIR", "output folder", "out/eval");
  args.flag("no-plots", "do not run gnuplot (the .gp scripts are still written)");
  args.flag("no-sheet", "no contact sheet (it needs a Vulkan device: the solution solid, the clip as an orange ghost skeleton)");
  args.option("device", "SELECTOR", "Vulkan device for the contact sheet: auto, an index, 'lavapipe', or part of its name", "auto");
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);

  EvalJob job;
  app::BvhOverrides bvh;
  try {
    if (!args.has("motion")) throw std::invalid_argument("--motion CLIP.bvh|DIR is required");
    if (args.has("fps")) job.rates = ratesOf(args);
    job.options.ikIterations = args.integer("ik-iterations");
    if (job.options.ikIterations < 1 || job.options.ikIterations > 1000) throw std::invalid_argument("--ik-iterations must be 1 .. 1000");
    if (args.has("bvh-scale")) job.bvhScale = args.number("bvh-scale");
    if (args.has("bvh-scale") && !(job.bvhScale > 0.0)) throw std::invalid_argument("--bvh-scale must be positive");
    bvh = app::readBvhOptions(args);
  } catch (const std::invalid_argument& e) {
    return app::usageError(e.what());
  }
  auto body = app::bvhBodyOptions(bvh);
  if (!body) return app::runtimeError(body.error());
  job.bvhBody = std::move(*body);
  const std::string sets = args.get("trackers");
  const bool given = std::find(argv.begin(), argv.end(), "--trackers") != argv.end() ||
                     std::any_of(argv.begin(), argv.end(), [](const std::string& a) { return a.rfind("--trackers=", 0) == 0; });
  std::error_code dirError;
  if (fs::is_directory(args.get("motion"), dirError) && !given) {
    job.sets = {eval::TrackerSet::Three, eval::TrackerSet::Four, eval::TrackerSet::Six, eval::TrackerSet::Full};
  } else {
    eval::TrackerSet set;
    if (!eval::parseTrackerSet(sets, set)) return app::usageError("--trackers must be 3, 4, 6 or full (got '" + sets + "')");
    job.sets = {set};
  }
  const fs::path motion = args.get("motion");
  std::error_code ec;
  job.folder = fs::is_directory(motion, ec);
  if (job.folder) {
    for (const auto& entry : fs::directory_iterator(motion, ec)) {
      std::string ext = entry.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
      if (entry.is_regular_file() && ext == ".bvh") job.clips.push_back(entry.path());
    }
    std::sort(job.clips.begin(), job.clips.end());
    if (job.clips.empty()) return app::runtimeError(motion.string() + ": no .bvh files in this folder");
  } else {
    if (!fs::exists(motion, ec)) return app::runtimeError(motion.string() + ": no such file or folder");
    job.clips.push_back(motion);
  }
  job.out = args.get("out");
  job.plots = !args.has("no-plots");
  job.sheet = !args.has("no-sheet");
  job.device = args.get("device");
  fs::create_directories(job.out, ec);
  if (ec) return app::runtimeError("cannot create " + job.out.string() + ": " + ec.message());
  return runJob(job);
}

}  // namespace

EMBODY_COMMAND("eval", "score the body against motion capture: a BVH clip's trackers through the runtime, every joint vs the clip", runEval);
