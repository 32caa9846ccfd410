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

// The columns of every answer, in order (CSV header, .npy columns).
inline constexpr const char* kColumns[] = {"hit", "t", "x", "y", "z", "nx", "ny", "nz", "inside"};
inline constexpr int kColumnCount = 9;

enum class OutputFormat { kCsv, kJsonLines, kNpy };

// The .npy rows of answers: kColumnCount floats per ray (hit and inside as 0/1, NaN where there is
// no point or normal), and visibility last when `visibility` is not empty.
void answerRows(std::span<const QueryHit> hits, std::span<const float> visibility, float* rows);

// The answers as one output document. `visibility`, when not empty, adds a last column
// "visibility" (one value per ray).
std::vector<uint8_t> formatAnswers(std::span<const QueryHit> hits, std::span<const float> visibility,
                                   OutputFormat format);

}  // namespace vff::query_tool
