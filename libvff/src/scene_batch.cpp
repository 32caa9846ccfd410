// scene_batch.cpp - vff::Scene's batches (vff/scene.h): the rays of a chunk are sorted by the
// instances whose spheres they reach, each instance answers its rays through its batch path, and
// the answers are combined per ray in id order (as the one-ray functions and the loop over
// instances do).
#include <algorithm>
#include <string>

#include "scene_impl.h"

namespace vff {

namespace {

constexpr size_t kChunk = 32768;  // rays a chunk

// The (instance, ray) pairs of a chunk, grouped by instance in ascending id, rays ascending within.
struct Pairs {
  std::vector<uint32_t> first;  // per instance: its pairs are [first[i], first[i + 1])
  std::vector<uint32_t> ray;    // per pair: the ray's index in the chunk
  std::vector<Ray> rays;        // per pair: the ray, gathered for the instance's batch
};

void pairUp(const Scene::Impl& m, std::span<const Ray> chunk, Pairs* p) {
  const size_t n = m.instances.size();
  std::vector<uint32_t> inst, rayOf;
  inst.reserve(chunk.size() * 2);
  rayOf.reserve(chunk.size() * 2);
  for (uint32_t r = 0; r < chunk.size(); ++r)
    m.bvh.walk(detail::boxRay(chunk[r]), [&](uint32_t id) {
      inst.push_back(id);
      rayOf.push_back(r);
      return chunk[r].tmax;
    });
  p->first.assign(n + 1, 0);
  for (uint32_t id : inst) ++p->first[id + 1];
  for (size_t i = 0; i < n; ++i) p->first[i + 1] += p->first[i];
  std::vector<uint32_t> fill(p->first.begin(), p->first.end() - 1);
  p->ray.resize(inst.size());
  for (size_t k = 0; k < inst.size(); ++k) p->ray[fill[inst[k]]++] = rayOf[k];
  p->rays.resize(inst.size());
  for (size_t k = 0; k < p->ray.size(); ++k) p->rays[k] = chunk[p->ray[k]];
}

Status sizes(size_t rays, size_t out) {
  if (rays == out) return {};
  return makeError(Code::kInvalidArgument,
                   "scene: out has " + std::to_string(out) + " entries for " + std::to_string(rays) + " rays");
}

// Runs answer(instance, rays of the pairs, answers of the pairs) for every instance with pairs.
template <class T, class Answer>
void answerPairs(const Scene::Impl& m, const Pairs& p, std::vector<T>* answers, Answer&& answer) {
  answers->resize(p.rays.size());
  const std::span<const Ray> rays(p.rays);
  const std::span<T> out(*answers);
  for (size_t i = 0; i + 1 < p.first.size(); ++i) {
    const uint32_t a = p.first[i], b = p.first[i + 1];
    if (a < b) answer(m.instances[i], rays.subspan(a, b - a), out.subspan(a, b - a));
  }
}

}  // namespace

Status Scene::intersect(std::span<const Ray> rays, std::span<SceneHit> out, const QueryOptions& options) const {
  if (Status s = Impl::ready(impl_.get()); !s) return s;
  if (Status s = sizes(rays.size(), out.size()); !s) return s;
  std::fill(out.begin(), out.end(), SceneHit{});
  if (!impl_) return {};
  Pairs p;
  std::vector<QueryHit> hits;
  for (size_t c = 0; c < rays.size(); c += kChunk) {
    const std::span<const Ray> chunk = rays.subspan(c, std::min(kChunk, rays.size() - c));
    pairUp(*impl_, chunk, &p);
    answerPairs(*impl_, p, &hits, [&](const Instance& in, std::span<const Ray> r, std::span<QueryHit> h) {
      in.intersect(r, h, options);
    });
    for (uint32_t i = 0; i + 1 < p.first.size(); ++i)
      for (uint32_t k = p.first[i]; k < p.first[i + 1]; ++k) {
        SceneHit& best = out[c + p.ray[k]];
        if (hits[k].hit && hits[k].t < best.t) {
          static_cast<QueryHit&>(best) = hits[k];
          best.instance = i;
        }
      }
  }
  return {};
}

Status Scene::occluded(std::span<const Ray> rays, std::span<uint8_t> out, const QueryOptions& options) const {
  if (Status s = Impl::ready(impl_.get()); !s) return s;
  if (Status s = sizes(rays.size(), out.size()); !s) return s;
  std::fill(out.begin(), out.end(), uint8_t(0));
  if (!impl_) return {};
  Pairs p;
  std::vector<Ray> open;
  std::vector<uint32_t> openRay;
  std::vector<uint8_t> blocked;
  for (size_t c = 0; c < rays.size(); c += kChunk) {
    const std::span<const Ray> chunk = rays.subspan(c, std::min(kChunk, rays.size() - c));
    const std::span<uint8_t> o = out.subspan(c, chunk.size());
    pairUp(*impl_, chunk, &p);
    // Instance by instance, only the rays no earlier instance has blocked: any instance's "yes"
    // is the answer, so the rest are not asked.
    for (size_t i = 0; i + 1 < p.first.size(); ++i) {
      open.clear();
      openRay.clear();
      for (uint32_t k = p.first[i]; k < p.first[i + 1]; ++k)
        if (!o[p.ray[k]]) {
          open.push_back(p.rays[k]);
          openRay.push_back(p.ray[k]);
        }
      if (open.empty()) continue;
      blocked.resize(open.size());
      impl_->instances[i].occluded(open, blocked, options);
      for (size_t k = 0; k < open.size(); ++k)
        if (blocked[k]) o[openRay[k]] = 1;
    }
  }
  return {};
}

Status Scene::visibility(std::span<const Ray> rays, std::span<float> out, const QueryOptions& options) const {
  if (Status s = Impl::ready(impl_.get()); !s) return s;
  if (Status s = sizes(rays.size(), out.size()); !s) return s;
  std::fill(out.begin(), out.end(), 1.0f);
  if (!impl_) return {};
  Pairs p;
  std::vector<float> vis;
  for (size_t c = 0; c < rays.size(); c += kChunk) {
    const std::span<const Ray> chunk = rays.subspan(c, std::min(kChunk, rays.size() - c));
    pairUp(*impl_, chunk, &p);
    answerPairs(*impl_, p, &vis, [&](const Instance& in, std::span<const Ray> r, std::span<float> o) {
      in.visibility(r, o, options);
    });
    for (size_t k = 0; k < p.ray.size(); ++k) out[c + p.ray[k]] *= vis[k];  // pairs in id order
  }
  return {};
}

}  // namespace vff
