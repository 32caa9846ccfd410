#include "progress.h"

#include <cinttypes>
#include <cstdio>

namespace vff::cli {

void Progress::update(uint64_t done, uint64_t total) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  std::lock_guard<std::mutex> lock(mu_);
  if (done != total && now - last_ < std::chrono::milliseconds(100)) return;
  last_ = now;
  const double secs = std::chrono::duration<double>(now - start_).count();
  const double eta = done ? secs * double(total - done) / double(done) : 0;
  std::fprintf(stderr, "\r%s: %" PRIu64 "/%" PRIu64 " %s", prog_.c_str(), done, total, unit_.c_str());
  if (raysPerMap_) std::fprintf(stderr, ", %.1f Mrays/s", secs > 0 ? double(done * raysPerMap_) / secs / 1e6 : 0.0);
  std::fprintf(stderr, ", ETA %.1f s   ", eta);
  if (done == total) std::fputc('\n', stderr);
  std::fflush(stderr);
}

}  // namespace vff::cli
