// options_codec.cpp - the block-codec option group (see options_codec.h).
#include "options_codec.h"

namespace vff::cli {

void OptionsCodec::add(CLI::App& app, Defaults defaults) {
  const bool tool = defaults == Defaults::kTool;
  CLI::Option* c = codec.add(app, tool ? "block codec" : "vff: block codec (default: the input's)");
  if (tool) c->capture_default_str();
  zstdLevelOption_ = app.add_option("--zstd-level", zstdLevel, tool ? "zstd level" : "vff: zstd level")
                         ->check(CLI::Range(1, 22))
                         ->capture_default_str();
  mapsPerBlockOption_ = app.add_option("--maps-per-block", mapsPerBlock,
                                       tool ? "maps per block (0: about 256 KiB per block)"
                                            : "vff: maps per block (0: about 256 KiB per block; default: the input's)");
}

bool OptionsCodec::given() const { return codec.given() || zstdLevelGiven() || mapsPerBlockGiven(); }

bool OptionsCodec::zstdLevelGiven() const { return zstdLevelOption_ != nullptr && zstdLevelOption_->count() > 0; }

bool OptionsCodec::mapsPerBlockGiven() const {
  return mapsPerBlockOption_ != nullptr && mapsPerBlockOption_->count() > 0;
}

}  // namespace vff::cli
