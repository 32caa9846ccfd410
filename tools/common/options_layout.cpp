// options_layout.cpp - the packed-layout option group (see options_layout.h).
#include "options_layout.h"

namespace vff::cli {

namespace {

bool given(const CLI::Option* option) { return option != nullptr && option->count() > 0; }

}  // namespace

void OptionsLayout::add(CLI::App& app, Defaults defaults) {
  if (defaults == Defaults::kTool) {
    target.add(app, "GPU texture target of the packed layout")->capture_default_str();
    maxTextureSizeOption_ = app.add_option("--max-texture-size", maxTextureSize, "GPU limit: largest slice width/height")
                                ->capture_default_str()
                                ->check(CLI::Range(1u, 65536u));
    maxLayersOption_ = app.add_option("--max-layers", maxLayers, "GPU limit: most array layers / 3D depth")
                           ->capture_default_str()
                           ->check(CLI::Range(1u, 65536u));
    gutterOption_ = app.add_option("--gutter", gutter, "texels of edge replication around each tile")
                        ->capture_default_str()
                        ->check(CLI::Range(0u, 64u));
    return;
  }
  target.add(app, "vff: GPU texture target of the packed layout (default: the input's)");
  maxTextureSizeOption_ =
      app.add_option("--max-texture-size", maxTextureSize, "vff: largest slice width/height (default: the input's)")
          ->check(CLI::PositiveNumber);
  maxLayersOption_ =
      app.add_option("--max-layers", maxLayers, "vff: most array layers or 3D depth (default: the input's)")
          ->check(CLI::PositiveNumber);
  gutterOption_ =
      app.add_option("--gutter", gutter, "vff: texels of edge replication around each tile (default: the input's)")
          ->check(CLI::Range(0u, 64u));
}

bool OptionsLayout::given() const {
  return target.given() || cli::given(maxTextureSizeOption_) || cli::given(maxLayersOption_) ||
         cli::given(gutterOption_);
}

LayoutLimits OptionsLayout::limits(const LayoutLimits& base) const {
  LayoutLimits l = base;
  if (target.given()) l.target = target.value();
  if (cli::given(maxTextureSizeOption_)) l.maxTextureSize = maxTextureSize;
  if (cli::given(maxLayersOption_)) l.maxLayers = maxLayers;
  if (cli::given(gutterOption_)) l.gutter = gutter;
  return l;
}

}  // namespace vff::cli
