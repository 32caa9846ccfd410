// vff/spelling.h - how a front end (a command line, a binding, a manifest) names the values of
// libvff's enums. There is one table of spellings, the *Name() functions of vff/format.h; reading a
// spelling back loops over the enum's values and asks that function, so every front end accepts the
// same words and lists them in the same order (the enum's). Header-only.
//
//   const auto e = vff::kDistanceEncodings.parse("unorm8-chord");  // DistanceEncoding::kUnorm8Chord
//   vff::kDistanceEncodings.all();  // {"unorm8-diameter", "unorm8-chord", ...}
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "vff/format.h"

namespace vff {

// The values first..last of the enum E (consecutive, in enum order), each spelled `name(value)`.
template <typename E>
struct Spellings {
  E first;
  E last;
  const char* (*name)(E) noexcept;

  // Every spelling, in enum order (for CLI::IsMember, which lists them in --help and in errors).
  std::vector<std::string> all() const {
    std::vector<std::string> out;
    for (E v = first;; v = next(v)) {
      out.emplace_back(name(v));
      if (v == last) break;
    }
    return out;
  }

  // The value spelled `text`; nothing when no value is.
  std::optional<E> parse(std::string_view text) const {
    for (E v = first;; v = next(v)) {
      if (text == name(v)) return v;
      if (v == last) return std::nullopt;
    }
  }

 private:
  static E next(E v) { return static_cast<E>(static_cast<std::underlying_type_t<E>>(v) + 1); }
};

// vff-bake's --directions words, shorter than directionSchemeName's: "concentric" for
// kConcentricEqualArea, "hemi-oct" for kHemiOctahedral ("invalid" otherwise).
inline const char* directionSchemeSpelling(DirectionScheme s) noexcept {
  switch (s) {
    case DirectionScheme::kConcentricEqualArea: return "concentric";
    case DirectionScheme::kHemiOctahedral: return "hemi-oct";
    case DirectionScheme::kInvalid: break;
  }
  return "invalid";
}

inline constexpr Spellings<DistanceEncoding> kDistanceEncodings{
    DistanceEncoding::kUnorm8Diameter, DistanceEncoding::kBc4Diameter, distanceEncodingName};
inline constexpr Spellings<PositionScheme> kPositionSchemes{
    PositionScheme::kOctaHemi2, PositionScheme::kSphericalFibonacci, positionSchemeName};
inline constexpr Spellings<DirectionScheme> kDirectionSchemes{
    DirectionScheme::kConcentricEqualArea, DirectionScheme::kHemiOctahedral, directionSchemeSpelling};
inline constexpr Spellings<Codec> kCodecs{Codec::kStored, Codec::kZstd, codecName};
inline constexpr Spellings<LayoutTarget> kLayoutTargets{LayoutTarget::kTexture2DArray, LayoutTarget::kTexture3D,
                                                        layoutTargetName};

}  // namespace vff
