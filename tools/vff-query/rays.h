// rays.h - the rays vff-query reads and the answers it writes.
//
// Input lines (standard input or a text file), one ray each, in either spelling, mixed freely:
//   CSV:        ox,oy,oz,dx,dy,dz[,tmin,tmax]        (commas or blanks between the numbers)
//   JSON lines: {"origin":[ox,oy,oz],"direction":[dx,dy,dz],"tmin":0,"tmax":10}   (tmin, tmax optional)
//               or [ox,oy,oz,dx,dy,dz] / [ox,oy,oz,dx,dy,dz,tmin,tmax]
// Blank lines and lines starting with '#' are skipped, and so is a first line of column names
// "ox,oy,oz,dx,dy,dz[,tmin,tmax]". Rays without their own tmin/tmax take the command line's.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "vff/query.h"

namespace vff::query_tool {

// Where and why a line of rays could not be read: 1-based line and column (in bytes).
struct LineError {
  uint64_t line = 0;
  uint64_t column = 0;
  std::string message;
};

struct ParsedRays {
  std::vector<Ray> rays;            // every ray before the first bad line
  std::optional<LineError> error;  // the first bad line, if any
};

// Reads text lines of rays (see above). Stops at the first bad line.
ParsedRays parseRayLines(std::string_view text, float tmin, float tmax);

// Checks one ray: finite origin and direction, a non-zero direction, tmin <= tmax, no NaN bound.
// Returns the problem and the 0-based index of the number it concerns (0..7).
std::optional<std::pair<std::string, int>> checkRay(const Ray& ray);

// The columns of every answer, in order (CSV header, .npy columns): the hit, then which map
// (positional sample) and texel (i, j) of it answered (vff::LookupSite; -1 where the ray made no
// lookup).
inline constexpr const char* kColumns[] = {"hit", "t", "x", "y", "z", "nx", "ny", "nz", "inside", "sample", "i", "j"};
inline constexpr int kColumnCount = 12;
inline constexpr int kSiteColumns = 3;  // sample, i, j: left out when the sites are not asked for

enum class OutputFormat { kCsv, kJsonLines, kNpy };

// The answers to a run of rays: one hit per ray, one site per ray and one visibility per ray when
// asked for (else empty).
struct Answers {
  std::span<const QueryHit> hits;
  std::span<const LookupSite> sites;
  std::span<const float> visibility;
  bool withSites = true;         // the columns sample, i, j (sites holds one per ray)
  bool withVisibility = false;   // the column visibility (visibility holds one per ray)
};

// The .npy rows of answers: kColumnCount floats per ray (hit and inside as 0/1, NaN where there is
// no point or normal, sample and texel exact as floats, -1 without a lookup; without sites those
// three columns are left out), and visibility last when asked for.
void answerRows(const Answers& a, float* rows);
// The number of those columns.
inline size_t columnCount(bool sites, bool visibility) {
  return size_t(kColumnCount - (sites ? 0 : kSiteColumns) + (visibility ? 1 : 0));
}

// The answers as one output document (CSV with a header line, JSON lines, or .npy). With
// visibility, a last column "visibility".
std::vector<uint8_t> formatAnswers(const Answers& a, OutputFormat format);

}  // namespace vff::query_tool
