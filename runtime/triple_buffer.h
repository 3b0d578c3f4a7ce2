#pragma once
// A lock-free triple buffer: one writer, one reader, three slots. The writer fills its back slot
// and publishes it without ever blocking; the reader takes the newest published slot without
// ever blocking and keeps it until it asks again. Intermediate slots the reader never took are
// simply overwritten (the reader wants the newest pose, not every pose).
//
// The "middle" slot index and a fresh-data bit live in one atomic byte; publish and acquire are
// each one exchange (acq_rel), which hands the slot's contents over with the right ordering.
#include <array>
#include <atomic>
#include <cstdint>

namespace embody::runtime {

template <class T>
class TripleBuffer {
 public:
  TripleBuffer() = default;
  explicit TripleBuffer(const T& initial) { slots_.fill(initial); }
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  // Writer side.
  T& back() { return slots_[back_]; }
  void publish() { back_ = static_cast<uint8_t>(middle_.exchange(static_cast<uint8_t>(back_ | kFresh), std::memory_order_acq_rel) & kIndex); }

  // Reader side: takes the newest published slot if there is one; true when it changed.
  bool acquire() {
    if ((middle_.load(std::memory_order_relaxed) & kFresh) == 0) return false;
    front_ = static_cast<uint8_t>(middle_.exchange(front_, std::memory_order_acq_rel) & kIndex);
    return true;
  }
  const T& front() const { return slots_[front_]; }
  T& front() { return slots_[front_]; }

  // Either side, for initialisation before the threads start.
  std::array<T, 3>& slots() { return slots_; }

 private:
  static constexpr uint8_t kIndex = 0x3, kFresh = 0x4;
  std::array<T, 3> slots_{};
  alignas(64) std::atomic<uint8_t> middle_{1};
  uint8_t back_ = 0;   // writer-owned
  uint8_t front_ = 2;  // reader-owned
};

}  // namespace embody::runtime
