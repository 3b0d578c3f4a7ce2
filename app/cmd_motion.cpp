// embody motion: inspect and record pose sources (synthetic motions, JSON Lines traces, BVH).
//   embody motion list
//   embody motion info SOURCE [--json] [--user-height M] [--bvh-scale S] [--bvh-up AXIS] [--bvh-forward AXIS]
//                     [--bone-map FILE]
//   embody motion record --motion SOURCE --out FILE.jsonl [--frames N] [--fps F] [--three-point] [--filter]
//                        [--lose left,right@2-3]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "app/args.h"
#include "app/bvh_options.h"
#include "app/job_options.h"
#include "avatar/body/calibration.h"
#include "runtime/task_layout.h"
#include "tracking/one_euro_filter.h"
#include "tracking/synthetic_source.h"
#include "tracking/trace.h"

namespace {

using namespace embody;
using namespace embody::tracking;

void sourceOptions(app::Args& args) {
  args.option("user-height", "METRES", "the user's height, " + avatar::bodyHeightRange() +
                                           ": synthetic motions are built for it, BVH fitted to it", "1.75");
  args.option("bvh-scale", "M_PER_UNIT", "metres per BVH unit (e.g. 0.0564 for CMU); default: fit the rest skeleton to --user-height");
  app::declareBvhOptions(args);
  args.option("bone-map", "FILE", "the same as --bvh-bone-map (motion commands have no avatar)");
  args.flag("three-point", "keep only the head and hands (an HMD with two controllers)");
  args.option("lose", "TRACKERS@FROM-TO", "make trackers invalid in a time window, e.g. left,right@2.0-3.0");
}

// Opens the source with the shared options; the error is printed, exit code in `code`.
std::unique_ptr<PoseSource> openSource(const app::Args& args, const std::string& spec, const SourceOptions& opts,
                                       int& code) {
  std::optional<TrackingLossSpec> loss;
  if (args.has("lose")) {
    auto l = parseTrackingLoss(args.get("lose"));
    if (!l) {
      std::fprintf(stderr, "error: --lose: %s\n", l.error().c_str());
      code = 2;
      return nullptr;
    }
    loss = *l;
  }
  auto src = openPoseSource(spec, opts);
  if (!src) {
    std::fprintf(stderr, "error: %s\n", src.error().c_str());
    code = 1;
    return nullptr;
  }
  std::unique_ptr<PoseSource> s = std::move(*src);
  if (loss) s = withTrackingLoss(std::move(s), loss->lost, loss->from, loss->to);
  return s;
}

// Reads the shared source options; throws std::invalid_argument on bad values (usage errors).
SourceOptions readSourceOptions(const app::Args& args) {
  SourceOptions o;
  o.userHeight = static_cast<float>(args.number("user-height"));
  if (!avatar::plausibleBodyHeight(o.userHeight))
    throw std::invalid_argument("--user-height must be " + avatar::bodyHeightRange());
  if (args.has("bvh-scale")) {
    o.bvhScale = args.number("bvh-scale");
    if (!(o.bvhScale > 0.0)) throw std::invalid_argument("--bvh-scale must be positive");
  }
  if (args.has("three-point")) o.trackers = TrackerMask::threePoint();
  app::BvhOverrides bvh = app::readBvhOptions(args);
  if (bvh.boneMapFile.empty()) bvh.boneMapFile = args.get("bone-map");
  auto body = app::bvhBodyOptions(bvh);
  if (!body) throw std::runtime_error(body.error());
  o.bvh = std::move(*body);
  return o;
}

std::string trackerList(TrackerMask m) {
  std::string s;
  for (auto id : kAllTrackers)
    if (m.has(id)) s += (s.empty() ? "" : ", ") + std::string(trackerKey(id));
  return s.empty() ? "(none)" : s;
}

int list() {
  for (const auto& m : syntheticMotions())
    std::printf("synthetic:%-8s %4.1f s  %s\n", std::string(m.name).c_str(), m.period, std::string(m.description).c_str());
  std::printf("\nAlso: FILE.bvh (motion capture) and FILE.jsonl (recorded traces, docs/tracking.md).\n");
  return 0;
}

// What one tracker does over a whole motion.
struct TrackerRange {
  size_t valid = 0;
  glm::vec3 lo{1e9f}, hi{-1e9f};
  float path = 0.0f, maxSpeed = 0.0f;
  glm::vec3 first{0.0f}, last{0.0f};
  bool any = false;
};
using TrackerRanges = std::array<TrackerRange, kTrackerCount>;

// Walks the motion at `rate` Hz over `n` samples and summarises each tracker.
TrackerRanges walkMotion(PoseSource& s, double rate, size_t n) {
  TrackerRanges r{};
  for (size_t i = 0; i < n; ++i) {
    const PoseSample p = s.sample(static_cast<double>(i) / rate);
    for (auto id : kAllTrackers) {
      const TrackerPose& t = p[id];
      TrackerRange& g = r[static_cast<size_t>(index(id))];
      if (!t.valid) continue;
      ++g.valid;
      g.lo = glm::min(g.lo, t.position);
      g.hi = glm::max(g.hi, t.position);
      if (g.any) {
        const float d = glm::length(t.position - g.last);
        g.path += d;
        g.maxSpeed = std::max(g.maxSpeed, d * static_cast<float>(rate));
      } else {
        g.first = t.position;
      }
      g.last = t.position;
      g.any = true;
    }
  }
  return r;
}

// The `embody motion info --json` object (the text output prints from it too).
nlohmann::json motionInfoJson(const PoseSource& s, const SourceOptions& opts, const TrackerRanges& r, size_t n) {
  nlohmann::json j;
  j["source"] = s.name();
  j["trackers"] = nlohmann::json::array();
  for (auto id : kAllTrackers)
    if (s.trackers().has(id)) j["trackers"].push_back(trackerKey(id));
  j["duration_s"] = s.duration();
  j["periodic"] = s.periodic();
  j["native_rate_hz"] = s.nativeRate();
  j["frames"] = s.frameCount();
  j["notes"] = s.notes();
  j["user_height_m"] = opts.userHeight;
  nlohmann::json per = nlohmann::json::object();
  for (auto id : kAllTrackers) {
    const TrackerRange& g = r[static_cast<size_t>(index(id))];
    if (!s.trackers().has(id)) continue;
    nlohmann::json t = {{"valid_fraction", static_cast<double>(g.valid) / static_cast<double>(n)}};
    if (g.any) {
      t["min"] = {g.lo.x, g.lo.y, g.lo.z};
      t["max"] = {g.hi.x, g.hi.y, g.hi.z};
      t["path_m"] = g.path;
      t["displacement_m"] = glm::length(glm::vec2(g.last.x - g.first.x, g.last.z - g.first.z));
      t["max_speed_m_s"] = g.maxSpeed;
    }
    per[std::string(trackerKey(id))] = t;
  }
  j["per_tracker"] = per;
  return j;
}

void printMotionInfo(const PoseSource& s, const TrackerRanges& r, const nlohmann::json& j,
                     const runtime::TaskLayout& layout) {
  std::printf("source:    %s\n", s.name().c_str());
  std::printf("trackers:  %s\n", trackerList(s.trackers()).c_str());
  std::printf("duration:  %.3f s%s", s.duration(), s.periodic() ? " (repeats)" : "");
  if (s.frameCount() > 0) std::printf(", %zu frames at %.2f Hz", s.frameCount(), s.nativeRate());
  std::printf("\n");
  for (const auto& note : s.notes()) std::printf("note:      %s\n", note.c_str());
  std::printf("\n%-11s %6s %20s %20s %8s %8s\n", "tracker", "valid", "height (y) m", "path m", "moved m", "max m/s");
  for (auto id : kAllTrackers) {
    if (!s.trackers().has(id)) continue;
    const TrackerRange& g = r[static_cast<size_t>(index(id))];
    const auto& t = j["per_tracker"][std::string(trackerKey(id))];
    if (!g.any) {
      std::printf("%-11s %5.0f%%  never valid\n", std::string(trackerKey(id)).c_str(), 0.0);
      continue;
    }
    char height[32];
    std::snprintf(height, sizeof height, "%.3f .. %.3f", g.lo.y, g.hi.y);
    std::printf("%-11s %5.0f%% %20s %20.3f %8.3f %8.2f\n", std::string(trackerKey(id)).c_str(),
                100.0 * t["valid_fraction"].get<double>(), height, g.path, t["displacement_m"].get<double>(),
                g.maxSpeed);
  }
  std::printf("\nIK tasks for these trackers (priority, task):\n%s", layout.describe().c_str());
}

int info(app::Argv argv) {
  app::Args args("embody motion info", "Describes a pose source: trackers, duration, rate, notes, and what the "
                                       "trackers do over the whole motion.");
  args.positional("SOURCE", "synthetic:NAME, FILE.bvh or FILE.jsonl");
  args.flag("json", "print one JSON object instead of text");
  sourceOptions(args);
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);
  SourceOptions opts;
  try {
    opts = readSourceOptions(args);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::runtime_error& e) {  // an unreadable bone map file
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  int code = 0;
  auto src = openSource(args, args.get("SOURCE"), opts, code);
  if (!src) return code;
  PoseSource& s = *src;
  // Walk the motion at 90 Hz (or its native rate) and summarise each tracker.
  const double rate = s.nativeRate() > 0.0 ? s.nativeRate() : 90.0;
  const size_t n = static_cast<size_t>(std::floor(s.duration() * rate + 1e-6)) + 1;
  const TrackerRanges r = walkMotion(s, rate, n);
  nlohmann::json j = motionInfoJson(s, opts, r, n);
  const runtime::TaskLayout layout = runtime::taskLayoutFor(s.trackers());
  if (args.has("json")) {
    j["inferred_lower_body"] = layout.inferLowerBody;
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  printMotionInfo(s, r, j, layout);
  return 0;
}

int record(app::Argv argv) {
  app::Args args("embody motion record", "Records any pose source as a JSON Lines trace (docs/tracking.md), "
                                         "sampled at a fixed rate; replay it with --motion FILE.jsonl.");
  args.option("motion", "SOURCE", "synthetic:NAME, FILE.bvh or FILE.jsonl");
  args.option("out", "FILE.jsonl", "the trace to write");
  args.option("frames", "N", "samples to write (default: the whole motion, one period for synthetic ones)");
  args.option("fps", "HZ", "sample rate (1 .. 1000)", "90");
  args.flag("filter", "apply the One Euro filter (as the runtime does) before writing");
  sourceOptions(args);
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);
  SourceOptions opts;
  double fps = 0.0;
  int frames = -1;
  try {
    if (!args.has("motion") || !args.has("out")) throw std::invalid_argument("--motion and --out are required");
    opts = readSourceOptions(args);
    fps = app::readFps(args);  // the limits every command applies (app/job_options.h)
    if (args.has("frames")) {
      frames = args.integer("frames");
      if (frames < 1) throw std::invalid_argument("--frames must be at least 1");
    }
  } catch (const std::invalid_argument& e) {
    return app::usageError(e.what());
  } catch (const std::runtime_error& e) {  // an unreadable bone map file
    return app::runtimeError(e.what());
  }
  int code = 0;
  auto src = openSource(args, args.get("motion"), opts, code);
  if (!src) return code;
  PoseSource& s = *src;
  if (frames < 0) frames = static_cast<int>(std::floor(s.duration() * fps + 1e-6)) + (s.periodic() ? 0 : 1);
  frames = std::max(frames, 1);
  TraceWriter w;
  if (auto st = w.open(args.get("out"), s.trackers(), s.name(), opts.userHeight); !st) {
    std::fprintf(stderr, "error: %s\n", st.error().c_str());
    return 1;
  }
  PoseFilter filter;
  for (int i = 0; i < frames; ++i) {
    PoseSample p = s.sample(static_cast<double>(i) / fps);
    if (args.has("filter")) p = filter.apply(p);
    if (auto st = w.write(p); !st) {
      std::fprintf(stderr, "error: %s\n", st.error().c_str());
      return 1;
    }
  }
  if (auto st = w.close(); !st) {
    std::fprintf(stderr, "error: %s\n", st.error().c_str());
    return 1;
  }
  std::printf("wrote %d samples (%.3f s at %g Hz, trackers %s) to %s\n", frames, (frames - 1) / fps, fps,
              trackerList(s.trackers()).c_str(), args.get("out").c_str());
  return 0;
}

int runMotion(app::Argv argv) {
  const std::string usage =
      "usage: embody motion <list|info|record> ...\n\n"
      "  list                       the built-in synthetic motions\n"
      "  info SOURCE [--json]       trackers, duration, rate and ranges of a pose source\n"
      "  record --motion SOURCE --out FILE.jsonl [--frames N] [--fps F]\n"
      "                             record any source as a JSON Lines trace\n\n"
      "SOURCE is synthetic:NAME, FILE.bvh or FILE.jsonl. Run 'embody motion info --help' for options.\n";
  if (argv.empty()) return app::usageError("missing subcommand: list, info or record (see 'embody motion --help')");
  const std::string& sub = argv[0];
  if (sub == "--help" || sub == "-h") {
    std::fputs(usage.c_str(), stdout);
    return 0;
  }
  if (sub == "list") return list();
  if (sub == "info") return info(argv.subspan(1));
  if (sub == "record") return record(argv.subspan(1));
  return app::usageError("unknown subcommand '" + sub + "': list, info or record (see 'embody motion --help')");
}

}  // namespace

EMBODY_COMMAND("motion", "list, inspect and record pose sources (synthetic, BVH, JSON Lines traces)", runMotion);
