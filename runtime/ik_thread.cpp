#include "runtime/ik_thread.h"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <chrono>

#include "core/enum_names.h"

namespace embody::runtime {

IkThread::IkThread(BodySolver& solver, const Clock& clock, const IkStageConfig& config,
                   const avatar::SkeletonPose& initialPose)
    : stage_(std::in_place, solver, clock, config) {
  process_ = [this](const tracking::PoseSample& sample, SolvedFrame& out) { stage_->process(sample, out); };
  SolvedFrame f;
  f.pose = initialPose;
  for (auto& s : output_.slots()) s = f;
}

IkThread::IkThread(Process process, const avatar::SkeletonPose& initialPose) : process_(std::move(process)) {
  SolvedFrame f;
  f.pose = initialPose;
  for (auto& s : output_.slots()) s = f;
}

IkThread::~IkThread() { stop(); }

namespace {

// The IK thread sleeps between samples and works a budget of about a millisecond when one comes:
// it should win the CPU over bulk work (shader compiles, a build, the rasteriser's workers) the
// way a headset runtime's compositor does. It asks for the lowest real-time priority (SCHED_FIFO
// 1: it preempts every normal thread at once, and the kernel's real-time throttling still leaves
// the others their share should a solve ever run away), else nice -10; without the right to
// either (not root, no CAP_SYS_NICE) it keeps the normal priority. Which one it got is reported.
IkThreadPriority raiseThisThreadsPriority() {
  sched_param param{};
  param.sched_priority = 1;
  if (pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0) return IkThreadPriority::Realtime;
  const auto tid = static_cast<id_t>(syscall(SYS_gettid));
  if (setpriority(PRIO_PROCESS, tid, -10) == 0) return IkThreadPriority::Raised;
  return IkThreadPriority::Normal;
}

}  // namespace

void IkThread::start() {
  if (running_.exchange(true)) return;
  thread_ = std::thread([this] {
    priority_.store(raiseThisThreadsPriority(), std::memory_order_release);
    run();
  });
}

constexpr EnumName<IkThreadPriority> kIkThreadPriorityNames[] = {{IkThreadPriority::Realtime, "realtime"},
                                                                 {IkThreadPriority::Raised, "nice -10"},
                                                                 {IkThreadPriority::Normal, "normal"}};

const char* toString(IkThreadPriority p) {
  return enumName(kIkThreadPriorityNames, p, "normal");
}

void IkThread::stop() {
  if (!running_.exchange(false)) return;
  submitted_.fetch_add(1, std::memory_order_acq_rel);  // wake the thread
  submitted_.notify_one();
  if (thread_.joinable()) thread_.join();
}

void IkThread::submit(const tracking::PoseSample& sample) {
  input_.back() = sample;
  input_.publish();
  submitted_.fetch_add(1, std::memory_order_acq_rel);
  submitted_.notify_one();
}

void IkThread::run() {
  uint32_t seen = 0;
  while (true) {
    submitted_.wait(seen, std::memory_order_acquire);  // sleeps until submit() or stop()
    const uint32_t now = submitted_.load(std::memory_order_acquire);
    if (!running_.load(std::memory_order_acquire)) break;
    if (now - seen > 1) skipped_.fetch_add(now - seen - 1, std::memory_order_relaxed);
    seen = now;
    if (!input_.acquire()) {
      // submit() publishes before it counts, so an earlier acquire can already have taken this
      // sample (solving it for the previous count, whose own sample it overwrote). That earlier
      // sample was skipped: count it, or framesSolved() + samplesSkipped() falls one short of
      // the samples submitted (a waiter for all of them hung under load).
      {
        std::lock_guard lock(doneMutex_);
        skipped_.fetch_add(1, std::memory_order_relaxed);
      }
      done_.notify_all();
      continue;
    }
    if (resetRequested_.exchange(false, std::memory_order_acq_rel) && stage_) stage_->reset();
    process_(input_.front(), output_.back());
    output_.publish();
    {
      std::lock_guard lock(doneMutex_);  // a joiner between its check and its wait sees this
      solved_.fetch_add(1, std::memory_order_acq_rel);
    }
    solved_.notify_all();
    done_.notify_all();
  }
}

bool IkThread::waitUntilCaughtUp(std::chrono::steady_clock::time_point deadline) {
  const uint32_t target = samplesSubmitted();
  std::unique_lock lock(doneMutex_);
  return done_.wait_until(lock, deadline, [&] {
    // Skipped samples count as handled: their newer sample is the one being solved.
    return framesSolved() + samplesSkipped() >= target || !running_.load(std::memory_order_acquire);
  }) && framesSolved() + samplesSkipped() >= target;
}

bool IkThread::waitForFrames(uint32_t count, double timeoutSeconds) const {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeoutSeconds);
  while (framesSolved() < count) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
  return true;
}

}  // namespace embody::runtime
