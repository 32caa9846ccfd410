// query_site.cpp - which map and texel answer a ray (vff/query.h, LookupSite): prepare(), the first
// step of every query, stopped before the texel is read; batches through the group kernel's first
// steps, as the nearest batches find their texels.
#include <algorithm>
#include <optional>

#include "query/query_impl.h"

namespace vff {
namespace {

LookupSite siteOf(const FieldQuery::Impl::Lookup& l) { return LookupSite{true, l.k0, l.i, l.j}; }

}  // namespace

void FieldQuery::Impl::sitesBatch(std::span<const Ray> rays, std::span<LookupSite> out, const QueryOptions& o,
                                  const RigidTransform* x) const noexcept {
  std::optional<detail::ToObject> to;
  if (x) to.emplace(*x);
  auto objectRay = [&](size_t r) { return to ? to->ray(rays[r]) : rays[r]; };
  const detail::GroupKernel* kernel = detail::groupKernel();
  if (!kernel) {
    for (size_t r = 0; r < rays.size(); ++r) {
      Lookup l;
      out[r] = prepare(objectRay(r), o, &l) ? siteOf(l) : LookupSite{};
    }
    return;
  }
  forEachGroup(*kernel, rays, detail::toObjectTables(groupTables(o, false), to ? &*to : nullptr), [&](size_t base, size_t n, detail::Group& g) {
    detail::forEachClear(g.reached, n, [&](size_t r) { out[base + r] = LookupSite{}; });
    for (uint32_t p = 0; p < g.count; ++p) {
      const size_t r = base + g.ray[p];
      if ((g.redo >> p) & 1u) {  // the rays the kernel left to the reference
        Lookup l;
        out[r] = prepare(objectRay(r), o, &l) ? siteOf(l) : LookupSite{};
      } else {
        out[r] = LookupSite{true, g.k[p], g.i[p], g.j[p]};
      }
    }
  });
}

LookupSite FieldQuery::site(const Ray& ray, const QueryOptions& options) const noexcept {
  Impl::Lookup l;
  if (!impl_ || !impl_->prepare(ray, options, &l)) return LookupSite{};
  return siteOf(l);
}

void FieldQuery::sites(std::span<const Ray> rays, std::span<LookupSite> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(rays.size(), out.size());
  if (impl_) {
    impl_->sitesBatch(rays.first(n), out.first(n), options, nullptr);
  } else {
    std::fill_n(out.begin(), n, LookupSite{});
  }
}

LookupSite Instance::site(const Ray& worldRay, const QueryOptions& options) const noexcept {
  return field ? field->site(detail::ToObject(transform).ray(worldRay), options) : LookupSite{};
}

void Instance::sites(std::span<const Ray> worldRays, std::span<LookupSite> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(worldRays.size(), out.size());
  if (field && field->impl_) {
    field->impl_->sitesBatch(worldRays.first(n), out.first(n), options, &transform);
  } else {
    std::fill_n(out.begin(), n, LookupSite{});
  }
}

}  // namespace vff
