// rays.h - the rays vff-query reads and the answers it writes.
//
// Input lines (standard input or a text file), one ray each, in either spelling, mixed freely:
//   CSV:        ox,oy,oz,dx,dy,dz[,tmin,tmax]        (commas or blanks between the numbers)
//   JSON lines: {"origin":[ox,oy,oz],"direction":[dx,dy,dz],"tmin":0,"tmax":10}   (tmin, tmax optional)
//               or [ox,oy,oz,dx,dy,dz] / [ox,oy,oz,dx,dy,dz,tmin,tmax]
// Blank lines and lines starting with '#' are skipped, and so is a first line of column names
// "ox,oy,oz,dx,dy,dz[,tmin,tmax]". Rays without their own tmin/tmax take the command line's. A
// UTF-8 byte order mark before the first line is skipped; a NUL byte, and a JSON ray with a key
// other than origin, direction, tmin and tmax, are errors. Messages show the input's bytes outside
// printable ASCII as \xHH.
#pragma once

#include <cmath>
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
// Bytes of the input as a message may show them: printable ASCII as is, every other byte (and " and
// \) as \xHH, since a terminal must not receive raw binary; cut after `limit` bytes.
std::string shown(std::string_view bytes, size_t limit = 40);

ParsedRays parseRayLines(std::string_view text, float tmin, float tmax);

// Checks one ray: finite origin and direction, a non-zero direction, tmin <= tmax, no NaN bound.
// Returns the problem and the 0-based index of the number it concerns (0..7).
std::optional<std::pair<std::string, int>> checkRay(const Ray& ray);
// checkRay(ray) finds nothing: the test alone, inlined, for every row of a large input.
inline bool rayIsGood(const Ray& ray) {
  const float v[6] = {ray.origin.x, ray.origin.y, ray.origin.z, ray.direction.x, ray.direction.y, ray.direction.z};
  bool finite = true;
  for (float x : v) finite &= std::isfinite(x);
  return finite && (v[3] != 0 || v[4] != 0 || v[5] != 0) && ray.tmin <= ray.tmax;  // (false for a NaN bound)
}

// The columns an answer can have (CSV header, .npy columns): the hit, then which map (positional
// sample) and texel (i, j) of it answered (vff::LookupSite; -1 where the ray made no lookup), then
// the visibility (0..1). By default all but the visibility, in this order.
enum class Column : uint8_t { kHit, kT, kX, kY, kZ, kNx, kNy, kNz, kInside, kSample, kI, kJ, kVisibility };
inline constexpr const char* kColumns[] = {"hit", "t",      "x", "y", "z", "nx", "ny", "nz", "inside",
                                           "sample", "i", "j", "visibility"};
inline constexpr int kAllColumns = 13;

// The default columns: every one but the visibility, without sample, i, j when !sites, and with the
// visibility last when asked for.
std::vector<Column> defaultColumns(bool sites, bool visibility);
// The columns of a comma-separated list of their names (any order, each at most once), or the
// problem with the list.
std::optional<std::string> parseColumns(std::string_view list, std::vector<Column>* out);
inline bool hasColumn(std::span<const Column> columns, Column c) {
  for (Column x : columns)
    if (x == c) return true;
  return false;
}
// Whether the columns need the lookup sites (sample, i or j).
inline bool needsSites(std::span<const Column> columns) {
  return hasColumn(columns, Column::kSample) || hasColumn(columns, Column::kI) || hasColumn(columns, Column::kJ);
}

enum class OutputFormat { kCsv, kJsonLines, kNpy };

// The answers to a run of rays: one hit per ray, one site per ray when the columns need them
// (needsSites) and one visibility per ray when they have it (else empty).
struct Answers {
  std::span<const QueryHit> hits;
  std::span<const LookupSite> sites;
  std::span<const float> visibility;
  std::span<const Column> columns;  // the output's, in order
};

// The .npy rows of answers: a float per column per ray (hit and inside as 0/1, t inf for a miss,
// NaN where there is no point or normal, sample and texel exact as floats, -1 without a lookup).
void answerRows(const Answers& a, float* rows);

// The answers as one output document: CSV with a header line or .npy, of the answers' columns, or
// JSON lines (always every key but the sites without them and the visibility without it).
std::vector<uint8_t> formatAnswers(const Answers& a, OutputFormat format);

}  // namespace vff::query_tool
