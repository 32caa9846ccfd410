// options_codec.h - the block-codec option group: --codec, --zstd-level, --maps-per-block (the
// codec fields of vff::WriteOptions). vff-bake and vff-convert spell and check them here.
//
//   vff::cli::OptionsCodec codec;
//   codec.add(app, vff::cli::Defaults::kTool);
//   ... after vff::cli::parse():  w.codec = codec.codec.value(); w.zstdLevel = codec.zstdLevel; ...
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>

#include "enum_option.h"
#include "vff/format.h"

namespace vff::cli {

struct OptionsCodec {
  EnumOption<Codec> codec{"--codec", kCodecs, Codec::kStored};
  int zstdLevel = 19;         // 1..22
  uint32_t mapsPerBlock = 0;  // G; 0: the writer's automatic G (about 256 KiB per block)

  // Adds the three options. kTool: the codec's and level's defaults shown in --help; kInput: the
  // codec and G default to the input's, descriptions start "vff: " (the level's default is shown).
  void add(CLI::App& app, Defaults defaults);
  // Any of the three is on the command line.
  bool given() const;
  bool zstdLevelGiven() const;
  bool mapsPerBlockGiven() const;

 private:
  CLI::Option* zstdLevelOption_ = nullptr;
  CLI::Option* mapsPerBlockOption_ = nullptr;
};

}  // namespace vff::cli
