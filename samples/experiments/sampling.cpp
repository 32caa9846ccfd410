// sampling.cpp - per-pixel random numbers, hemisphere and sphere sampling, and the experiments'
// parallel loops: the project's one chunked loop (platform/parallel.h) under common.h's names.
#include <algorithm>
#include <chrono>

#include "common.h"
#include "platform/parallel.h"

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

unsigned resolveThreads(unsigned threads) { return vff::parallel::resolveThreads(threads); }

void parallelFor(uint64_t count, uint64_t chunk, unsigned threads,
                 const std::function<void(uint64_t, uint64_t)>& fn) {
  vff::parallel::parallelFor(count, chunk, threads, fn);
}

// The workers are started (and wait) before the clock starts, and joined after it stops; the time
// ends when the last of them finishes its last chunk.
double timedParallelFor(uint64_t count, uint64_t chunk, unsigned threads,
                        const std::function<void(uint64_t, uint64_t)>& fn) {
  using Clock = std::chrono::steady_clock;
  vff::parallel::WorkerPool pool(vff::parallel::workerCount(count, chunk, threads));
  const Clock::time_point start = Clock::now();
  std::vector<Clock::time_point> end(pool.size(), start);
  pool.parallelForWorkers(count, chunk, [&](unsigned w, size_t begin, size_t stop) {
    fn(begin, stop);
    end[w] = Clock::now();
  });
  return std::chrono::duration<double>(*std::max_element(end.begin(), end.end()) - start).count();
}

}  // namespace vffx
