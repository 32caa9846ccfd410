// reference.cpp - vff_query_reference: what vff-query must print, from libvff's one-ray calls.
//
//   vff_query_reference rays FIELD N SEED > rays.csv       N rays around FIELD's sphere (CSV lines)
//   vff_query_reference describe FIELD                     "MAPS M": its map count and resolution
//   vff_query_reference answer FIELD rays.csv [--interpolated | --refined] [--visibility] [--off-object] [--rotate AX AY AZ A]
//                       [--translate X Y Z] [--scale S]    the answers as vff-query's CSV
// The answers come from FieldQuery/Instance::intersect, ::site and ::visibility on one ray at a time, so the
// tests compare vff-query's batches (split over threads) with the one-ray path.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "rays.h"
#include "vff/vff.h"

namespace {

int makeRays(const char* path, int n, unsigned seed) {
  auto f = vff::File::open(path);
  if (!f) return std::fprintf(stderr, "%s\n", f.error().toString().c_str()), 1;
  const vff::Sphere s = f->field().sphere;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int i = 0; i < n; ++i) {
    // A third start inside the sphere, the rest outside, aimed near its centre.
    const float k = i % 3 == 0 ? 0.5f : 2.5f;
    float o[3], d[3];
    for (int a = 0; a < 3; ++a) o[a] = s.center[a] + k * s.radius * u(rng);
    for (int a = 0; a < 3; ++a) d[a] = (i % 3 == 0) ? u(rng) : s.center[a] + 0.6f * s.radius * u(rng) - o[a];
    if (d[0] == 0 && d[1] == 0 && d[2] == 0) d[2] = 1;
    std::printf("%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", o[0], o[1], o[2], d[0], d[1], d[2]);
  }
  return 0;
}

int answer(int argc, char** argv) {
  auto f = vff::File::open(argv[2]);
  if (!f) return std::fprintf(stderr, "%s\n", f.error().toString().c_str()), 1;
  auto q = vff::FieldQuery::fromFile(*f);
  if (!q) return std::fprintf(stderr, "%s\n", q.error().toString().c_str()), 1;
  std::ifstream in(argv[3]);
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  auto parsed = vff::query_tool::parseRayLines(s, 0.0f, std::numeric_limits<float>::infinity());
  if (parsed.error) return std::fprintf(stderr, "bad ray line %llu\n", (unsigned long long)parsed.error->line), 1;
  vff::QueryOptions qo;
  bool visibility = false;
  std::optional<vff::Instance> inst;
  vff::Vec3 axis{0, 0, 1}, t{};
  float angle = 0, scale = 1;
  bool placed = false;
  for (int i = 4; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--interpolated")) qo.reconstruction = vff::Reconstruction::kInterpolated;
    else if (!std::strcmp(argv[i], "--refined")) qo.reconstruction = vff::Reconstruction::kRefined;
    else if (!std::strcmp(argv[i], "--visibility")) visibility = true;
    else if (!std::strcmp(argv[i], "--off-object")) qo.origin = vff::RayOrigin::kOffObject;
    else if (!std::strcmp(argv[i], "--rotate") && i + 4 < argc) {
      axis = {std::strtof(argv[i + 1], nullptr), std::strtof(argv[i + 2], nullptr), std::strtof(argv[i + 3], nullptr)};
      angle = std::strtof(argv[i + 4], nullptr), i += 4, placed = true;
    } else if (!std::strcmp(argv[i], "--translate") && i + 3 < argc) {
      t = {std::strtof(argv[i + 1], nullptr), std::strtof(argv[i + 2], nullptr), std::strtof(argv[i + 3], nullptr)};
      i += 3, placed = true;
    } else if (!std::strcmp(argv[i], "--scale") && i + 1 < argc) {
      scale = std::strtof(argv[++i], nullptr), placed = true;
    } else {
      return std::fprintf(stderr, "unknown argument %s\n", argv[i]), 1;
    }
  }
  if (placed) inst = vff::Instance{&*q, vff::RigidTransform::fromAxisAngle(axis, angle, t, scale)};
  std::vector<vff::QueryHit> hits;
  std::vector<vff::LookupSite> sites;
  std::vector<float> vis;
  for (const vff::Ray& r : parsed.rays) {
    hits.push_back(inst ? inst->intersect(r, qo) : q->intersect(r, qo));
    sites.push_back(inst ? inst->site(r, qo) : q->site(r, qo));
    if (visibility) vis.push_back(inst ? inst->visibility(r, qo) : q->visibility(r, qo));
  }
  const std::vector<vff::query_tool::Column> columns = vff::query_tool::defaultColumns(true, visibility);
  const auto out = vff::query_tool::formatAnswers({hits, sites, vis, columns}, vff::query_tool::OutputFormat::kCsv);
  std::fwrite(out.data(), 1, out.size(), stdout);
  return 0;
}

}  // namespace

int describe(const char* path) {
  auto f = vff::File::open(path);
  if (!f) return std::fprintf(stderr, "%s\n", f.error().toString().c_str()), 1;
  std::printf("%llu %u\n", (unsigned long long)f->field().mapCount, f->field().mapResolution);
  return 0;
}

int main(int argc, char** argv) {
  if (argc == 3 && !std::strcmp(argv[1], "describe")) return describe(argv[2]);
  if (argc == 5 && !std::strcmp(argv[1], "rays")) return makeRays(argv[2], std::atoi(argv[3]), unsigned(std::atoi(argv[4])));
  if (argc >= 4 && !std::strcmp(argv[1], "answer")) return answer(argc, argv);
  std::fprintf(stderr, "usage: vff_query_reference rays FIELD N SEED | answer FIELD RAYS.csv [options]\n");
  return 1;
}
