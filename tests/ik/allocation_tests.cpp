// A counting allocator proves that solve() allocates nothing after setup. Replacing the global
// operator new in this translation unit replaces it for the whole test executable; counting is
// only switched on inside the measured scope.
#include <catch2/catch.hpp>

#include <atomic>
#include <cstdlib>
#include <new>

#include "tests/support/sample_models.h"
#include "ik/solver.h"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};

void* countedAlloc(std::size_t size) {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}

struct CountAllocations {
  CountAllocations() {
    g_allocations = 0;
    g_counting = true;
  }
  ~CountAllocations() { g_counting = false; }
  long count() const { return g_allocations.load(); }
};
}  // namespace

void* operator new(std::size_t size) { return countedAlloc(size); }
void* operator new[](std::size_t size) { return countedAlloc(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
// The nothrow forms too (Catch2 uses them): every new in the program must pair with our delete,
// or AddressSanitizer rightly reports an allocation/deallocation mismatch.
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
  return std::malloc(size ? size : 1);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept { return operator new(size, tag); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

using namespace embody;
using namespace embody::ik;

namespace {

// Solves a sequence of target sets that exercise the clamping loop (joint limits pinned) and
// unreachable targets; returns the allocations counted during the solves after the first.
long allocationsDuringSolves(const Model& model, Path path, bool warm = false) {
  Data data(model);
  SolveOptions o;
  o.path = path;
  o.warm_active_set = warm;
  o.max_iterations = 20;
  std::vector<Eigen::Vector3d> offsets = {{0.3, 0.2, 0.1}, {-0.4, 0.5, 0.2}, {2.0, 2.0, 2.0}, {0.0, -0.3, 0.4}};
  std::vector<Eigen::Vector3d> base;
  for (size_t t = 0; t < model.tasks.size(); ++t) base.push_back(data.taskPosition(static_cast<TaskId>(t)));
  (void)solve(model, data, o);  // the first call may touch lazily initialised statics
  long total = 0;
  int clamped = 0;
  for (const Eigen::Vector3d& off : offsets) {
    CountAllocations counter;  // measures setting valid targets and solving
    for (size_t t = 0; t < model.tasks.size(); ++t)
      if (model.tasks[t].desc.type != TaskType::Orientation)
        (void)data.setTarget(static_cast<TaskId>(t), Eigen::Vector3d(base[t] + off * (t % 2 ? 1.0 : -0.5)));
    const SolveReport& r = solve(model, data, o);
    clamped += r.active_clamps.empty() ? 0 : 1;
    total += counter.count();
  }
  CHECK(clamped > 0);  // the clamping loop ran
  return total;
}

}  // namespace

TEST_CASE("solve allocates nothing after the first call (fast path, humanoid and coupled spine)") {
  CHECK(allocationsDuringSolves(test::sampleHumanoid().value(), Path::Fast) == 0);
  CHECK(allocationsDuringSolves(test::sampleSpine(true).value(), Path::Fast) == 0);
  CHECK(allocationsDuringSolves(test::sampleSpine(false).value(), Path::Fast) == 0);
}

TEST_CASE("solve allocates nothing after the first call (reference path)") {
  CHECK(allocationsDuringSolves(test::sampleHumanoid().value(), Path::Reference) == 0);
  CHECK(allocationsDuringSolves(test::sampleSpine(true).value(), Path::Reference) == 0);
}

TEST_CASE("solve allocates nothing after the first call with the warm active set (both paths)") {
  for (Path path : {Path::Fast, Path::Reference}) {
    CHECK(allocationsDuringSolves(test::sampleHumanoid().value(), path, true) == 0);
    CHECK(allocationsDuringSolves(test::sampleSpine(true).value(), path, true) == 0);
  }
}

TEST_CASE("the counting allocator counts (sanity check of the test itself)") {
  CountAllocations counter;
  std::vector<int>* v = new std::vector<int>(100);
  delete v;
  CHECK(counter.count() >= 2);
}
