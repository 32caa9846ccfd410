// convert_options.h - vff-convert's command line: the options (with the shared layout, codec and
// enum option groups of tools/common) and the checks CLI11 cannot make.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <optional>
#include <string>

#include "enum_option.h"
#include "options_codec.h"
#include "options_layout.h"
#include "resample.h"

namespace vff::convert {

inline constexpr const char* kProg = "vff-convert";

struct Options {
  std::string input, output, to;
  bool half = false;
  bool quiet = false;
  cli::OptionsLayout layout;  // --to vff: the input's unless given
  cli::OptionsCodec codec;    // --to vff: the input's unless given
  unsigned threads = 0;
  // Conversions that change the maps (resample.h).
  cli::EnumOption<DistanceEncoding> encoding{"--encoding", vff::kDistanceEncodings};
  cli::EnumOption<PositionScheme> positions{"--positions", vff::kPositionSchemes};
  cli::EnumOption<DownsampleRule> downsample{
      "--downsample", vff::Spellings<DownsampleRule>{DownsampleRule::kMin, DownsampleRule::kTent, downsampleRuleName}};
  cli::EnumOption<PositionResample> resample{
      "--resample", vff::Spellings<PositionResample>{PositionResample::kNearest, PositionResample::kInterpolated,
                                                     positionResampleName}};
  std::optional<uint32_t> mapSize, count;

  // An option that changes the maps is given.
  bool resampling() const;
};

// Adds every option of `o` to `app`.
void addOptions(CLI::App& app, Options& o);
// Sets o->to from the output's extension when --to is not given, then checks that the options
// given apply to that kind of output. Returns the usage error, or nothing.
std::optional<std::string> checkOptions(Options* o);

}  // namespace vff::convert
