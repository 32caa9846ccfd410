// options_layout.h - the packed-layout option group: --target, --max-texture-size, --max-layers,
// --gutter (vff::LayoutLimits). vff-bake and vff-convert spell and check them here.
//
//   vff::cli::OptionsLayout layout;
//   layout.add(app, vff::cli::Defaults::kTool);
//   ... after vff::cli::parse():  w.layout = layout.limits(vff::LayoutLimits{});
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>

#include "enum_option.h"
#include "vff/format.h"

namespace vff::cli {

struct OptionsLayout {
  EnumOption<LayoutTarget> target{"--target", kLayoutTargets, LayoutLimits{}.target};
  uint32_t maxTextureSize = LayoutLimits{}.maxTextureSize;
  uint32_t maxLayers = LayoutLimits{}.maxLayers;
  uint32_t gutter = LayoutLimits{}.gutter;

  // Adds the four options. kTool: LayoutLimits' defaults shown in --help, limits 1..65536 (gutter
  // 0..64); kInput: no default shown, any positive limit (gutter 0..64), descriptions start "vff: ".
  void add(CLI::App& app, Defaults defaults);
  // Any of the four is on the command line.
  bool given() const;
  // `base` with each option given in its place.
  LayoutLimits limits(const LayoutLimits& base) const;

 private:
  CLI::Option* maxTextureSizeOption_ = nullptr;
  CLI::Option* maxLayersOption_ = nullptr;
  CLI::Option* gutterOption_ = nullptr;
};

}  // namespace vff::cli
