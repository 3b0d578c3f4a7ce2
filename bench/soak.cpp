// embody_soak: drives the runtime's real path (pose source -> One Euro filter -> tracking-loss
// guard -> IkThread/IkStage -> triple buffer -> skeleton pose -> skinning palette) for a set time
// through every synthetic motion and recorded clip, injecting faults the way headsets produce
// them, and reports what held: frames, deadline misses, time to recover after each fault, the
// tracker-to-body error once recovered, NaN count (must be 0) and resident memory (flat).
//
//   embody_soak [--seconds S] [--avatar FILE] [--motion SPEC]... [--synthetic-only]
//               [--budget-ms MS] [--seed N] [--json FILE]
//
// Faults, one per slot of `slotSeconds`, in turn: a tracker lost 0.05-5 s, a NaN/Inf burst, a
// 10 m teleport glitch, a recenter (the play space turns 90 degrees and moves, for good), the
// head lost while the hands stay live, a clock jump (forward 5 s, or back 0.5 s), a stalled
// render side (300 ms). docs/reliability.md has the figures.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "avatar/avatar_loader.h"
#include "avatar/gltf/gltf_loader.h"
#include "avatar/procedural/default_avatar.h"
#include "runtime/avatar_body_solver.h"
#include "runtime/ik_thread.h"
#include "test_paths.h"
#include "tracking/pose_source.h"
#include "tracking/space_transform.h"
#include "tracking/synthetic_source.h"

using namespace embody;
using tracking::TrackerId;
using SteadyClock = std::chrono::steady_clock;

namespace {

enum class Fault { TrackerLost, NonFinite, Teleport, Recenter, HeadLost, ClockJump, RenderStall, Count };
constexpr const char* kFaultNames[] = {"tracker_lost", "nan_inf_burst", "teleport_10m", "recenter",
                                       "head_lost",    "clock_jump",    "render_stall"};

struct Slot {
  Fault fault = Fault::TrackerLost;
  int source = 0;
  double start = 0.0, faultStart = 0.0, faultEnd = 0.0, end = 0.0;  // soak seconds
  TrackerId tracker = TrackerId::LeftHand;
  double clockJump = 0.0;
  // Filled in by the render side.
  double recoverySeconds = -1.0;  // < 0: not recovered before the slot ended
  double maxErrorAfterRecovery = 0.0;
};

struct Options {
  double seconds = 1800.0;
  double slotSeconds = 0.0;  // 0: from the run length
  double budgetMs = 1.0;
  double trackingHz = 72.0, renderHz = 90.0;
  double recoveredWithin = 0.05;  // metres: every reachable residual under it counts as recovered
  std::string avatar, json;
  std::vector<std::string> motions;
  bool syntheticOnly = false;
  uint64_t seed = 1;
};

size_t residentBytes() {
  std::ifstream f("/proc/self/statm");
  size_t pages = 0, resident = 0;
  f >> pages >> resident;
  return resident * static_cast<size_t>(sysconf(_SC_PAGESIZE));
}

std::vector<Slot> schedule(const Options& o, int sources) {
  std::mt19937_64 rng(o.seed);
  auto uniform = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  const int faults = static_cast<int>(Fault::Count);
  const double slot = o.slotSeconds > 0.0 ? o.slotSeconds : std::clamp(o.seconds / (2.0 * faults), 1.5, 8.0);
  std::vector<Slot> out;
  for (int k = 0; (k + 1) * slot <= o.seconds + 1e-9; ++k) {
    Slot s;
    s.fault = static_cast<Fault>(k % faults);
    s.source = k % sources;
    s.start = k * slot;
    s.end = s.start + slot;
    s.faultStart = s.start + 0.25 * slot;
    const double longest = std::min(5.0, 0.45 * slot);
    double length = 0.0;
    switch (s.fault) {
      case Fault::TrackerLost: length = uniform(0.05, longest); break;
      case Fault::NonFinite: length = uniform(0.03, 0.15); break;
      case Fault::Teleport: length = uniform(0.02, 0.2); break;
      case Fault::HeadLost: length = uniform(0.2, longest); break;
      case Fault::RenderStall: length = 0.3; break;
      default: break;  // recenter and clock jump are instantaneous and persist
    }
    s.faultEnd = s.faultStart + length;
    s.tracker = std::array{TrackerId::LeftHand, TrackerId::RightHand, TrackerId::Head}[k % 3];
    s.clockJump = (k / faults) % 2 ? -0.5 : 5.0;
    out.push_back(s);
  }
  return out;
}

// What the headset would hand over at soak time `t`: the source's pose with the slot's fault,
// after every recenter and clock jump so far.
struct FaultInjector {
  const std::vector<Slot>& slots;
  tracking::SpaceTransform playSpace;  // every recenter so far
  double clockOffset = 0.0;
  size_t applied = 0;  // slots whose persistent fault has been applied

  void apply(const Slot& s, double t, tracking::PoseSample& sample) {
    const size_t k = static_cast<size_t>(&s - slots.data());
    if (t >= s.faultStart && applied <= k) {
      applied = k + 1;
      if (s.fault == Fault::Recenter) {
        const tracking::SpaceTransform turnAndMove{glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0)),
                                                   glm::vec3(1.0f, 0.0f, 0.5f)};
        playSpace = turnAndMove.after(playSpace);
      }
      if (s.fault == Fault::ClockJump) clockOffset += s.clockJump;
    }
    sample.time += clockOffset;
    playSpace.apply(sample);
    if (t < s.faultStart || t >= s.faultEnd) return;
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    switch (s.fault) {
      case Fault::TrackerLost: sample[s.tracker].valid = false; break;
      case Fault::NonFinite:
        sample[s.tracker].position = glm::vec3(nan, inf, 0.0f);
        sample[TrackerId::Head].orientation = glm::quat(nan, 0, 0, 0);
        break;
      case Fault::Teleport: sample[s.tracker].position += glm::vec3(10.0f, 0.0f, 0.0f); break;
      case Fault::HeadLost: sample[TrackerId::Head].valid = false; break;
      default: break;
    }
  }
};

}  // namespace

namespace {

bool finitePose(const avatar::SkeletonPose& pose, const std::vector<glm::mat4>& palette) {
  for (const auto& t : pose.local) {
    const float sum = t.translation.x + t.translation.y + t.translation.z + t.rotation.w + t.rotation.x +
                      t.rotation.y + t.rotation.z + t.scale.x + t.scale.y + t.scale.z;
    if (!std::isfinite(sum)) return false;
  }
  for (const auto& m : palette)
    for (int c = 0; c < 4; ++c)
      if (!std::isfinite(m[c].x + m[c].y + m[c].z + m[c].w)) return false;
  return true;
}

// The render side: takes the newest solved frame at the display rate, computes the skinning
// palette, checks it, and scores each slot's recovery. Stalls when its slot says so.
struct RenderSide {
  runtime::IkThread& ik;
  const avatar::AvatarAsset& asset;
  std::vector<Slot>& slots;
  const Options& o;
  SteadyClock::time_point start;
  std::atomic<bool> stop{false};
  size_t framesRendered = 0, deadlineMisses = 0, nonFinite = 0;
  double ikMaxMs = 0.0;
  std::vector<glm::mat4> globals, palette;

  double now() const { return std::chrono::duration<double>(SteadyClock::now() - start).count(); }

  void run() {
    size_t stalledSlot = SIZE_MAX;
    for (long i = 1; !stop.load(std::memory_order_acquire); ++i) {
      std::this_thread::sleep_until(start + std::chrono::duration<double>(i / o.renderHz));
      const double t = now();
      const size_t k = std::min(slots.size() - 1, static_cast<size_t>(t / (slots[0].end - slots[0].start)));
      Slot& s = slots[k];
      if (s.fault == Fault::RenderStall && t >= s.faultStart && stalledSlot != k) {
        stalledSlot = k;
        std::this_thread::sleep_for(std::chrono::duration<double>(s.faultEnd - s.faultStart));
      }
      if (!ik.acquire()) continue;
      const runtime::SolvedFrame& f = ik.frame();
      avatar::computeGlobals(asset.skeleton, f.pose, globals);
      avatar::computeSkinningPalette(asset, globals, palette);
      ++framesRendered;
      deadlineMisses += f.stats.deadlineMiss ? 1 : 0;
      ikMaxMs = std::max(ikMaxMs, f.stats.ikSeconds * 1e3);
      if (!finitePose(f.pose, palette)) ++nonFinite;
      score(s, f, now());
    }
  }

  void score(Slot& s, const runtime::SolvedFrame& f, double t) const {
    if (t < s.faultEnd) return;
    float worst = 0.0f;
    bool settled = true;
    for (size_t i = 0; i < f.stats.residual.size(); ++i) {
      const auto st = f.stats.status[i];
      if (st != tracking::TrackerStatus::Tracked && st != tracking::TrackerStatus::Absent) settled = false;
      if (f.stats.residual[i] >= 0.0f && f.stats.reachable[i]) worst = std::max(worst, f.stats.residual[i]);
    }
    if (!std::isfinite(worst)) worst = std::numeric_limits<float>::infinity();
    if (s.recoverySeconds < 0.0) {
      if (settled && worst <= o.recoveredWithin) s.recoverySeconds = t - s.faultEnd;
    } else {
      s.maxErrorAfterRecovery = std::max(s.maxErrorAfterRecovery, static_cast<double>(worst));
    }
  }
};

Options parseOptions(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--seconds") o.seconds = std::stod(value());
    else if (a == "--slot-seconds") o.slotSeconds = std::stod(value());
    else if (a == "--budget-ms") o.budgetMs = std::stod(value());
    else if (a == "--avatar") o.avatar = value();
    else if (a == "--motion") o.motions.push_back(value());
    else if (a == "--synthetic-only") o.syntheticOnly = true;
    else if (a == "--seed") o.seed = std::stoull(value());
    else if (a == "--json") o.json = value();
    else throw std::invalid_argument("unknown option " + a);
  }
  if (!(o.seconds >= 3.0 && o.seconds <= 7 * 86400.0)) throw std::invalid_argument("--seconds must be 3 .. 604800");
  if (!(o.budgetMs > 0.0 && o.budgetMs <= 1000.0)) throw std::invalid_argument("--budget-ms must be > 0 and <= 1000");
  return o;
}

// Every standing synthetic motion, then the recorded clips in the shared mocap folder (when present), then
// --motion arguments.
Result<std::vector<std::unique_ptr<tracking::PoseSource>>> openSources(const Options& o) {
  std::vector<std::string> specs;
  // synthetic:seated is for the seated body (--seated): a standing solver cannot meet its hips.
  for (const auto& m : tracking::syntheticMotions())
    if (m.name != "seated") specs.push_back("synthetic:" + std::string(m.name));
  std::error_code ec;
  const auto mocap = test::sharedDir() / "mocap";
  if (!o.syntheticOnly && std::filesystem::is_directory(mocap, ec)) {
    std::vector<std::string> clips;
    for (const auto& e : std::filesystem::directory_iterator(mocap, ec))
      if (e.path().extension() == ".bvh" || e.path().extension() == ".jsonl") clips.push_back(e.path().string());
    std::sort(clips.begin(), clips.end());
    specs.insert(specs.end(), clips.begin(), clips.end());
  }
  specs.insert(specs.end(), o.motions.begin(), o.motions.end());
  std::vector<std::unique_ptr<tracking::PoseSource>> out;
  for (const auto& spec : specs) {
    auto s = tracking::openPoseSource(spec);
    if (!s) return Error{spec + ": " + s.error()};
    out.push_back(std::move(s).value());
  }
  return out;
}

}  // namespace

namespace {

// Per source: slots and recovered ones (a clip the avatar cannot follow within recoveredWithin
// never counts as recovered, whatever the fault).
nlohmann::json perSource(const std::vector<Slot>& slots, const std::vector<std::string>& names) {
  nlohmann::json out = nlohmann::json::object();
  for (size_t k = 0; k < names.size(); ++k) {
    size_t count = 0, recovered = 0;
    for (const auto& s : slots)
      if (static_cast<size_t>(s.source) == k) {
        ++count;
        recovered += s.recoverySeconds >= 0.0 ? 1 : 0;
      }
    out[names[k]] = {{"slots", count}, {"recovered", recovered}};
  }
  return out;
}

nlohmann::json summarize(const std::vector<Slot>& slots, const std::vector<std::string>& sourceNames,
                         const RenderSide& render, const runtime::IkThread& ik, size_t rssStart, size_t rssEnd,
                         double seconds) {
  nlohmann::json faults = nlohmann::json::object();
  double recoveryMax = 0.0, errorMax = 0.0;
  size_t unrecovered = 0;
  for (int f = 0; f < static_cast<int>(Fault::Count); ++f) {
    size_t count = 0, recovered = 0;
    double rMax = 0.0, rSum = 0.0, eMax = 0.0;
    for (const auto& s : slots) {
      if (static_cast<int>(s.fault) != f) continue;
      ++count;
      if (s.recoverySeconds < 0.0) continue;
      ++recovered;
      rMax = std::max(rMax, s.recoverySeconds);
      rSum += s.recoverySeconds;
      eMax = std::max(eMax, s.maxErrorAfterRecovery);
    }
    faults[kFaultNames[f]] = {{"injected", count}, {"recovered", recovered},
                              {"recovery_max_s", rMax}, {"recovery_mean_s", recovered ? rSum / recovered : 0.0},
                              {"error_after_recovery_max_m", eMax}};
    recoveryMax = std::max(recoveryMax, rMax);
    errorMax = std::max(errorMax, eMax);
    unrecovered += count - recovered;
  }
  const auto mb = [](size_t b) { return static_cast<double>(b) / (1024.0 * 1024.0); };
  return {{"seconds", seconds},
          {"frames_submitted", ik.samplesSubmitted()},
          {"frames_solved", ik.framesSolved()},
          {"samples_skipped", ik.samplesSkipped()},
          {"frames_rendered", render.framesRendered},
          {"deadline_misses", render.deadlineMisses},
          {"ik_max_ms", render.ikMaxMs},
          {"nan_frames", render.nonFinite},
          {"faults_injected", slots.size()},
          {"faults_unrecovered", unrecovered},
          {"recovery_max_s", recoveryMax},
          {"error_after_recovery_max_m", errorMax},
          {"rss_start_mb", mb(rssStart)},
          {"rss_end_mb", mb(rssEnd)},
          {"faults", faults},
          {"sources", perSource(slots, sourceNames)}};
}

int soak(const Options& o) {
  avatar::AvatarAsset asset;
  if (o.avatar.empty()) {
    asset = avatar::buildDefaultAvatar();
  } else {
    auto a = avatar::loadAvatarFile(o.avatar);
    if (!a) return std::fprintf(stderr, "embody_soak: error: %s\n", a.error().c_str()), 1;
    asset = std::move(a).value();
  }
  auto sources = openSources(o);
  if (!sources) return std::fprintf(stderr, "embody_soak: error: %s\n", sources.error().c_str()), 1;
  auto solver = runtime::AvatarBodySolver::create(asset, {});
  if (!solver) return std::fprintf(stderr, "embody_soak: error: %s\n", solver.error().c_str()), 1;
  std::vector<Slot> slots = schedule(o, static_cast<int>(sources->size()));
  runtime::IkStageConfig cfg;
  cfg.budgetSeconds = o.budgetMs * 1e-3;
  runtime::IkThread ik(**solver, runtime::steadyClock(), cfg, avatar::SkeletonPose::rest(asset.skeleton));
  ik.start();
  const auto start = SteadyClock::now();
  RenderSide render{ik, asset, slots, o, start};
  std::thread renderThread([&] { render.run(); });
  FaultInjector inject{slots};
  size_t rssStart = 0;
  const double end = slots.back().end;
  for (long i = 0;; ++i) {
    const double t = i / o.trackingHz;
    if (t >= end) break;
    std::this_thread::sleep_until(start + std::chrono::duration<double>(t));
    const Slot& s = slots[std::min(slots.size() - 1, static_cast<size_t>(t / (slots[0].end - slots[0].start)))];
    tracking::PoseSource& src = *(*sources)[static_cast<size_t>(s.source)];
    const double d = src.duration();
    tracking::PoseSample sample = src.sample(d > 0.0 ? std::fmod(t, d) : t);
    sample.time = t;
    inject.apply(s, t, sample);
    ik.submit(sample);
    if (rssStart == 0 && t >= 1.0) rssStart = residentBytes();
  }
  render.stop = true;
  renderThread.join();
  ik.stop();
  std::vector<std::string> names;
  for (const auto& src : *sources) names.push_back(src->name());
  const nlohmann::json j = summarize(slots, names, render, ik, rssStart, residentBytes(), end);
  std::printf("%s\n", j.dump(2).c_str());
  if (!o.json.empty()) std::ofstream(o.json) << j.dump(2) << "\n";
  return render.nonFinite == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return soak(parseOptions(argc, argv));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "embody_soak: error: %s\nusage: embody_soak [--seconds S] [--avatar FILE] [--motion SPEC]... "
                         "[--synthetic-only] [--budget-ms MS] [--seed N] [--json FILE]\n", e.what());
    return 2;
  }
}
