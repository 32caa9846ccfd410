// parallel.h - the project's one parallel loop: [0, count) cut into chunks of `chunk` items that
// worker threads claim, in increasing order, from one atomic counter, calling fn(begin, end) for
// each. Header-only, so libvff exports nothing for it: the writer includes it from here, and every
// other caller (the baker, the tools, the Python module, the GPU harness, the samples) links the
// CMake target vff_parallel (libvff/CMakeLists.txt) and includes "platform/parallel.h".
//
// The contract, the same for parallelFor, parallelForWorkers and WorkerPool:
// * threads == 0 means every core (std::thread::hardware_concurrency(), at least 1): resolveThreads.
//   The calling thread is worker 0. The free loops start at most one worker per chunk
//   (workerCount), so with one (threads == 1, or count <= chunk) they run inline, starting no thread.
// * Which worker runs a chunk, and when, depends on timing: fn writes its results by index (never
//   in the order chunks complete), so that they do not depend on the thread count (the project's
//   determinism rule), and it may run concurrently with itself on other chunks.
// * fn may throw: no chunk is handed out after that, the chunks already running finish, and the
//   first exception is rethrown on the calling thread once every worker has stopped.
// * A thread that cannot be started is done without: the loop runs on the workers it has, with the
//   same results.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

namespace vff::parallel {

// `threads`, or every core for 0.
inline unsigned resolveThreads(unsigned threads) noexcept {
  return threads ? threads : std::max(1u, std::thread::hardware_concurrency());
}

// The number of chunks of [0, count) (a chunk of 0 counts as 1).
inline size_t chunkCount(size_t count, size_t chunk) noexcept {
  chunk = std::max<size_t>(1, chunk);
  return count / chunk + (count % chunk != 0);
}

// The workers a loop over `count` items in chunks of `chunk` runs on (at least 1): the worker
// indices parallelForWorkers passes are below it, so per-worker state can be sized with it.
inline unsigned workerCount(size_t count, size_t chunk, unsigned threads) noexcept {
  return unsigned(std::clamp<size_t>(chunkCount(count, chunk), 1, resolveThreads(threads)));
}

// One loop's chunks and what its workers share: the counter they claim chunks from, and the first
// exception thrown.
class ChunkLoop {
 public:
  ChunkLoop(size_t count, size_t chunk) noexcept
      : count_(count), chunk_(std::max<size_t>(1, chunk)), chunks_(chunkCount(count, chunk)) {}

  // fn(worker, begin, end) for each chunk claimed, until none is left or fn has thrown anywhere.
  template <class Fn>
  void work(unsigned worker, Fn& fn) noexcept {
    try {
      for (size_t c; (c = next_.fetch_add(1, std::memory_order_relaxed)) < chunks_;) {
        const size_t begin = c * chunk_;
        fn(worker, begin, std::min(count_, begin + chunk_));
      }
    } catch (...) {
      fail(std::current_exception());
    }
  }
  // Rethrows the first exception a worker caught (after every worker has stopped).
  void rethrow() const {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void fail(std::exception_ptr e) noexcept {
    next_.store(chunks_, std::memory_order_relaxed);  // hand out no further chunk
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!error_) error_ = std::move(e);
  }

  const size_t count_, chunk_, chunks_;
  std::atomic<size_t> next_{0};
  std::mutex mutex_;
  std::exception_ptr error_;
};

// fn(worker, begin, end) over the chunks of [0, count), on workerCount(count, chunk, threads)
// workers started for this call: `worker` (below that count) names the thread, for state of its
// own (scratch buffers, a non-thread-safe accessor, partial sums merged afterwards in worker order).
template <class Fn>
void parallelForWorkers(size_t count, size_t chunk, unsigned threads, Fn&& fn) {
  if (count == 0) return;
  ChunkLoop loop(count, chunk);
  const unsigned workers = workerCount(count, chunk, threads);
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  for (unsigned w = 1; w < workers; ++w) {
    try {
      pool.emplace_back([&loop, &fn, w] { loop.work(w, fn); });
    } catch (...) {
      break;  // no more threads: the workers started share the chunks
    }
  }
  loop.work(0, fn);
  for (std::thread& t : pool) t.join();
  loop.rethrow();
}

// fn(begin, end) over the chunks of [0, count) on up to `threads` threads (0: every core).
template <class Fn>
void parallelFor(size_t count, size_t chunk, unsigned threads, Fn&& fn) {
  parallelForWorkers(count, chunk, threads, [&fn](unsigned, size_t begin, size_t end) { fn(begin, end); });
}

// The same loops on threads started once and kept, for a caller that runs many loops and must not
// pay for starting threads in each (a benchmark timing its passes). The calling thread is worker 0;
// the others sleep between loops (C++20 atomic waits). A loop waits only for the helpers that joined
// it: one the system has not yet woken when the chunks run out stays out of it. One loop at a
// time, run by the thread that owns the pool.
class WorkerPool {
 public:
  // resolveThreads(threads) workers; returns once every started thread is waiting.
  explicit WorkerPool(unsigned threads) {
    const unsigned want = resolveThreads(threads);
    helpers_.reserve(want - 1);
    for (unsigned w = 1; w < want; ++w) {
      try {
        helpers_.emplace_back([this, w] { helper(w); });
      } catch (...) {
        break;  // fewer workers, the same results
      }
    }
    for (unsigned s; (s = started_.load(std::memory_order_acquire)) < helpers_.size();) started_.wait(s);
  }
  ~WorkerPool() {
    stop_.store(true, std::memory_order_relaxed);
    state_.store(nextGeneration(state_.load(std::memory_order_relaxed)), std::memory_order_release);
    state_.notify_all();
    for (std::thread& t : helpers_) t.join();
  }
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // The workers, the calling thread included: worker indices are below it.
  unsigned size() const noexcept { return unsigned(helpers_.size()) + 1; }

  // As the free parallelForWorkers, on this pool's workers.
  template <class Fn>
  void parallelForWorkers(size_t count, size_t chunk, Fn&& fn) {
    if (count == 0) return;
    ChunkLoop loop(count, chunk);
    using F = std::remove_reference_t<Fn>;
    struct Job {
      ChunkLoop* loop;
      F* fn;
    } job{&loop, &fn};
    if (!helpers_.empty()) {
      job_ = [](void* j, unsigned w) {
        Job& jb = *static_cast<Job*>(j);
        jb.loop->work(w, *jb.fn);
      };
      context_ = &job;
      state_.store(nextGeneration(state_.load(std::memory_order_relaxed)) | kOpen, std::memory_order_release);
      state_.notify_all();
    }
    loop.work(0, fn);
    if (!helpers_.empty()) {
      // Closed to helpers still asleep; then wait for those inside to leave.
      for (uint64_t s = state_.fetch_and(~kOpen, std::memory_order_acq_rel) & ~kOpen; (s & kCount) != 0;
           s = state_.load(std::memory_order_acquire))
        state_.wait(s, std::memory_order_acquire);
    }
    loop.rethrow();
  }
  // As the free parallelFor, on this pool's workers.
  template <class Fn>
  void parallelFor(size_t count, size_t chunk, Fn&& fn) {
    parallelForWorkers(count, chunk, [&fn](unsigned, size_t begin, size_t end) { fn(begin, end); });
  }

 private:
  // state_: the loop's generation (high 32 bits), whether it is open to helpers, and how many
  // helpers are inside it. Each new generation is a loop to join, or the stop.
  static constexpr uint64_t kOpen = uint64_t(1) << 31;
  static constexpr uint64_t kCount = kOpen - 1;
  static uint64_t nextGeneration(uint64_t s) noexcept { return ((s >> 32) + 1) << 32; }

  void helper(unsigned w) {
    started_.fetch_add(1, std::memory_order_release);
    started_.notify_one();
    uint64_t seen = 0;  // the generation last handled
    for (;;) {
      uint64_t s = state_.load(std::memory_order_acquire);
      if ((s >> 32) == seen) {
        state_.wait(s, std::memory_order_acquire);
        continue;
      }
      seen = s >> 32;
      if (stop_.load(std::memory_order_relaxed)) return;
      bool joined = false;
      while ((s & kOpen) && !(joined = state_.compare_exchange_weak(s, s + 1, std::memory_order_acq_rel,
                                                                     std::memory_order_acquire))) {
      }
      if (!joined) continue;  // that loop is over
      seen = s >> 32;  // (the loop joined, should a newer one have opened meanwhile)
      job_(context_, w);
      const uint64_t left = state_.fetch_sub(1, std::memory_order_acq_rel) - 1;
      if ((left & kCount) == 0 && !(left & kOpen)) state_.notify_all();  // the caller waits for it
    }
  }

  std::vector<std::thread> helpers_;
  std::atomic<unsigned> started_{0};
  std::atomic<uint64_t> state_{0};
  std::atomic<bool> stop_{false};
  // Written before a loop opens (release), read by the helpers that join it (acquire).
  void (*job_)(void*, unsigned) = nullptr;
  void* context_ = nullptr;
};

}  // namespace vff::parallel
