// progress.h - the progress line the tools print on stderr while they work: the maps done of the
// total, the ray rate for bakes and the time left, redrawn at most 10 times a second, only when
// enabled (on a terminal, not with --quiet or --json). Safe to update from several threads.
#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace vff::cli {

class Progress {
 public:
  // `raysPerMap` > 0 adds the rate in rays per second (bakes); 0 leaves it out. `unit` names what
  // is counted.
  Progress(std::string prog, bool enabled, uint64_t raysPerMap = 0, std::string unit = "maps")
      : prog_(std::move(prog)), unit_(std::move(unit)), enabled_(enabled), raysPerMap_(raysPerMap) {}
  // `done` of `total` units; the line ends when done == total.
  void update(uint64_t done, uint64_t total);

 private:
  std::string prog_;
  std::string unit_;
  bool enabled_;
  uint64_t raysPerMap_;
  std::mutex mu_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_{};
};

}  // namespace vff::cli
