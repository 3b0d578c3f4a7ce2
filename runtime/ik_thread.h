#pragma once
// The IK thread: the tracking side submits samples, the thread runs IkStage on the newest one
// (filter, loss guard, budgeted warm-started solve) and publishes a SolvedFrame; the render side
// takes the newest completed frame. Both hand-offs are lock-free triple buffers: submit() and
// acquire() never block, so the render thread never waits on the solver. Samples arriving faster
// than they are solved are skipped (counted in samplesSkipped()), never queued.
#include <atomic>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

#include "runtime/ik_stage.h"
#include "runtime/triple_buffer.h"

namespace embody::runtime {

// The scheduling the IK thread obtained (IkThread::priority): SCHED_FIFO, nice -10, or neither.
enum class IkThreadPriority { Normal, Raised, Realtime };
const char* toString(IkThreadPriority p);

class IkThread {
 public:
  // `initialPose` sizes every slot (and is what acquire() returns before the first solve).
  IkThread(BodySolver& solver, const Clock& clock, const IkStageConfig& config, const avatar::SkeletonPose& initialPose);
  // Any per-sample work in place of IkStage (e.g. runtime::TrackedAvatarBody::solveInto, which also
  // places the body in the tracking space). Runs on the IK thread only.
  using Process = std::function<void(const tracking::PoseSample& sample, SolvedFrame& out)>;
  IkThread(Process process, const avatar::SkeletonPose& initialPose);
  ~IkThread();
  IkThread(const IkThread&) = delete;
  IkThread& operator=(const IkThread&) = delete;

  void start();
  void stop();  // joins; safe to call twice

  // Tracking side (one thread): hands over the newest sample.
  void submit(const tracking::PoseSample& sample);

  // Any thread: the stage starts afresh (filter, loss guard, warm start: IkStage::reset) before
  // its next solve. After a recenter the trackers jump by design; without this the filter would
  // glide the body across the room and the warm start would begin from the old place. A thread
  // built with a Process owns its state and ignores this.
  void requestReset() { resetRequested_.store(true, std::memory_order_release); }

  // Render side (one thread): takes the newest completed frame; true when it is new.
  bool acquire() { return output_.acquire(); }
  const SolvedFrame& frame() const { return output_.front(); }

  uint32_t framesSolved() const { return solved_.load(std::memory_order_acquire); }
  uint32_t samplesSubmitted() const { return submitted_.load(std::memory_order_acquire); }
  uint32_t samplesSkipped() const { return skipped_.load(std::memory_order_relaxed); }
  // What the thread got when it started (Normal before start()).
  IkThreadPriority priority() const { return priority_.load(std::memory_order_acquire); }
  // Blocks the caller (a test, an offline driver; not the render loop) until at least `count`
  // frames are solved or `timeoutSeconds` of wall time pass; true when reached.
  bool waitForFrames(uint32_t count, double timeoutSeconds) const;
  // The render loop's join: blocks until every sample submitted so far is solved or skipped, or
  // until `deadline` (steady clock), whichever comes first; never past the deadline. True when
  // caught up. Then acquire() takes the newest frame either way.
  bool waitUntilCaughtUp(std::chrono::steady_clock::time_point deadline);

 private:
  void run();

  std::optional<IkStage> stage_;
  Process process_;
  TripleBuffer<tracking::PoseSample> input_;
  TripleBuffer<SolvedFrame> output_;
  std::atomic<uint32_t> submitted_{0};
  std::atomic<uint32_t> solved_{0};
  std::atomic<uint32_t> skipped_{0};
  std::atomic<bool> running_{false};
  std::atomic<bool> resetRequested_{false};
  std::atomic<IkThreadPriority> priority_{IkThreadPriority::Normal};
  std::thread thread_;
  std::mutex doneMutex_;  // only for the join's timed wait (done_); the hand-offs stay lock-free
  std::condition_variable done_;
};

}  // namespace embody::runtime
