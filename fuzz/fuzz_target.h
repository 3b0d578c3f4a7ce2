#pragma once
// One fuzz target per parser of outside data (docs/reliability.md). A target file defines its body
// with EMBODY_FUZZ_TARGET(name): under libFuzzer (the clang build-fuzz tree, EMBODY_LIBFUZZER) that
// is LLVMFuzzerTestOneInput; in the normal build it registers `name` with the replay driver
// (fuzz/replay_main.cpp), one executable that replays every kept corpus in CI.
//
// A target returns 0 and never crashes on any input; an accepted input that breaks an invariant
// of the parsed data (a NaN, an index out of range) is a bug too: EMBODY_FUZZ_CHECK aborts.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

namespace embody::fuzz {

using TargetFn = int (*)(const uint8_t* data, size_t size);
bool registerTarget(const char* name, TargetFn fn);

[[noreturn]] inline void invariantBroken(const char* what, const char* file, int line) {
  std::fprintf(stderr, "%s:%d: fuzz invariant broken: %s\n", file, line, what);
  std::abort();
}

}  // namespace embody::fuzz

#define EMBODY_FUZZ_CHECK(cond) \
  ((cond) ? static_cast<void>(0) : ::embody::fuzz::invariantBroken(#cond, __FILE__, __LINE__))

#ifdef EMBODY_LIBFUZZER
#define EMBODY_FUZZ_TARGET(name) extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
#else
#define EMBODY_FUZZ_TARGET(name)                                                                 \
  static int embodyFuzz_##name(const uint8_t* data, size_t size);                                \
  [[maybe_unused]] static const bool embodyFuzzRegistered_##name =                              \
      ::embody::fuzz::registerTarget(#name, embodyFuzz_##name);                                  \
  static int embodyFuzz_##name(const uint8_t* data, size_t size)
#endif
