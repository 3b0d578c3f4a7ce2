// The global operator new of the reliability test executable, and malloc/calloc/realloc/
// posix_memalign/aligned_alloc as called from the project's code (the executable links with
// -Wl,--wrap for each: Eigen allocates with std::malloc, not operator new). Counts while a
// CountAllocations is alive (any thread).
#include "allocation_counter.h"

#include <atomic>
#include <cstdlib>
#include <new>

extern "C" {
void* __real_malloc(std::size_t);
void* __real_calloc(std::size_t, std::size_t);
void* __real_realloc(void*, std::size_t);
int __real_posix_memalign(void**, std::size_t, std::size_t);
void* __real_aligned_alloc(std::size_t, std::size_t);
}

namespace {
std::atomic<bool> gCounting{false};
std::atomic<long> gCount{0};
std::atomic<size_t> gLargest{0};

void record(std::size_t size) {
  if (!gCounting.load(std::memory_order_relaxed)) return;
  gCount.fetch_add(1, std::memory_order_relaxed);
  size_t prev = gLargest.load(std::memory_order_relaxed);
  while (size > prev && !gLargest.compare_exchange_weak(prev, size, std::memory_order_relaxed)) {
  }
}

void* counted(std::size_t size, bool nothrow) {
  record(size);
  if (void* p = __real_malloc(size ? size : 1)) return p;
  if (nothrow) return nullptr;
  throw std::bad_alloc();
}
}  // namespace

extern "C" {
void* __wrap_malloc(std::size_t size) {
  record(size);
  return __real_malloc(size);
}
void* __wrap_calloc(std::size_t n, std::size_t size) {
  record(n * size);
  return __real_calloc(n, size);
}
void* __wrap_realloc(void* p, std::size_t size) {
  record(size);
  return __real_realloc(p, size);
}
int __wrap_posix_memalign(void** p, std::size_t alignment, std::size_t size) {
  record(size);
  return __real_posix_memalign(p, alignment, size);
}
void* __wrap_aligned_alloc(std::size_t alignment, std::size_t size) {
  record(size);
  return __real_aligned_alloc(alignment, size);
}
}

namespace embody::test {
CountAllocations::CountAllocations() {
  gCount = 0;
  gLargest = 0;
  gCounting = true;
}
CountAllocations::~CountAllocations() { gCounting = false; }
AllocationCounts CountAllocations::counts() const { return {gCount.load(), gLargest.load()}; }
}  // namespace embody::test

void* operator new(std::size_t size) { return counted(size, false); }
void* operator new[](std::size_t size) { return counted(size, false); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return counted(size, true); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return counted(size, true); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
