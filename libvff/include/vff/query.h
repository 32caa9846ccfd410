// vff/query.h - answering rays with a visibility field: the CPU query.
//
// A FieldQuery is a query-ready view of one object's field. It answers rays in the object's space
// (spec/geometry.md section 7); an Instance places it in a world with a rigid transform (rotation,
// translation, uniform scale) and answers world-space rays.
//
//   vff::Result<vff::File> file = vff::File::open("bunny.vff");
//   vff::Result<vff::FieldQuery> q = vff::FieldQuery::fromFile(*file);   // borrows *file
//   vff::Ray ray{origin, direction, 0.0f, tmax};
//   vff::QueryHit h = q->intersect(ray);                                  // h.hit, h.t, h.point
//   bool blocked = q->occluded(ray);                                      // the shadow/AO shortcut
//
// What a query answers.
// * A ray whose origin is outside the bounding sphere (inter-object) enters the sphere at distance
//   tEntry; the map of the positional sample nearest to the entry point, looked up in the ray's
//   direction, gives the distance d to the surface: the hit is at t = tEntry + d (section 7.2).
// * A ray whose origin is inside the sphere is answered by one of two tests, chosen by
//   QueryOptions::origin (where the ray starts):
//   - RayOrigin::kOnObject (the default): a point on the object looking out, the paper's test
//     (section 7.3). The ray leaves the sphere at d1; the reversed ray, entering there, reports the
//     surface at d2 from the exit point. The ray is occluded when d2 < d1 - bias. The field only
//     sees the surface from outside, so intersect() then reports the LAST surface crossing before
//     the exit, at t = d1 - d2, not necessarily the first.
//   - RayOrigin::kOffObject: a point elsewhere inside the sphere (the ground under the object,
//     another object touching it), section 7.4. The ray extended backwards enters the sphere before
//     its origin; the forward lookup from that entry point gives the first surface along the line.
//     When it lies ahead of the origin it is the answer (the first surface, as for a ray from
//     outside); when it lies behind (the origin sits in a hollow of the object), the ray is
//     answered by section 7.3 with no bias. The kOnObject test misses a contact shadow whenever the
//     last surface lies beyond tmax (ambient occlusion at ranges below 2R); this one does not.
//   Rays from outside the sphere get the same answer under both. vff::Scene chooses per ray and
//   instance from each ray's source (vff/scene.h).
// * Reconstruction::kNearest is the paper's: one sample, one texel. kInterpolated blends the few
//   samples within one mean spacing of the entry point (each looked up in the ray's direction, its hit point projected
//   back onto the ray) and, within each map, the 2 x 2 texels around the direction, with weights
//   that fall off with distance. Hits and misses are never averaged as numbers: the weights of the
//   hits and of the misses are summed separately, the ray hits when the hits outweigh the misses,
//   and the distance is the weighted mean of the hits' distances only. visibility() returns the
//   misses' share of the weight (1: certainly unoccluded): a smooth value for ambient occlusion.
//   Rays answered by section 7.3 are answered as with kNearest (blending takes the origin's own
//   surface, seen by the neighbouring samples' rays, for an occluder); kOffObject rays blend their
//   forward lookups from the entry point.
// * Limits. Under section 7.3 the field knows only the last surface before the exit point: with a
//   finite tmax, a ray whose first surface lies before tmax and whose last lies beyond it is
//   reported unoccluded (kOffObject rays only when their origin lies in a hollow of the object). A bit1 field has no distances: an outside ray's hit is reported at the
//   entry point, and rays from inside are never occluded.
//
// Units. A Ray's direction need not be unit length; t is measured in multiples of it, as in Embree
// (point = origin + t * direction). Results are approximate: see spec/geometry.md section 7.2.
//
// Threads. A FieldQuery is immutable after creation: every member function is const and may be
// called from many threads at once. The batch functions run on the calling thread. (The first
// kInterpolated call builds the neighbour lists that reconstruction reads, once, whichever
// thread makes it; kNearest never needs them.)
//
// Speed. Call the batch functions (FieldQuery's or Instance's): they answer kNearest rays 32 at a
// time, in AVX-512 or AVX2 vectors where the CPU has them (8 in SSE2 vectors on other x86-64
// CPUs), the rays that reach the sphere gathered from consecutive groups of 64 so that the
// vectors are full, and fetch the texels from memory ahead of their use; kInterpolated batches
// plan 16 rays at once (also gathered from consecutive groups) and fetch all their texels, then
// blend them 16 at once over kUnorm8Diameter fields (in AVX-512 or AVX2 lanes where the CPU has
// them). They give bit for bit the answers of the one-ray functions, in a fraction of their time
// (vff-experiments bench measures it). Hand them thousands of rays per call where you can: each call ends
// with its last rays in a part-filled vector (vff-experiments bench --batch 256 against the
// default 4096). occluded() and visibility() with kNearest are fastest on
// kUnorm8Diameter fields, whose hit flags the group kernel decodes as well. An Instance's kNearest
// batches are as fast as its field's: the group kernel takes each ray to object space itself.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <vector>

#include "vff/direction.h"
#include "vff/error.h"
#include "vff/export.h"
#include "vff/format.h"
#include "vff/positions.h"
#include "vff/refine.h"

namespace vff {

class File;

struct Ray {
  Vec3 origin;
  Vec3 direction;  // non-zero; need not be unit length
  float tmin = 0.0f;
  float tmax = std::numeric_limits<float>::infinity();
};

enum class Reconstruction : uint8_t {
  kNearest = 0,       // the paper: nearest positional sample, texel containing the direction
  kInterpolated = 1,  // miss-aware blend of the neighbouring samples and texels (see above)
  // A refined field's answer (vff/refine.h, spec/geometry.md section 7.5): kNearest's where the
  // field is sure; where its texel is marked unsure, or its hit lies within the refinement's margin
  // of either end of the ray's range (tmin or the origin, tmax), an exact ray cast against the
  // object's triangles over [tmin, tmax] (two-sided; QueryHit::normal the triangle's, facing the
  // ray). Rays answered by section 7.3 (from the object's own surface) get kNearest's answer. A
  // field without a refinement answers as kNearest. visibility() is 0 or 1.
  kRefined = 2,
};

// Which map and texel answer a ray: the positional sample nearest to the point where the lookup
// enters the sphere, and the texel of that sample's map that holds the lookup's direction (section
// 7.2; for a ray from inside, section 7.3's reversed ray entering at the exit point). kNearest
// reads exactly this texel; kInterpolated centres its blend on it (the sample always contributes,
// its neighbours and the 2 x 2 texels around the direction with it). valid is false when the ray
// makes no lookup: it misses the sphere, the sphere begins beyond tmax, or (bit1 fields) it starts
// inside. Texel (i, j) is byte j * M + i of map `sample` (vff/direction.h).
struct LookupSite {
  bool valid = false;
  uint32_t sample = 0;
  uint32_t i = 0, j = 0;
};

// Where the rays of a call start, for the rays that start inside the bounding sphere (see above).
enum class RayOrigin : uint8_t {
  kOnObject = 0,   // on this object's own surface: section 7.3, with QueryOptions::intraBias
  kOffObject = 1,  // anywhere else (not on this object): section 7.4; intraBias is not used
};

struct QueryOptions {
  Reconstruction reconstruction = Reconstruction::kNearest;
  RayOrigin origin = RayOrigin::kOnObject;
  // Intra-object bias, as a fraction of the radius R: a ray from inside is occluded when
  // d2 < d1 - bias * R. Negative: the default, defaultIntraBias(field). Only for
  // RayOrigin::kOnObject: a ray that starts off the object (a point of the ground under it) has no
  // surface of its own to skip, and is answered by section 7.4 instead (origin above).
  float intraBias = -1.0f;
};

// The default intra-object bias (fraction of R): two quantisation steps at normal incidence plus
// one mean angular spacing of the positional samples, sqrt(4 pi / mapCount): snapping the exit
// point to its nearest sample moves the reversed ray sideways by up to about that much, and the
// origin's own surface must not count as an occluder. (vff-experiments intra-ao compares the
// spacings: less lets the origin's surface occlude it, more hides surfaces near contacts.)
VFF_API float defaultIntraBias(const FieldDesc& field) noexcept;

// The kernel the batch functions use for kNearest on this CPU: "avx512", "avx2", "sse2" or
// "scalar".
VFF_API const char* batchKernelName() noexcept;

// The neighbour lists kInterpolated blends over: for every positional sample, up to
// kQueryNeighbours other samples around it (the samples nearest to two rings of probe directions
// at 1 and 1.6 mean spacings), padded with UINT32_MAX: mapCount * kQueryNeighbours entries. A GPU
// port of kInterpolated uploads them (gpu/loader). Experimental (vff/export.h): the lists change
// with the blend.
inline constexpr uint32_t kQueryNeighbours = 8;
// The radius of kInterpolated's kernel, in mean sample spacings sqrt(4 pi / mapCount).
inline constexpr float kQueryKernelSpacings = 1.3f;
VFF_EXPERIMENTAL std::vector<uint32_t> queryNeighbours(const PositionSet& positions);

struct QueryHit {
  bool hit = false;
  float t = std::numeric_limits<float>::infinity();  // along the ray, in multiples of its direction
  Vec3 point;              // origin + t * direction (object space for FieldQuery, world for Instance)
  Vec3 normal;             // unit surface normal, when hasNormal (object or world space, as point)
  bool hasNormal = false;  // the field has a normal plane and the ray hit
  bool inside = false;     // answered by section 7.3 (the origin was inside the bounding sphere, and
                           // the ray started on the object or, off it, in a hollow of it)
};

// A query-ready view of one field. Borrows its maps: from a File (which must outlive the
// FieldQuery) or from caller memory. Holds a small table per positional sample (its position,
// tangent frame and neighbour list: 84 bytes per map), for octa-hemi2 n <= 128 one byte per cell
// of the sample grid (n^2 bytes) and, for unorm8-chord, the decode scale of each texel of a map
// (4 bytes per texel of one map).
//
// Queries read the maps at random, so on Linux (6.1 and later) making a FieldQuery asks the
// kernel to back the whole 2 MiB pages within the maps with huge pages (madvise MADV_COLLAPSE;
// hugePageBytes() says how many bytes it got): the TLB then covers the field. The bytes stay as
// they are, and the caller's. The kernel declines for file mappings (a File's stored blocks) and
// where transparent huge pages are off.
class VFF_API FieldQuery {
 public:
  FieldQuery() noexcept;  // empty: every ray misses
  FieldQuery(FieldQuery&&) noexcept;
  FieldQuery& operator=(FieldQuery&&) noexcept;
  ~FieldQuery();

  // Decodes every block of the file's distance (and normal) plane into the file's cache once, so
  // that queries never fail or allocate. Errors: those of File::mapData (kBlockChecksum,
  // kBlockDecode...), kPositionScheme for a scheme this library cannot evaluate, kUnsupported for a
  // partial result of vff-bake --map-range (META "vff.partial", spec/partial.md), whose maps outside
  // its range are not the field's.
  static Result<FieldQuery> fromFile(const File& file);
  // Borrows map-major planes laid out as in a file (mapCount * mapBytes each; normals may be empty).
  // Errors: kInvalidArgument when a size does not match the description; the checks of
  // FieldDesc validation (kMapCount, kPositionScheme...).
  // A refinement (vff/refine.h; borrowed, like the maps) enables Reconstruction::kRefined; its
  // problems are kInvalidArgument. fromFile takes the file's REFN section when it has one.
  static Result<FieldQuery> fromMaps(const FieldDesc& field, std::span<const uint8_t> distance,
                                     std::span<const uint8_t> normals = {}, const RefinementView& refinement = {});

  const FieldDesc& field() const noexcept;
  const PositionSet& positions() const noexcept;
  bool hasNormals() const noexcept;
  // Bytes of the maps this view reads (the field's payload: what a GPU would hold).
  uint64_t payloadBytes() const noexcept;
  // Bytes of those maps the kernel moved to huge pages when this view was made (see above).
  uint64_t hugePageBytes() const noexcept;
  // Whether the field has a refinement (kRefined answers from it), and the bytes its exact step
  // reads: the unsure bits, the vertex positions, and the triangle BVH built from them (its nodes
  // and the triangles' indices). payloadBytes() + refinementBytes(): the memory a refined query
  // needs (what a GPU would hold).
  bool refined() const noexcept;
  uint64_t refinementBytes() const noexcept;

  // Object-space queries.
  QueryHit intersect(const Ray& ray, const QueryOptions& options = {}) const noexcept;
  // True when the ray hits the object with t in [tmin, tmax].
  bool occluded(const Ray& ray, const QueryOptions& options = {}) const noexcept;
  // The probability that the ray reaches tmax unoccluded: 0 or 1 for kNearest; for kInterpolated
  // the misses' (and far hits') share of the blend weight.
  float visibility(const Ray& ray, const QueryOptions& options = {}) const noexcept;

  // Batches (the calling thread; out.size() must equal rays.size(), extra entries are ignored).
  void intersect(std::span<const Ray> rays, std::span<QueryHit> out, const QueryOptions& options = {}) const noexcept;
  void occluded(std::span<const Ray> rays, std::span<uint8_t> out, const QueryOptions& options = {}) const noexcept;
  void visibility(std::span<const Ray> rays, std::span<float> out, const QueryOptions& options = {}) const noexcept;

  // The lookup site of a ray (LookupSite above), found by the same steps as the queries'. The batch
  // runs on the calling thread; out.size() must equal rays.size() (extra entries are ignored).
  LookupSite site(const Ray& ray, const QueryOptions& options = {}) const noexcept;
  void sites(std::span<const Ray> rays, std::span<LookupSite> out, const QueryOptions& options = {}) const noexcept;

  struct Impl;  // opaque
  friend struct Instance;  // (its batches reach the field's kernel with their transform)

 private:
  std::unique_ptr<Impl> impl_;
};

// world = translation + scale * (rotation * object). rotation is row-major and orthonormal
// (det +1); scale > 0.
struct VFF_API RigidTransform {
  float rotation[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  Vec3 translation;
  float scale = 1.0f;

  Vec3 toWorldPoint(Vec3 p) const noexcept;
  Vec3 toWorldVector(Vec3 v) const noexcept;  // rotation * scale * v
  Vec3 toObjectPoint(Vec3 p) const noexcept;
  Vec3 toObjectVector(Vec3 v) const noexcept;
  // A rotation of `radians` about `axis` (need not be unit), then the scale, then the translation.
  static RigidTransform fromAxisAngle(Vec3 axis, float radians, Vec3 translation = {}, float scale = 1.0f) noexcept;
};

// A field placed in a world. Borrows the FieldQuery. Rays and results are in world space; t is
// the same parameter as in object space, because the direction is transformed with the ray.
struct VFF_API Instance {
  const FieldQuery* field = nullptr;
  RigidTransform transform;

  QueryHit intersect(const Ray& worldRay, const QueryOptions& options = {}) const noexcept;
  bool occluded(const Ray& worldRay, const QueryOptions& options = {}) const noexcept;
  float visibility(const Ray& worldRay, const QueryOptions& options = {}) const noexcept;
  // Batches of world-space rays, as fast as the field's own (out.size() must equal
  // worldRays.size(); extra entries are ignored): kNearest batches take each ray to object space
  // in the field's batch kernel, kInterpolated ones a few hundred at a time. The same answers as
  // the one-ray functions above.
  void intersect(std::span<const Ray> worldRays, std::span<QueryHit> out, const QueryOptions& options = {}) const noexcept;
  void occluded(std::span<const Ray> worldRays, std::span<uint8_t> out, const QueryOptions& options = {}) const noexcept;
  void visibility(std::span<const Ray> worldRays, std::span<float> out, const QueryOptions& options = {}) const noexcept;
  // The lookup site (LookupSite) of a world-space ray, one ray or a batch.
  LookupSite site(const Ray& worldRay, const QueryOptions& options = {}) const noexcept;
  void sites(std::span<const Ray> worldRays, std::span<LookupSite> out, const QueryOptions& options = {}) const noexcept;
  // The bounding sphere in world space.
  Sphere worldSphere() const noexcept;
};

}  // namespace vff
