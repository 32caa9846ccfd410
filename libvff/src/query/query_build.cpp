// query_build.cpp - building a FieldQuery (vff/query.h): the tables of FieldQuery::Impl
// (query_impl.h) from a field's maps, and the plain tables the group kernel reads (query_group.h),
// taken from them for each batch.
#include <nlohmann/json.hpp>

#include <cstring>
#include <string>

#include "vff/reader.h"

#include "platform/huge_pages.h"
#include "query/query_impl.h"

namespace vff {
namespace {

constexpr float kPi = 3.14159265358979323846f;

// detail::adviseHugePages over each run of maps that lie back to back; the bytes it got.
uint64_t adviseMapRuns(const std::vector<const uint8_t*>& maps, uint64_t mapBytes) {
  uint64_t got = 0;
  for (size_t k = 0; k < maps.size();) {
    size_t end = k + 1;
    while (end < maps.size() && maps[end] == maps[end - 1] + mapBytes) ++end;
    got += detail::adviseHugePages(maps[k], size_t((end - k) * mapBytes));
    k = end;
  }
  return got;
}

}  // namespace

void FieldQuery::Impl::build() {
  const uint32_t n = field.mapCount;
  center = toVec(field.sphere.center);
  radius = field.sphere.radius;
  m = field.mapResolution;
  distanceStep = quantizationStep(field.distanceEncoding, radius, 1.0f);
  const uint64_t planeBytes = uint64_t(n) * distMapBytes;
  byteTexels = (field.distanceEncoding == DistanceEncoding::kUnorm8Diameter ||
                field.distanceEncoding == DistanceEncoding::kUnorm8Chord) &&
               m <= 4096 && n > 0;
  contiguous = byteTexels && planeBytes >= 4 && planeBytes < (uint64_t(1) << 31);
  for (uint32_t k = 0; k < n && contiguous; ++k) contiguous = dist[k] == dist[0] + size_t(k) * distMapBytes;
  floatMapIndices = n < (1u << 24);
  bool normalsContiguous = !norm.empty() && uint64_t(n) * normMapBytes < (uint64_t(1) << 31);
  for (uint32_t k = 0; k < n && normalsContiguous; ++k) normalsContiguous = norm[k] == norm[0] + size_t(k) * normMapBytes;
  if (contiguous && field.distanceEncoding == DistanceEncoding::kUnorm8Diameter && floatMapIndices &&
      (norm.empty() || normalsContiguous)) {
    blendTables.texels = dist[0];
    blendTables.mapBytes = int32_t(distMapBytes);
    blendTables.m = m;
    blendTables.distanceScale = distanceStep;  // (texel()'s scale)
    if (!norm.empty()) {
      blendTables.normals = norm[0];
      blendTables.normalMapBytes = int32_t(normMapBytes);
    }
  }
  // The maps are read at random: on huge pages, where the OS gives them (huge_pages.h).
  hugePages = adviseMapRuns(dist, distMapBytes) + adviseMapRuns(norm, normMapBytes);
  frames.resize(n);
  unit4.assign(size_t(n) * 4, 0.0f);
  for (uint32_t k = 0; k < n; ++k) {
    const Vec3 u = positions.position(k);
    unit4[size_t(k) * 4] = u.x;
    unit4[size_t(k) * 4 + 1] = u.y;
    unit4[size_t(k) * 4 + 2] = u.z;
    frames[k] = positions.frame(k);
  }
  if (positions.scheme() == PositionScheme::kOctaHemi2) {
    octaMasks = detail::octaCandidateMasks(positions.param());
    octaCornerRows = detail::octaCornerRows(octaMasks, positions.param());
    if (!octaMasks.empty()) octaMasks.resize(octaMasks.size() + 3, 0);  // GroupTables::octaMasks' padding
  }
  spacing = std::sqrt(4.0f * kPi / float(n));
  // The kernel reaches 1.3 mean spacings (ground AO under the bunny, vff-experiments ao: 1.0 and
  // 1.6 are less accurate or cost more).
  const float r = kQueryKernelSpacings * spacing;
  kernelRadius2 = r * r;
  defaultBias = defaultIntraBias(field);
  offTolerance = 2.0f * radius / 255.0f;
  if (field.distanceEncoding == DistanceEncoding::kUnorm8Chord) {
    chordScale.resize(size_t(m) * m);
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i)
        chordScale[size_t(j) * m + i] =
            quantizationStep(field.distanceEncoding, radius, texelDirection(field.directionScheme, m, i, j).z);
  }
}

std::vector<uint32_t> queryNeighbours(const PositionSet& positions) {
  // The samples nearest to probe directions on two rings around each sample: this finds the
  // samples whose Voronoi cells border the kernel around it, in every scheme.
  const uint32_t n = positions.count();
  std::vector<uint32_t> out(size_t(n) * kQueryNeighbours, UINT32_MAX);
  if (n == 0) return out;
  const float spacing = std::sqrt(4.0f * kPi / float(n));
  constexpr int kProbes = 12;
  for (uint32_t k = 0; k < n; ++k) {
    uint32_t found[kQueryNeighbours];
    uint32_t count = 0;
    const Vec3 u = positions.position(k);
    const Frame f = positions.frame(k);
    for (float ring : {1.0f, 1.6f}) {
      const float a = ring * spacing;
      for (int p = 0; p < kProbes && count < kQueryNeighbours; ++p) {
        const float phi = 2.0f * kPi * (float(p) + (ring > 1.2f ? 0.5f : 0.0f)) / kProbes;
        const Vec3 d = u * std::cos(a) + (f.t * std::cos(phi) + f.b * std::sin(phi)) * std::sin(a);
        const uint32_t q = positions.nearest(d);
        if (q == k) continue;
        // An octa-hemi2 equator copy has the same position as its twin: keep one of them.
        bool dup = false;
        for (uint32_t c = 0; c < count; ++c) dup = dup || found[c] == q;
        if (!dup) found[count++] = q;
      }
    }
    std::copy(found, found + count, out.begin() + ptrdiff_t(size_t(k) * kQueryNeighbours));
  }
  return out;
}

const char* batchKernelName() noexcept { return detail::groupKernelName(); }

float defaultIntraBias(const FieldDesc& field) noexcept {
  if (field.mapCount == 0 || !(field.sphere.radius > 0)) return 0.0f;
  const float step = quantizationStep(field.distanceEncoding, 1.0f, 1.0f);
  return 2.0f * step + std::sqrt(4.0f * kPi / float(field.mapCount));
}

FieldQuery::FieldQuery() noexcept = default;
FieldQuery::FieldQuery(FieldQuery&&) noexcept = default;
FieldQuery& FieldQuery::operator=(FieldQuery&&) noexcept = default;
FieldQuery::~FieldQuery() = default;

Result<FieldQuery> FieldQuery::fromMaps(const FieldDesc& field, std::span<const uint8_t> distance,
                                        std::span<const uint8_t> normals, const RefinementView& refinement) {
  if (Status s = checkFieldDesc(field); !s) return s.error();
  auto ps = PositionSet::fromField(field);
  if (!ps) return ps.error();
  const uint64_t db = distanceMapBytes(field.distanceEncoding, field.mapResolution);
  const uint64_t nb = normalMapBytes(field.normalEncoding, field.mapResolution);
  if (distance.size() != db * field.mapCount)
    return makeError(Code::kInvalidArgument, "distance plane holds " + std::to_string(distance.size()) +
                                                 " bytes, the field needs " + std::to_string(db * field.mapCount));
  if (!normals.empty() && (field.normalEncoding == NormalEncoding::kNone || normals.size() != nb * field.mapCount))
    return makeError(Code::kInvalidArgument, "normal plane holds " + std::to_string(normals.size()) +
                                                 " bytes, the field needs " + std::to_string(nb * field.mapCount));
  auto impl = std::make_unique<Impl>();
  impl->field = field;
  impl->positions = *ps;
  impl->distMapBytes = db;
  impl->normMapBytes = nb;
  impl->dist.resize(field.mapCount);
  for (uint32_t k = 0; k < field.mapCount; ++k) impl->dist[k] = distance.data() + k * db;
  impl->payload = distance.size();
  if (!normals.empty()) {
    impl->norm.resize(field.mapCount);
    for (uint32_t k = 0; k < field.mapCount; ++k) impl->norm[k] = normals.data() + k * nb;
    impl->payload += normals.size();
  }
  if (!refinement.empty()) {
    // The reader's checks of a REFN section, made on the section this refinement would be.
    if (auto raw = encodeRefinement(field, refinement); !raw) return std::move(raw).error();
  }
  impl->build();
  if (Status s = impl->setRefinement(refinement); !s) return s.error();
  FieldQuery q;
  q.impl_ = std::move(impl);
  return q;
}

Result<FieldQuery> FieldQuery::fromFile(const File& file) {
  const FieldDesc& field = file.field();
  // A partial result (spec/partial.md) holds misses in place of the maps outside its range: it
  // must not answer rays as if they were the field's.
  if (const auto meta = nlohmann::json::parse(file.metadata(), nullptr, false);
      meta.is_object() && meta.contains("vff.partial"))
    return makeError(Code::kUnsupported, "the file is a partial result (META \"vff.partial\": " +
                                             meta["vff.partial"].dump() +
                                             "); only the whole field answers rays: merge the parts with vff-bake --merge");
  auto ps = PositionSet::fromField(field);
  if (!ps) return ps.error();
  auto impl = std::make_unique<Impl>();
  impl->field = field;
  impl->positions = *ps;
  impl->distMapBytes = distanceMapBytes(field.distanceEncoding, field.mapResolution);
  impl->normMapBytes = normalMapBytes(field.normalEncoding, field.mapResolution);
  impl->dist.resize(field.mapCount);
  for (uint32_t k = 0; k < field.mapCount; ++k) {
    auto map = file.mapData(Plane::kDistance, k);
    if (!map) return map.error();
    impl->dist[k] = map->data();
  }
  impl->payload = file.plane(Plane::kDistance).rawBytes;
  if (file.hasNormals()) {
    impl->norm.resize(field.mapCount);
    for (uint32_t k = 0; k < field.mapCount; ++k) {
      auto map = file.mapData(Plane::kNormal, k);
      if (!map) return map.error();
      impl->norm[k] = map->data();
    }
    impl->payload += file.plane(Plane::kNormal).rawBytes;
  }
  impl->build();
  if (Status s = impl->setRefinement(file.refinement()); !s) return s.error();
  FieldQuery q;
  q.impl_ = std::move(impl);
  return q;
}

const FieldDesc& FieldQuery::field() const noexcept {
  static const FieldDesc kEmpty{};
  return impl_ ? impl_->field : kEmpty;
}
const PositionSet& FieldQuery::positions() const noexcept {
  static const PositionSet kEmpty{};
  return impl_ ? impl_->positions : kEmpty;
}
bool FieldQuery::hasNormals() const noexcept { return impl_ && !impl_->norm.empty(); }
uint64_t FieldQuery::payloadBytes() const noexcept { return impl_ ? impl_->payload : 0; }
uint64_t FieldQuery::hugePageBytes() const noexcept { return impl_ ? impl_->hugePages : 0; }

detail::GroupTables FieldQuery::Impl::groupTables(const QueryOptions& o, bool decodeHits) const noexcept {
  detail::GroupTables t;
  t.center = center;
  t.radius = radius;
  t.octaN = positions.scheme() == PositionScheme::kOctaHemi2 ? positions.param() : 0;
  t.unit4 = unit4.data();
  t.octaMasks = octaMasks.empty() ? nullptr : octaMasks.data();
  t.octaCornerRows = octaCornerRows.empty() ? nullptr : octaCornerRows.data();
  t.scheme = field.directionScheme;
  t.m = m;
  t.bit1 = field.distanceEncoding == DistanceEncoding::kBit1;
  t.insideLo = (o.intraBias >= 0 ? o.intraBias : defaultBias) * radius;
  t.offObject = o.origin == RayOrigin::kOffObject;
  t.offTolerance = offTolerance;
  t.gridGuard = detail::gridGuard(t.octaN);
  t.texelGuard = detail::texelGuard(m);
  t.maps = dist.data();
  t.encoding = field.distanceEncoding;
  t.byteTexels = byteTexels;
  if (contiguous) {
    t.texels = dist[0];
    t.mapBytes = int32_t(distMapBytes);
  }
  t.decodeHits = decodeHits && byteTexels && field.distanceEncoding == DistanceEncoding::kUnorm8Diameter;
  t.distanceScale = distanceStep;
  return t;
}

detail::PlanTables FieldQuery::Impl::planTables() const noexcept {
  needNeighbours();
  detail::PlanTables t;
  t.unit4 = unit4.data();
  t.neighbours = neighbours.data();
  t.kernelRadius2 = kernelRadius2;
  t.center = center;
  t.radius = radius;
  t.m = m;
  t.scheme = field.directionScheme;
  t.texels = blendTables.texels;
  t.mapBytes = blendTables.mapBytes;
  return t;
}

}  // namespace vff
