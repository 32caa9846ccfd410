// query_site.cpp - which map and texel answer a ray (vff/query.h, LookupSite): prepare(), the first
// step of every query, stopped before the texel is read.
#include <algorithm>

#include "query_impl.h"

namespace vff {

LookupSite FieldQuery::site(const Ray& ray, const QueryOptions& options) const noexcept {
  LookupSite s;
  Impl::Lookup l;
  if (!impl_ || !impl_->prepare(ray, options, &l)) return s;
  s.valid = true;
  s.sample = l.k0;
  s.i = l.i;
  s.j = l.j;
  return s;
}

void FieldQuery::sites(std::span<const Ray> rays, std::span<LookupSite> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(rays.size(), out.size());
  for (size_t r = 0; r < n; ++r) out[r] = site(rays[r], options);
}

LookupSite Instance::site(const Ray& worldRay, const QueryOptions& options) const noexcept {
  return field ? field->site(detail::ToObject(transform).ray(worldRay), options) : LookupSite{};
}

void Instance::sites(std::span<const Ray> worldRays, std::span<LookupSite> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(worldRays.size(), out.size());
  if (!field) {
    std::fill_n(out.begin(), n, LookupSite{});
    return;
  }
  const detail::ToObject x(transform);
  for (size_t r = 0; r < n; ++r) out[r] = field->site(x.ray(worldRays[r]), options);
}

}  // namespace vff
