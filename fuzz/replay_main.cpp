// The fuzz replay driver (gcc, CI): runs a registered target over corpus files, then over
// deterministic mutants of them (byte flips, truncations, spliced numbers), so `make test` checks
// every parser against its kept corpus without a clang/libFuzzer build. Real fuzzing is
// `make fuzz` (docs/reliability.md).
//
//   embody_fuzz_replay TARGET [--mutants N] [--seconds S] PATH...   (files or folders)
//
// On a crash the input is written to crash-TARGET-replay (async-signal-safe) and its origin is
// printed, so it can be replayed alone and kept as a regression file.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "fuzz/fuzz_target.h"

namespace embody::fuzz {
namespace {

std::map<std::string, TargetFn>& targets() {
  static std::map<std::string, TargetFn> t;
  return t;
}

// The input being run, for the crash handler.
const uint8_t* gInput = nullptr;
size_t gInputSize = 0;
char gCrashPath[256] = "crash-replay";
char gOrigin[512] = "";

void onCrash(int sig) {
  const int fd = ::open(gCrashPath, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd >= 0 && gInput) {
    [[maybe_unused]] ssize_t w = ::write(fd, gInput, gInputSize);
    ::close(fd);
  }
  static const char msg[] = "\nembody_fuzz_replay: crash on ";
  [[maybe_unused]] ssize_t w = ::write(2, msg, sizeof msg - 1);
  w = ::write(2, gOrigin, std::strlen(gOrigin));
  w = ::write(2, "; input written to ", 19);
  w = ::write(2, gCrashPath, std::strlen(gCrashPath));
  w = ::write(2, "\n", 1);
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

// splitmix64: a fixed sequence on every machine.
struct Rng {
  uint64_t s;
  uint64_t next() {
    uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  size_t below(size_t n) { return n ? static_cast<size_t>(next() % n) : 0; }
};

// Values that hit limits and conversions: huge counts, negatives, non-finite spellings.
constexpr const char* kSplices[] = {"1000000000", "4294967295", "-1", "1e308", "NaN", "-Infinity",
                                    "null",       "0",          "{}", "[]",    "\"", "99999999999999999999"};

std::vector<uint8_t> mutate(const std::vector<uint8_t>& in, Rng& rng) {
  std::vector<uint8_t> out = in;
  const int edits = 1 + static_cast<int>(rng.below(4));
  for (int e = 0; e < edits; ++e) {
    const size_t at = rng.below(out.size() + 1);
    switch (rng.below(6)) {
      case 0:  // flip a bit
        if (!out.empty()) out[std::min(at, out.size() - 1)] ^= static_cast<uint8_t>(1u << rng.below(8));
        break;
      case 1:  // truncate
        out.resize(at);
        break;
      case 2: {  // splice a hostile token
        const char* s = kSplices[rng.below(std::size(kSplices))];
        out.insert(out.begin() + static_cast<std::ptrdiff_t>(at), s, s + std::strlen(s));
        break;
      }
      case 3: {  // delete a run
        const size_t n = std::min(out.size() - std::min(at, out.size()), 1 + rng.below(16));
        out.erase(out.begin() + static_cast<std::ptrdiff_t>(std::min(at, out.size())),
                  out.begin() + static_cast<std::ptrdiff_t>(std::min(at, out.size()) + n));
        break;
      }
      case 4:  // random byte
        if (!out.empty()) out[std::min(at, out.size() - 1)] = static_cast<uint8_t>(rng.next());
        break;
      default: {  // duplicate a run (repeated blocks: deep nesting, many joints)
        if (out.empty()) break;
        const size_t from = rng.below(out.size());
        const size_t n = std::min(out.size() - from, 1 + rng.below(64));
        std::vector<uint8_t> run(out.begin() + static_cast<std::ptrdiff_t>(from),
                                 out.begin() + static_cast<std::ptrdiff_t>(from + n));
        out.insert(out.begin() + static_cast<std::ptrdiff_t>(std::min(at, out.size())), run.begin(), run.end());
        break;
      }
    }
  }
  return out;
}

std::vector<uint8_t> readFile(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

int usage() {
  std::fprintf(stderr, "usage: embody_fuzz_replay TARGET [--mutants N] [--seconds S] PATH...\ntargets:");
  for (const auto& [name, fn] : targets()) std::fprintf(stderr, " %s", name.c_str());
  std::fprintf(stderr, "\n");
  return 2;
}

}  // namespace

bool registerTarget(const char* name, TargetFn fn) {
  targets()[name] = fn;
  return true;
}

}  // namespace embody::fuzz

int main(int argc, char** argv) {
  using namespace embody::fuzz;
  if (argc < 3 || !targets().count(argv[1])) return usage();
  const std::string name = argv[1];
  const TargetFn fn = targets()[name];
  long mutants = 0;
  double seconds = 1e9;
  std::vector<std::filesystem::path> files;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--mutants" && i + 1 < argc) {
      mutants = std::stol(argv[++i]);
    } else if (a == "--seconds" && i + 1 < argc) {
      seconds = std::stod(argv[++i]);
    } else if (std::filesystem::is_directory(a)) {
      for (const auto& e : std::filesystem::directory_iterator(a))
        if (e.is_regular_file()) files.push_back(e.path());
    } else if (std::filesystem::is_regular_file(a)) {
      files.push_back(a);
    } else {
      std::fprintf(stderr, "embody_fuzz_replay: error: no such file or folder '%s'\n", a.c_str());
      return 2;
    }
  }
  if (files.empty()) {
    std::fprintf(stderr, "embody_fuzz_replay: error: no corpus files\n");
    return 1;
  }
  std::sort(files.begin(), files.end());
  std::snprintf(gCrashPath, sizeof gCrashPath, "crash-%s-replay", name.c_str());
  for (int sig : {SIGSEGV, SIGABRT, SIGFPE, SIGBUS, SIGILL}) std::signal(sig, onCrash);

  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  long runs = 0;
  auto run = [&](const std::vector<uint8_t>& bytes) {
    gInput = bytes.data();
    gInputSize = bytes.size();
    fn(bytes.data(), bytes.size());
    ++runs;
  };
  std::vector<std::vector<uint8_t>> corpus;
  for (const auto& f : files) {
    corpus.push_back(readFile(f));
    std::snprintf(gOrigin, sizeof gOrigin, "%s", f.c_str());
    run(corpus.back());
  }
  Rng rng{0x5EEDull};
  for (long m = 0; m < mutants && elapsed() < seconds; ++m) {
    const size_t k = static_cast<size_t>(m) % files.size();
    std::snprintf(gOrigin, sizeof gOrigin, "mutant %ld of %s", m, files[k].c_str());
    run(mutate(corpus[k], rng));
  }
  std::printf("%s: %ld inputs (%zu corpus files, %ld mutants) in %.2f s, no crash\n", name.c_str(), runs,
              files.size(), runs - static_cast<long>(files.size()), elapsed());
  return 0;
}
