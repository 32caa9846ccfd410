// experiment.cpp - the driver shared by the image experiments, and the result table.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli.h"
#include "common.h"

namespace vffx {

namespace {

const char* reconstructionName(vff::Reconstruction r) {
  return r == vff::Reconstruction::kNearest ? "nearest" : r == vff::Reconstruction::kRefined ? "refined" : "interpolated";
}

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

// Writes IMAGE.png and IMAGE.exr; prints the error and returns false on failure.
bool writeImages(const Image& image, const std::string& base) {
  for (const vff::Status& st : {writePng(image, base + ".png"), writeExr(image, base + ".exr")}) {
    if (!st) {
      vff::cli::reportError(kProg, "", st.error());
      return false;
    }
  }
  return true;
}

// The distance field at the field's memory (its payload bytes, counted as sdf_field.h says), in
// the experiment's SDF rows: images, error maps, table rows. Returns an exit code, 0 on success.
int renderSdfRows(const Options& o, const ImageExperiment& e, const World& world, const ExactTracer& exact,
                  const GBuffer& g, const std::vector<uint8_t>& mask, const Image& reference, const BakedQuery& c,
                  int rays, unsigned threads, uint32_t stream, const std::string& base, float range,
                  const std::string& label, std::vector<Image>* strip, std::vector<TableRow>* rows) {
  if (c.query.payloadBytes() < kSdfMinBudget) {  // a field this small has no distance field beside it
    std::fprintf(stderr, "%s: %s: note: no distance-field rows for %s: its %llu bytes are under the %llu a distance grid needs\n",
                 kProg, e.name.c_str(), c.name.c_str(), static_cast<unsigned long long>(c.query.payloadBytes()),
                 static_cast<unsigned long long>(kSdfMinBudget));
    return 0;
  }
  auto built = SdfField::build(world.objectMesh, {.budgetBytes = c.query.payloadBytes(), .values = o.sdfValues, .bandVoxels = o.sdfBand});
  if (!built) return vff::cli::reportError(kProg, o.mesh, built.error());
  SdfField& sdf = *built;
  sdf.transform = world.transform;
  const double mib = 1.0 / 1048576.0;
  std::fprintf(stderr, "%s: %s: distance field at %s's memory: voxel %.4g R, %.2f MiB (NanoVDB %.2f MiB, dense %.2f MiB), %d builds in %.2f s\n",
               kProg, e.name.c_str(), c.name.c_str(), double(sdf.voxelSize() / world.radius), double(sdf.bytes()) * mib,
               double(sdf.nanovdbBytes()) * mib, double(sdf.denseBytes()) * mib, sdf.builds(), sdf.buildSeconds());
  char what[256];
  std::snprintf(what, sizeof what, "distance field, %s's memory (%s, voxel %.4g R, %ux%ux%u; NanoVDB %.2f MiB, dense %.2f MiB)",
                c.name.c_str(), sdf.values() == SdfValues::kFp8 ? "fp8" : "float", double(sdf.voxelSize() / world.radius),
                sdf.dims(0), sdf.dims(1), sdf.dims(2), double(sdf.nanovdbBytes()) * mib, double(sdf.denseBytes()) * mib);
  for (vff::Reconstruction r : e.sdfRows) {
    const char* mode = r == vff::Reconstruction::kNearest ? "sphere trace" : "cone";
    double seconds = 0;
    const Image img = renderImage(g, threads, stream, e.makeShader(world, exact, nullptr, &sdf, r, rays, range), &seconds);
    const ErrorStats st = compareImages(reference, img, mask);
    const std::string name = base + "-sdf-" + c.name + "-" + (r == vff::Reconstruction::kNearest ? "trace" : "cone");
    if (!writeImages(img, name)) return vff::cli::kExitIo;
    if (auto w = writeErrorMap(reference, img, mask, 8.0f, name + "-error.png"); !w)
      return vff::cli::reportError(kProg, "", w.error());
    if (strip) strip->push_back(img), strip = nullptr;
    rows->push_back({std::string(what) + label, mode, double(sdf.bytes()) * mib, st.rms, st.max, seconds, false});
    std::fprintf(stderr, "%s: %s: distance field at %s, %s in %.2f s, RMS %.2f\n", kProg, e.name.c_str(), c.name.c_str(),
                 mode, seconds, st.rms);
  }
  return 0;
}

// The fields an image experiment renders: the bakes of `configs` (refined unless --no-refined),
// then the loaded `files` (moved). Non-zero: the exit code of a failed bake, reported.
int gatherFields(const Options& o, const ImageExperiment& e, const World& world, const vff::bake::Scene& scene,
                 const std::vector<FieldConfig>& configs, unsigned threads,
                 std::vector<std::unique_ptr<BakedQuery>>& files, std::vector<std::unique_ptr<BakedQuery>>* fields) {
  for (const FieldConfig& fc : configs) {
    auto baked = bakeQuery(world, scene, fc, e.normals, threads);
    if (!baked) return vff::cli::reportError(kProg, o.mesh, baked.error());
    std::fprintf(stderr, "%s: %s: baked %s in %.2f s (%.2f MiB)\n", kProg, e.name.c_str(), (*baked)->name.c_str(),
                 (*baked)->bakeSeconds, (*baked)->payloadMiB());
    // A refined bake answers kNearest and kInterpolated as before, and kRefined from its REFN data.
    if (o.sdfRefined)
      if (vff::Status st = refineQuery(world, baked->get(), {.threads = threads}); !st)
        return vff::cli::reportError(kProg, o.mesh, st.error());
    fields->push_back(std::move(*baked));
  }
  for (std::unique_ptr<BakedQuery>& f : files) {
    std::fprintf(stderr, "%s: %s: loaded %s (%.2f MiB)\n", kProg, e.name.c_str(), f->description.c_str(), f->payloadMiB());
    fields->push_back(std::move(f));
  }
  return 0;
}

}  // namespace

std::string formatTable(const std::vector<TableRow>& rows, bool contact) {
  std::ostringstream s;
  s << "| configuration | reconstruction | memory MiB | RMS (8-bit) | " << (contact ? "RMS contact | RMS outside | " : "")
    << "max | time s |\n";
  s << "|---|---|---:|---:|" << (contact ? "---:|---:|" : "") << "---:|---:|\n";
  auto rms = [](const TableRow& r, double v) { return r.reference ? std::string(v == r.rms ? "(reference)" : "-") : fixed(v, 2); };
  for (const TableRow& r : rows) {
    s << "| " << r.configuration << " | " << r.reconstruction << " | "
      << (r.memoryMiB < 0 ? std::string("-") : fixed(r.memoryMiB, 2)) << " | " << rms(r, r.rms) << " | ";
    if (contact) s << (r.rmsContact < 0 ? std::string("-") : rms(r, r.rmsContact)) << " | "
                   << (r.rmsOutside < 0 ? std::string("-") : rms(r, r.rmsOutside)) << " | ";
    s << (r.reference ? std::string("-") : fixed(r.max, 0)) << " | " << fixed(r.seconds, 2) << " |\n";
  }
  return s.str();
}

int runImageExperiment(const Options& o, const ImageExperiment& e) {
  std::vector<FieldConfig> configs;
  // With --field and no --config, only the files are evaluated.
  const std::vector<std::string> none;
  for (const std::string& c : !o.configs.empty() ? o.configs : o.fields.empty() ? e.defaultConfigs : none) {
    FieldConfig fc;
    if (!parseFieldConfig(c, &fc)) {
      vff::cli::usageError(kProg, "--config " + c + ": expected MAPSxMxM with an octa-hemi2 map count (e.g. 4226x64x64)");
      return vff::cli::kExitUsage;
    }
    configs.push_back(fc);
  }
  const int rays = o.rays > 0 ? o.rays : e.defaultRays;
  const unsigned threads = resolveThreads(o.threads);

  auto setup = makeSetup(o, threads);
  if (!setup) return vff::cli::reportError(kProg, o.mesh, setup.error());
  World* world = &(*setup)->world;
  ExactTracer* exact = &*(*setup)->exact;
  vff::bake::Scene* scene = &*(*setup)->scene;
  // The files of --field, checked against the mesh before anything is rendered.
  std::vector<std::unique_ptr<BakedQuery>> files;
  for (const std::string& path : o.fields) {
    auto field = loadQuery(*world, path, e.normals);
    if (!field) {
      const int rc = vff::cli::reportError(kProg, path, field.error());
      // A file of another mesh or sphere is an invalid input for this experiment.
      return field.error().code == vff::Code::kInvalidArgument ? vff::cli::kExitInvalidFile : rc;
    }
    files.push_back(std::move(*field));
  }
  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  if (ec) {
    vff::cli::printError(kProg, o.out + ": cannot create the output folder: " + ec.message());
    return vff::cli::kExitIo;
  }

  const GBuffer g = traceGBuffer(*world, *exact, o.size, threads);
  std::vector<uint8_t> mask(g.pixels.size());
  for (size_t i = 0; i < mask.size(); ++i)
    mask[i] = (e.comparePlane && g.pixels[i].kind == PixelKind::kPlane) ||
              (e.compareObject && g.pixels[i].kind == PixelKind::kObject);
  // The contact region: plane pixels inside the bounding sphere (their rays start inside it).
  std::vector<uint8_t> contact(mask.size()), outside(mask.size());
  for (size_t i = 0; i < mask.size(); ++i) {
    const Vec3 d = g.pixels[i].point - world->center;
    const bool in = dot(d, d) <= world->radius * world->radius;
    contact[i] = mask[i] && g.pixels[i].kind == PixelKind::kPlane && in;
    outside[i] = mask[i] && !contact[i];
  }
  const uint32_t stream = 0x76ff0000u ^ uint32_t(std::hash<std::string>{}(e.name) & 0xffffu);
  auto measure = [&](const Image& reference, const Image& img, TableRow row) {
    const ErrorStats st = compareImages(reference, img, mask);
    row.rms = st.rms;
    row.max = st.max;
    if (e.contactRegion) {
      row.rmsContact = compareImages(reference, img, contact).rms;
      row.rmsOutside = compareImages(reference, img, outside).rms;
    }
    return row;
  };

  // The fields: the bakes of --config, then the files of --field.
  std::vector<std::unique_ptr<BakedQuery>> fields;
  if (const int rc = gatherFields(o, e, *world, *scene, configs, threads, files, &fields)) return rc;

  std::vector<TableRow> rows;
  std::vector<Image> strip;  // exact | first configuration nearest | interpolated | distance field
  const std::vector<float> ranges = e.ranges.empty() ? std::vector<float>{0.0f} : e.ranges;
  for (float range : ranges) {
    // With several ranges, every row and file names its range ("ao-r0.5-...", "4226x64x64 @ 0.5 R").
    char tag[32] = "", label[32] = "";
    if (e.ranges.size() > 1) {
      std::snprintf(tag, sizeof tag, "-r%g", double(range));
      std::snprintf(label, sizeof label, " @ %g R", double(range));
    }
    const std::string base = o.out + "/" + e.name + tag;
    double seconds = 0;
    const Image reference = renderImage(
        g, threads, stream, e.makeShader(*world, *exact, nullptr, nullptr, vff::Reconstruction::kNearest, rays, range),
        &seconds);
    if (!writeImages(reference, base + "-exact")) return vff::cli::kExitIo;
    const double meshMiB = double(world->worldMesh.positions.size() * 4 + world->worldMesh.indices.size() * 4) / 1048576.0;
    rows.push_back({"exact (Embree, " + std::to_string(world->worldMesh.triangleCount()) + " triangles)" + label, "-",
                    meshMiB + double(exact->memoryBytes()) / 1048576.0, 0, 0, seconds, true});
    std::fprintf(stderr, "%s: %s: exact reference%s in %.2f s\n", kProg, e.name.c_str(), label, seconds);
    const bool firstRange = strip.empty();
    if (firstRange) strip.push_back(reference);
    for (const std::unique_ptr<BakedQuery>& field : fields) {
      const BakedQuery& c = *field;
      for (vff::Reconstruction r :
           {vff::Reconstruction::kNearest, vff::Reconstruction::kInterpolated, vff::Reconstruction::kRefined}) {
        if (r == vff::Reconstruction::kRefined && !c.query.refined()) continue;
        const Image img =
            renderImage(g, threads, stream, e.makeShader(*world, *exact, &c, nullptr, r, rays, range), &seconds);
        const std::string name = base + "-" + c.name + "-" + reconstructionName(r);
        if (!writeImages(img, name)) return vff::cli::kExitIo;
        if (firstRange && strip.size() < 3) strip.push_back(img);
        if (auto w = writeErrorMap(reference, img, mask, 8.0f, name + "-error.png"); !w)
          return vff::cli::reportError(kProg, "", w.error());
        // A refined row's memory: the maps, the unsure bits and the exact step.
        const double mib = c.payloadMiB() +
                           (r == vff::Reconstruction::kRefined ? double(c.query.refinementBytes()) / 1048576.0 : 0.0);
        rows.push_back(measure(reference, img, {c.description + label, reconstructionName(r), mib, 0, 0, seconds, false}));
        std::fprintf(stderr, "%s: %s: %s%s %s in %.2f s, RMS %.2f\n", kProg, e.name.c_str(), c.name.c_str(), label,
                     reconstructionName(r), seconds, rows.back().rms);
      }
      if (o.sdf && !e.sdfRows.empty()) {
        const bool first = strip.size() == 3;
        if (const int rc = renderSdfRows(o, e, *world, *exact, g, mask, reference, c, rays, threads, stream, base,
                                         range, label, first ? &strip : nullptr, &rows))
          return rc;
      }
    }
  }
  const std::string base = o.out + "/" + e.name;

  // The side-by-side comparison: exact, the first configuration nearest and interpolated, its
  // distance field's first image.
  if (auto w = writePng(sideBySide(strip), base + "-comparison.png"); !w) return vff::cli::reportError(kProg, "", w.error());

  uint64_t compared = 0;
  for (uint8_t m : mask) compared += m;
  std::ostringstream md;
  md << "Experiment `" << e.name << "`: " << o.mesh << ", " << o.size << "x" << o.size << ", " << rays
     << " rays per pixel, " << threads << " threads; error over " << compared << " "
     << (e.comparePlane && e.compareObject ? "plane and object" : e.comparePlane ? "plane" : "object")
     << " pixels against the exact image; memory: field payload (exact: mesh + Embree BVH; distance field: the bricks of its "
     << "narrow band and their indirection table, at most the field's payload); time: secondary rays only"
     << (e.contactRegion ? "; contact: the plane pixels inside the bounding sphere, outside: the rest" : "") << ".\n\n"
     << formatTable(rows, e.contactRegion);
  std::printf("%s", md.str().c_str());
  std::ofstream f(base + "-table.md");
  f << md.str();
  if (!f) {
    vff::cli::printError(kProg, base + "-table.md: cannot write");
    return vff::cli::kExitIo;
  }
  return vff::cli::kExitSuccess;
}

}  // namespace vffx
