#pragma once
// Counts heap allocations (every operator new of the test executable, allocation_counter.cpp)
// while a CountAllocations is alive: how many, and the largest single request.
#include <cstddef>

namespace embody::test {

struct AllocationCounts {
  long count = 0;
  size_t largestBytes = 0;
};

class CountAllocations {
 public:
  CountAllocations();
  ~CountAllocations();
  CountAllocations(const CountAllocations&) = delete;
  CountAllocations& operator=(const CountAllocations&) = delete;
  AllocationCounts counts() const;
};

}  // namespace embody::test
