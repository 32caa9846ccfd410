// test_parallel.cpp - the project's one parallel loop (libvff/src/platform/parallel.h): every item
// in exactly one chunk for any count, chunk and thread count; one thread runs inline; an exception
// reaches the caller; a result written by index is the same for every thread count; the worker
// pool does the same over many loops.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "platform/parallel.h"

namespace {

using vff::parallel::parallelFor;
using vff::parallel::parallelForWorkers;
using vff::parallel::WorkerPool;

// How often each item of [0, count) was visited, and whether every chunk was whole and aligned.
struct Coverage {
  std::vector<std::atomic<int>> visits;
  std::atomic<bool> badChunk{false};
  explicit Coverage(size_t count) : visits(count) {}
  void visit(size_t begin, size_t end, size_t count, size_t chunk) {
    const size_t c = std::max<size_t>(1, chunk);
    if (begin % c != 0 || end <= begin || end > count || end - begin != std::min(c, count - begin)) badChunk = true;
    for (size_t i = begin; i < end && i < visits.size(); ++i) visits[i]++;
  }
  // The first item not visited exactly once, or count.
  size_t firstWrong() const {
    for (size_t i = 0; i < visits.size(); ++i)
      if (visits[i] != 1) return i;
    return visits.size();
  }
};

TEST(Parallel, ChunksCoverEveryItemExactlyOnce) {
  const size_t counts[] = {0, 1, 2, 7, 100, 4097};
  const size_t chunks[] = {0, 1, 3, 64, 100000};
  const unsigned threads[] = {0, 1, 2, 3, 8};
  for (size_t count : counts)
    for (size_t chunk : chunks)
      for (unsigned t : threads) {
        Coverage c(count);
        parallelFor(count, chunk, t, [&](size_t b, size_t e) { c.visit(b, e, count, chunk); });
        EXPECT_EQ(c.firstWrong(), count) << "count " << count << ", chunk " << chunk << ", threads " << t;
        EXPECT_FALSE(c.badChunk) << "count " << count << ", chunk " << chunk << ", threads " << t;
      }
}

TEST(Parallel, WorkerIndicesStayBelowTheWorkerCount) {
  for (size_t count : {1u, 5u, 100u, 5000u})
    for (unsigned t : {0u, 1u, 2u, 4u, 16u}) {
      const unsigned workers = vff::parallel::workerCount(count, 7, t);
      EXPECT_GE(workers, 1u);
      EXPECT_LE(workers, vff::parallel::resolveThreads(t));
      EXPECT_LE(workers, vff::parallel::chunkCount(count, 7));
      std::atomic<unsigned> highest{0};
      Coverage c(count);
      parallelForWorkers(count, 7, t, [&](unsigned w, size_t b, size_t e) {
        for (unsigned h = highest; w > h && !highest.compare_exchange_weak(h, w);) {
        }
        c.visit(b, e, count, 7);
      });
      EXPECT_LT(highest.load(), workers) << "count " << count << ", threads " << t;
      EXPECT_EQ(c.firstWrong(), count);
    }
}

TEST(Parallel, OneThreadRunsInlineInOrder) {
  const std::thread::id caller = std::this_thread::get_id();
  std::vector<size_t> begins;
  bool elsewhere = false;
  parallelFor(1000, 10, 1, [&](size_t b, size_t) {
    elsewhere |= std::this_thread::get_id() != caller;
    begins.push_back(b);  // (no lock: inline)
  });
  EXPECT_FALSE(elsewhere);
  ASSERT_EQ(begins.size(), 100u);
  for (size_t k = 0; k < begins.size(); ++k) EXPECT_EQ(begins[k], 10 * k);
  // One chunk in all runs inline whatever the thread count.
  elsewhere = false;
  parallelFor(5, 10, 8, [&](size_t, size_t) { elsewhere |= std::this_thread::get_id() != caller; });
  EXPECT_FALSE(elsewhere);
}

TEST(Parallel, ManyThreadsRunOnSeveralThreads) {
  std::mutex m;
  std::set<std::thread::id> ids;
  // Each chunk waits a little, so that the other workers claim chunks too.
  parallelFor(64, 1, 4, [&](size_t, size_t) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const std::lock_guard<std::mutex> lock(m);
    ids.insert(std::this_thread::get_id());
  });
  EXPECT_GT(ids.size(), 1u);
  EXPECT_LE(ids.size(), 4u);
}

TEST(Parallel, AnExceptionReachesTheCallerAndStopsTheLoop) {
  for (unsigned t : {1u, 2u, 4u}) {
    std::atomic<size_t> ran{0};
    try {
      parallelFor(100000, 1, t, [&](size_t b, size_t) {
        ++ran;
        if (b == 10) throw std::runtime_error("chunk 10");
      });
      ADD_FAILURE() << "no exception with " << t << " threads";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "chunk 10");
    }
    // No chunk is handed out after the throw: far fewer than all of them ran.
    EXPECT_LT(ran.load(), 100000u) << t << " threads";
  }
  // The first of several is the one rethrown; the others are dropped.
  EXPECT_THROW(parallelFor(64, 1, 4, [](size_t, size_t) { throw std::logic_error("every chunk"); }), std::logic_error);
}

// A result computed per chunk and written by index (then reduced in index order) is the same bits
// for every thread count, although the chunks finish in another order each time.
std::vector<double> partialSums(unsigned threads, size_t count, size_t chunk) {
  std::vector<double> sums(vff::parallel::chunkCount(count, chunk));
  parallelFor(count, chunk, threads, [&](size_t b, size_t e) {
    double s = 0;
    for (size_t i = b; i < e; ++i) s += std::sin(double(i)) * 1e-3 + 1.0 / double(i + 1);
    sums[b / chunk] = s;
  });
  return sums;
}

TEST(Parallel, AReductionWrittenByIndexDoesNotDependOnTheThreadCount) {
  const size_t count = 50021, chunk = 97;
  auto reduce = [](const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return s;
  };
  const std::vector<double> one = partialSums(1, count, chunk);
  for (unsigned t : {0u, 2u, 3u, 8u, 16u}) {
    const std::vector<double> many = partialSums(t, count, chunk);
    ASSERT_EQ(many.size(), one.size());
    for (size_t k = 0; k < one.size(); ++k) ASSERT_EQ(many[k], one[k]) << "chunk " << k << ", threads " << t;
    EXPECT_EQ(reduce(many), reduce(one)) << t << " threads";
  }
}

TEST(Parallel, APoolRunsManyLoopsAndRethrows) {
  WorkerPool pool(4);
  EXPECT_GE(pool.size(), 1u);
  EXPECT_LE(pool.size(), 4u);
  for (size_t count : {0u, 1u, 3u, 1000u, 4097u}) {
    for (int round = 0; round < 10; ++round) {
      Coverage c(count);
      std::atomic<unsigned> highest{0};
      pool.parallelForWorkers(count, 16, [&](unsigned w, size_t b, size_t e) {
        for (unsigned h = highest; w > h && !highest.compare_exchange_weak(h, w);) {
        }
        c.visit(b, e, count, 16);
      });
      ASSERT_EQ(c.firstWrong(), count) << "count " << count << ", round " << round;
      ASSERT_FALSE(c.badChunk);
      ASSERT_LT(highest.load(), pool.size());
    }
  }
  EXPECT_THROW(pool.parallelFor(100, 1, [](size_t b, size_t) {
    if (b == 50) throw std::out_of_range("50");
  }), std::out_of_range);
  // The pool is still usable after a loop threw.
  Coverage c(500);
  pool.parallelFor(500, 3, [&](size_t b, size_t e) { c.visit(b, e, 500, 3); });
  EXPECT_EQ(c.firstWrong(), 500u);
  // The same partial sums as the free loop on one thread.
  const size_t count = 20011, chunk = 61;
  std::vector<double> sums(vff::parallel::chunkCount(count, chunk));
  pool.parallelFor(count, chunk, [&](size_t b, size_t e) {
    double s = 0;
    for (size_t i = b; i < e; ++i) s += std::sin(double(i)) * 1e-3 + 1.0 / double(i + 1);
    sums[b / chunk] = s;
  });
  EXPECT_EQ(sums, partialSums(1, count, chunk));
}

TEST(Parallel, APoolOfOneRunsInline) {
  WorkerPool pool(1);
  EXPECT_EQ(pool.size(), 1u);
  const std::thread::id caller = std::this_thread::get_id();
  bool elsewhere = false;
  pool.parallelFor(100, 1, [&](size_t, size_t) { elsewhere |= std::this_thread::get_id() != caller; });
  EXPECT_FALSE(elsewhere);
}

}  // namespace
