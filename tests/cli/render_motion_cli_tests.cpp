// `embody render --motion` and `embody demo` end to end: frames, contact sheet, nested stats.json
// with sane numbers, a recorded trace that replays, clear usage errors.
#include <array>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli/cli_support.h"
#include "test_paths.h"

using namespace embody::test;  // outDir, readJson, pngSize, runEmbody (cli_support.h)
namespace fs = std::filesystem;

namespace {

// An IK budget for these runs: generous in a release build. Sanitizer builds run the solver many
// times slower (ThreadSanitizer about 20x: 50 ms bought 6 iterations a frame, too few to bring
// the hands from the rest pose in 6 frames), so they get ten times more.
double budgetMs(double ms) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  return 10.0 * ms;
#else
  return ms;
#endif
}

std::string budgetArg(double ms) { return " --ik-budget-ms " + std::to_string(budgetMs(ms)) + " "; }

}  // namespace

TEST_CASE("embody render --motion synthetic:figure8: frames, contact sheet and nested stats.json", "[cli][render]") {
  const auto out = outDir("render_figure8");
  const fs::path trace = out.parent_path() / "figure8_recorded.jsonl";
  auto r = runEmbody("render --avatar default --motion synthetic:figure8 --frames 6 --fps 90 --size 96x80" + budgetArg(50) +
                     "--device lavapipe --validate --record " + trace.string() + " --out " + out.string(), true);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  CHECK(r.output.find("validation messages: 0") != std::string::npos);
  for (int i = 0; i < 6; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.png", i);
    CHECK(pngSize(out / name) == std::pair<uint32_t, uint32_t>(96, 80));
  }
  CHECK_FALSE(fs::exists(out / "frame_00006.png"));
  CHECK(pngSize(out / "contact_sheet.png").first > 96);
  const auto j = readJson(out / "stats.json");
  CHECK(j["frames"] == 6);
  CHECK(j["ik"]["budget_ms"].get<double>() == Approx(budgetMs(50.0)));
  CHECK(j["ik"]["p50_ms"].get<double>() > 0.0);
  CHECK(j["ik"]["p99_ms"].get<double>() >= j["ik"]["p50_ms"].get<double>());
  CHECK(j["ik"]["deadline_misses"].get<int>() >= 0);
  CHECK(j["ik"]["iterations_mean"].get<double>() >= 1.0);
  // All trackers on a synthetic motion built for this body: the avatar meets them.
  CHECK(j["tracking"]["head_error_p95_m"].get<double>() >= 0.0);
  CHECK(j["tracking"]["head_error_p95_m"].get<double>() < 0.01);
  CHECK(j["tracking"]["hand_error_p95_m"].get<double>() < 0.02);
  CHECK(j["tracking"]["non_finite_frames"] == 0);
  CHECK(j["render"]["p50_ms"].get<double>() > 0.0);

  // The recorded trace replays through the same pipeline.
  REQUIRE(fs::exists(trace));
  const auto replay = outDir("render_replay");
  auto rr = runEmbody("render --motion " + trace.string() + " --frames 4 --size 64x64 --view first --out " + replay.string(), true);
  INFO(rr.output);
  CHECK(rr.exitCode == 0);
  CHECK(pngSize(replay / "frame_00003.png") == std::pair<uint32_t, uint32_t>(64, 64));
  CHECK(readJson(replay / "stats.json")["calibration"]["from_first_head_sample"] == true);
}

TEST_CASE("embody render counts the frames whose body stands upright: all when standing, none lying down", "[cli][render]") {
  const auto out = outDir("render_upright");
  fs::create_directories(out);
  // A person lying on their back on the floor: the head 15 cm up looking at the sky, hands beside.
  const fs::path lying = out / "lying.jsonl";
  {
    std::ofstream f(lying);
    for (int i = 0; i <= 10; ++i)
      f << "{\"t\": " << 0.1 * i << R"(, "head": {"p": [0, 0.15, 0], "q": [0.7071, 0, 0, 0.7071]},)"
        << R"( "left": {"p": [-0.3, 0.1, 0.4], "q": [0, 0, 0, 1]}, "right": {"p": [0.3, 0.1, 0.4], "q": [0, 0, 0, 1]}})" << "\n";
  }
  for (const auto& [motion, standing] : {std::pair{std::string("synthetic:squat"), true}, std::pair{lying.string(), false}}) {
    const auto dir = out / (standing ? "standing" : "lying");
    auto r = runEmbody("render --motion " + motion + " --user-height 1.75 --frames 20 --fps 10 --size 32x32 --ik-iterations 10 --out " +
                       dir.string(), true);
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    const auto j = readJson(dir / "stats.json");
    const int upright = j["body"]["upright_frames"].get<int>();
    CHECK(upright == (standing ? 20 : 0));
    CHECK(r.output.find("body upright in " + std::to_string(upright) + " of 20 frames") != std::string::npos);
  }
}

TEST_CASE("embody render --three-point on the BVH walk steps and keeps the head on target", "[cli][render]") {
  EMBODY_REQUIRE_SHARED_ASSET(bvh, "cmu_12_01_walk.bvh");
  const auto out = outDir("render_walk_three_point");
  auto r = runEmbody("render --motion " + bvh + " --three-point --frames 90 --fps 30 --size 64x64 --view stereo" +
                     budgetArg(100) + "--user-height 1.75 --out " + out.string(), true);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  CHECK(pngSize(out / "frame_00089.png") == std::pair<uint32_t, uint32_t>(128, 64));  // the stereo pair side by side
  const auto j = readJson(out / "stats.json");
  CHECK(j["body"]["three_point"] == true);
  CHECK(j["body"]["steps"].get<int>() >= 4);
  CHECK(j["tracking"]["non_finite_frames"] == 0);
}

TEST_CASE("embody render --motion synthetic:seated --seated renders a seated avatar with its pose numbers", "[cli][render]") {
  const auto out = outDir("render_seated");
  auto r = runEmbody("render --motion synthetic:seated --seated --frames 60 --fps 30 --size 64x64" + budgetArg(100) +
                     "--out " + out.string(), true);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  CHECK(pngSize(out / "frame_00059.png") == std::pair<uint32_t, uint32_t>(64, 64));
  const auto j = readJson(out / "stats.json");
  INFO(j.dump());
  CHECK(j["tracking"]["non_finite_frames"] == 0);
  CHECK(j["tracking"]["head_error_p95_m"].get<double>() < 0.02);
  REQUIRE(j["seated"].is_object());
  CHECK(j["seated"]["frames"] == 60);
  CHECK(j["seated"]["hip_joint_drift_max_m"].get<double>() < 0.01);
  CHECK(j["seated"]["sole_height_m"][0].get<double>() > -0.01);
  CHECK(j["seated"]["knee_flexion_deg"][0].get<double>() > 70.0);
  CHECK(j["seated"]["knee_flexion_deg"][1].get<double>() < 110.0);
  // Without --motion there is nothing to sit.
  CHECK(runEmbody("render --seated --out " + out.string()).exitCode == 2);
}

TEST_CASE("embody render --motion reports bad input with exit codes 1 and 2", "[cli][render]") {
  const auto out = outDir("render_motion_errors");
  auto unknown = runEmbody("render --motion synthetic:moonwalk --out " + out.string(), true);
  CHECK(unknown.exitCode == 1);
  CHECK(unknown.output.find("figure8") != std::string::npos);  // lists the known motions
  CHECK(runEmbody("render --motion synthetic:idle --size 12 --out " + out.string()).exitCode == 2);
  CHECK(runEmbody("render --motion synthetic:idle --frames 0 --out " + out.string()).exitCode == 2);
  CHECK(runEmbody("render --motion synthetic:idle --ik-budget-ms -1 --out " + out.string()).exitCode == 2);
  CHECK(runEmbody("render --motion synthetic:idle --user-height 9 --out " + out.string()).exitCode == 2);
  CHECK(runEmbody("render --motion synthetic:idle --spine wobbly --out " + out.string()).exitCode == 2);
  auto noProfile = runEmbody("render --motion synthetic:idle --profile /nonexistent.json --out " + out.string(), true);
  CHECK(noProfile.exitCode == 1);
  CHECK(noProfile.output.find("profile") != std::string::npos);
}

TEST_CASE("embody demo writes frames, a contact sheet and stats to --out", "[cli][demo]") {
  const auto out = outDir("demo");
  auto r = runEmbody("demo --frames 3 --size 64x64 --no-mirror --out " + out.string(), true);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  CHECK(fs::exists(out / "frame_00002.png"));
  CHECK(fs::exists(out / "contact_sheet.png"));
  CHECK(readJson(out / "stats.json")["frames"] == 3);
  CHECK(r.output.find("mirror: skipped") != std::string::npos);
}

namespace {
std::string fileBytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}
}  // namespace

TEST_CASE("embody render --ik-iterations: the same command gives the same output bytes", "[cli][render]") {
  // A BVH clip at three points (feet stepping, the hardest case for the warm start): with a fixed
  // iteration count the frames and every tracking figure repeat to the bit; only timings differ.
  EMBODY_REQUIRE_SHARED_ASSET(clip, "cmu_12_01_walk.bvh");
  std::array<fs::path, 2> outs{outDir("render_iterations_a"), outDir("render_iterations_b")};
  for (const auto& out : outs) {
    auto r = runEmbody("render --avatar default --motion " + clip + " --three-point --frames 8 --fps 30 --size 64x64 "
                       "--ik-iterations 3 --device lavapipe --out " + out.string(), true);
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
  }
  for (int i = 0; i < 8; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.png", i);
    INFO(name);
    const std::string a = fileBytes(outs[0] / name);
    CHECK(!a.empty());
    CHECK(a == fileBytes(outs[1] / name));
  }
  const auto a = readJson(outs[0] / "stats.json"), b = readJson(outs[1] / "stats.json");
  CHECK(a["tracking"].dump() == b["tracking"].dump());
  CHECK(a["trackers"].dump() == b["trackers"].dump());
  CHECK(a["ik"]["iterations_mean"] == b["ik"]["iterations_mean"]);
  CHECK(a["ik"]["deadline_misses"] == 0);
}

TEST_CASE("embody render --ik-iterations rejects counts outside 1 .. 1000", "[cli][render]") {
  for (const char* bad : {"0", "-2", "1001", "x"}) {
    auto r = runEmbody(std::string("render --motion synthetic:figure8 --frames 1 --ik-iterations ") + bad + " --out " +
                           outDir("render_iterations_bad").string(), true);
    INFO(r.output);
    CHECK(r.exitCode == 2);
    CHECK(r.output.find("--ik-iterations") != std::string::npos);
  }
}

TEST_CASE("embody render --avatar CLIP.bvh --motion CLIP.bvh takes the --bvh-* overrides for both", "[cli][render]") {
  // The Mixamo fixture spun about its X axis over 48 frames: no direction keeps the head above the
  // feet, so the axes must be given. As the avatar the clip was loaded without them and failed
  // with a message asking for the very --bvh-up the command had been given.
  const fs::path out = outDir("render_bvh_overrides");
  fs::create_directories(out);
  const std::string clip = tumblingClip("mixamo.bvh", out / "tumble.bvh");
  const std::string common = " --frames 2 --fps 30 --size 64x64 --device lavapipe --out ";
  auto r = runEmbody("render --avatar " + clip + " --motion " + clip + common + (out / "measured").string(), true);
  CHECK(r.exitCode == 1);
  CHECK(r.output.find("--bvh-up") != std::string::npos);
  r = runEmbody("render --avatar " + clip + " --motion " + clip + " --bvh-up +Y --bvh-forward +Z" + common + (out / "given").string(), true);
  INFO(r.output);
  CHECK(r.exitCode == 0);
  CHECK(readJson(out / "given" / "stats.json")["frames"] == 2);
}
