// sampling.cpp - per-pixel random numbers, hemisphere and sphere sampling, the thread pool loop.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>

#include "common.h"

namespace vffx {

namespace {

uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace

Rng::Rng(uint32_t x, uint32_t y, uint32_t stream) {
  const uint64_t key = (uint64_t(x) << 32 | y) ^ splitmix64(stream);
  inc_ = (splitmix64(key ^ 0x5851f42d4c957f2dull) << 1) | 1u;
  state_ = splitmix64(key);
  nextU32();
}

uint32_t Rng::nextU32() {
  const uint64_t old = state_;
  state_ = old * 6364136223846793005ull + inc_;
  const auto xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
  const auto rot = uint32_t(old >> 59u);
  return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
}

float Rng::next01() { return float(nextU32() >> 8) * (1.0f / 16777216.0f); }

void orthonormalBasis(Vec3 n, Vec3* b, Vec3* c) {
  const float s = n.z >= 0 ? 1.0f : -1.0f;
  const float a = -1.0f / (s + n.z);
  const float k = n.x * n.y * a;
  *b = {1.0f + s * n.x * n.x * a, s * k, -s * n.x};
  *c = {k, s + n.y * n.y * a, -n.y};
}

Vec3 cosineDirection(Vec3 n, float u1, float u2) {
  const float r = std::sqrt(u1), phi = 2.0f * kPi * u2;
  const float x = r * std::cos(phi), y = r * std::sin(phi), z = std::sqrt(std::max(0.0f, 1.0f - u1));
  Vec3 b, c;
  orthonormalBasis(n, &b, &c);
  return b * x + c * y + n * z;
}

Vec3 uniformSphere(float u1, float u2) {
  const float z = 1.0f - 2.0f * u1, r = std::sqrt(std::max(0.0f, 1.0f - z * z)), phi = 2.0f * kPi * u2;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

unsigned resolveThreads(unsigned threads) {
  return threads ? threads : std::max(1u, std::thread::hardware_concurrency());
}

void parallelFor(uint64_t count, uint64_t chunk, unsigned threads,
                 const std::function<void(uint64_t, uint64_t)>& fn) {
  timedParallelFor(count, chunk, threads, fn);
}

double timedParallelFor(uint64_t count, uint64_t chunk, unsigned threads,
                        const std::function<void(uint64_t, uint64_t)>& fn) {
  using Clock = std::chrono::steady_clock;
  threads = resolveThreads(threads);
  chunk = std::max<uint64_t>(1, chunk);
  std::atomic<uint64_t> next{0};
  std::atomic<unsigned> started{0};
  std::atomic<bool> go{false};
  Clock::time_point start;
  std::vector<Clock::time_point> end(threads);
  auto worker = [&](unsigned w) {
    started.fetch_add(1);
    if (w == 0) {  // the clock starts once every worker is running
      while (started.load() < threads) std::this_thread::yield();
      start = Clock::now();
      go.store(true);
    } else {
      while (!go.load()) std::this_thread::yield();
    }
    for (;;) {
      const uint64_t begin = next.fetch_add(chunk);
      if (begin >= count) break;
      fn(begin, std::min(count, begin + chunk));
    }
    end[w] = Clock::now();
  };
  std::vector<std::thread> pool;
  for (unsigned i = 1; i < threads; ++i) pool.emplace_back(worker, i);
  worker(0);
  for (auto& t : pool) t.join();
  return std::chrono::duration<double>(*std::max_element(end.begin(), end.end()) - start).count();
}

}  // namespace vffx
