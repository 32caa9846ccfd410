// spelling.cpp - the spellings that are not libvff's names (see spelling.h).
#include "spelling.h"

namespace vff::cli {

const char* directionSchemeSpelling(DirectionScheme s) noexcept {
  switch (s) {
    case DirectionScheme::kConcentricEqualArea: return "concentric";
    case DirectionScheme::kHemiOctahedral: return "hemi-oct";
    case DirectionScheme::kInvalid: break;
  }
  return "invalid";
}

}  // namespace vff::cli
