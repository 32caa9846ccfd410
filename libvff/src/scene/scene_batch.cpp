// scene_batch.cpp - vff::Scene's batches (vff/scene.h). The rays of a chunk are paired with the
// instances whose spheres they reach; each pair's ray is taken into its instance's object space
// exactly as Instance's one-ray functions do; each field then answers the rays of all its
// instances in one call of its batch path (a thousand instances of one field make one large batch,
// which keeps the batch path's memory pipeline full); the answers are combined per ray in id order,
// as the one-ray functions and the loop over instances do.
#include <algorithm>
#include <memory>
#include <mutex>
#include <new>
#include <string>

#include "query/query_impl.h"
#include "scene/scene_impl.h"

namespace vff {

namespace {

// Rays a chunk. Few enough that a chunk's rays, box rays, traversal lists and pairs stay near the
// core's own caches (larger chunks run slower, the more so on two threads); many enough that the
// traversal's cost per node, and its partly filled vector steps near the leaves, are shared by
// many rays (smaller chunks run slower, the more so the more instances). The field's batch path
// gets the pairs of all its instances at once either way.
constexpr size_t kChunk = 8192;

// How far ahead pairing asks for the rays and the instances' steps it will read.
constexpr size_t kRaysAhead = 8, kLeavesAhead = 2;

using Pairs = detail::ScenePairs;
using Scratch = detail::SceneScratch;

// A scratch of the scene's spares (Scene::Impl::spare), or a new one, for the length of a call.
class ScratchLease {
 public:
  explicit ScratchLease(const Scene::Impl& m) : m_(m) {
    {
      std::lock_guard<std::mutex> lock(m.spareLock);
      if (!m.spare.empty()) {
        s_ = std::move(m.spare.back());
        m.spare.pop_back();
      }
    }
    if (!s_) s_ = std::make_unique<Scratch>();
  }
  ~ScratchLease() {
    std::lock_guard<std::mutex> lock(m_.spareLock);
    try {
      m_.spare.push_back(std::move(s_));
    } catch (const std::bad_alloc&) {  // (the scratch is then freed: the next call makes another)
    }
  }
  ScratchLease(const ScratchLease&) = delete;
  ScratchLease& operator=(const ScratchLease&) = delete;
  Scratch& operator*() const { return *s_; }

 private:
  const Scene::Impl& m_;
  std::unique_ptr<Scratch> s_;
};

void pairUp(const Scene::Impl& m, std::span<const Ray> chunk, Scratch* s) {
  Pairs* p = &s->pairs;
  s->boxRays.assign(chunk);
  const detail::RayLists& l = s->lists;
  m.bvh.collect(s->boxRays, &s->lists);
  p->count.assign(m.instances.size(), 0);
  for (size_t c = 0; c < l.prim.size(); ++c) p->count[l.prim[c]] = l.count[c];
  p->first.resize(m.instances.size());
  uint32_t at = 0;
  for (uint32_t id : m.byField) {
    p->first[id] = at;
    at += p->count[id];
  }
  p->ray.resize(at);
  p->rays.resize(at);
  // The rays of a leaf's list lie anywhere in the chunk, and the leaves' instances anywhere in
  // the table: each is asked for a few steps ahead (the loop is too short for the core to find
  // the loads itself).
  const size_t listed = l.rays.size();
  for (size_t c = 0; c < l.prim.size(); ++c) {
    const uint32_t id = l.prim[c], to = p->first[id];
    const detail::ToObject& x = m.toObject[id];
    if (c + kLeavesAhead < l.prim.size()) __builtin_prefetch(&m.toObject[l.prim[c + kLeavesAhead]]);
    for (uint32_t k = 0; k < l.count[c]; ++k) {
      const size_t item = l.first[c] + k;
      const uint32_t r = l.rays[item];
      if (item + kRaysAhead < listed) __builtin_prefetch(&chunk[l.rays[item + kRaysAhead]]);
      p->ray[to + k] = r;
      p->rays[to + k] = x.ray(chunk[r]);
    }
  }
}

Status sizes(size_t rays, size_t out) {
  if (rays == out) return {};
  return makeError(Code::kInvalidArgument,
                   "scene: out has " + std::to_string(out) + " entries for " + std::to_string(rays) + " rays");
}

// Runs answer(field, object-space rays, answers) once per field, over the pairs of all its
// instances.
template <class T, class Answer>
void answerPairs(const Scene::Impl& m, const Pairs& p, std::vector<T>* answers, Answer&& answer) {
  answers->resize(p.rays.size());
  const std::span<const Ray> rays(p.rays);
  const std::span<T> out(*answers);
  for (size_t g = 0; g + 1 < m.fieldStart.size(); ++g) {
    const uint32_t lo = m.byField[m.fieldStart[g]], hi = m.byField[m.fieldStart[g + 1] - 1];
    const uint32_t a = p.first[lo], b = p.first[hi] + p.count[hi];
    if (a < b) answer(*m.instances[lo].field, rays.subspan(a, b - a), out.subspan(a, b - a));
  }
}

// With sources (chunk-relative): each field answers the pairs whose ray starts on their own
// instance with `on` (section 7.3) and the rest with `off` (7.4): two calls over the pairs
// gathered apart, or one in place where none of the field's pairs starts on its instance.
// The gathered halves live in the scratch (part: its vector for T), kept from call to call.
template <class T, class Answer>
void answerSourcedPairs(const Scene::Impl& m, const Pairs& p, const uint32_t* sources, const QueryOptions& on,
                        const QueryOptions& off, Scratch* s, std::vector<T>* answers, std::vector<T>* partOf,
                        Answer&& answer) {
  answers->resize(p.rays.size());
  const std::span<const Ray> all(p.rays);
  const std::span<T> out(*answers);
  std::vector<uint8_t>& own = s->own;
  std::vector<Ray>& rays = s->sourcedRays;
  std::vector<uint32_t>& at = s->sourcedAt;
  std::vector<T>& part = *partOf;
  for (size_t g = 0; g + 1 < m.fieldStart.size(); ++g) {
    const uint32_t lo = m.byField[m.fieldStart[g]], hi = m.byField[m.fieldStart[g + 1] - 1];
    const uint32_t a = p.first[lo], b = p.first[hi] + p.count[hi];
    if (a == b) continue;
    const FieldQuery& field = *m.instances[lo].field;
    own.assign(b - a, 0);
    bool any = false;
    for (uint32_t f = m.fieldStart[g]; f < m.fieldStart[g + 1]; ++f) {
      const uint32_t id = m.byField[f];
      for (uint32_t k = p.first[id]; k < p.first[id] + p.count[id]; ++k)
        if (sources[p.ray[k]] == id) own[k - a] = 1, any = true;
    }
    if (!any) {
      answer(field, all.subspan(a, b - a), out.subspan(a, b - a), off);
      continue;
    }
    for (const uint8_t which : {uint8_t(0), uint8_t(1)}) {
      rays.clear();
      at.clear();
      for (uint32_t k = a; k < b; ++k)
        if (own[k - a] == which) rays.push_back(p.rays[k]), at.push_back(k);
      if (at.empty()) continue;
      part.resize(at.size());
      answer(field, std::span<const Ray>(rays), std::span<T>(part), which ? on : off);
      for (size_t q = 0; q < at.size(); ++q) out[at[q]] = part[q];
    }
  }
}

// A call's options: `all` for a call without sources; with sources, `own` for the pairs whose ray
// starts on their instance and `others` for the rest.
struct PassOptions {
  QueryOptions all, own, others;
  explicit PassOptions(const QueryOptions& o) : all(o), own(o), others(o) {
    own.origin = RayOrigin::kOnObject;
    others.origin = RayOrigin::kOffObject;
  }
};

// The pairs of a chunk answered (answer(field, rays, out, options)), with the chunk's sources or
// without (null).
template <class T, class Answer>
void answerChunk(const Scene::Impl& m, const Pairs& p, const uint32_t* sources, const PassOptions& pass, Scratch* s,
                 std::vector<T>* answers, std::vector<T>* part, Answer&& answer) {
  if (sources) {
    answerSourcedPairs(m, p, sources, pass.own, pass.others, s, answers, part, answer);
  } else {
    answerPairs(m, p, answers, [&](const FieldQuery& f, std::span<const Ray> r, std::span<T> o) {
      answer(f, r, o, pass.all);
    });
  }
}

Status checkSources(const Scene::Impl* m, size_t rays, std::span<const uint32_t> sources) {
  if (sources.size() != rays)
    return makeError(Code::kInvalidArgument, "scene: sources has " + std::to_string(sources.size()) + " entries for " +
                                                 std::to_string(rays) + " rays");
  const size_t n = m ? m->instances.size() : 0;
  for (size_t r = 0; r < sources.size(); ++r)
    if (sources[r] != kNoInstance && sources[r] >= n)
      return makeError(Code::kOutOfRange, "scene: sources[" + std::to_string(r) + "] = " + std::to_string(sources[r]) +
                                              " is no instance (the scene has " + std::to_string(n) +
                                              "; kNoInstance for none)");
  return {};
}

// The frame the three batches share, with sources (one per ray) or without (sources.data() null;
// with rays, checkSources has made sure that a call with sources has them): the checks, `out`
// filled with `none`, then chunk by chunk the pairs found, answered into the scratch's `answers` by
// answer(field, rays, answers, options), and combine(first ray of the chunk, chunk, pairs, answers)
// folding them into `out`.
template <class Out, class T, class Answer, class Combine>
Status runBatch(const Scene::Impl* impl, std::span<const Ray> rays, std::span<const uint32_t> sources,
                std::span<Out> out, const Out& none, const QueryOptions& options, std::vector<T> Scratch::*answers,
                std::vector<T> Scratch::*part, Answer&& answer, Combine&& combine) {
  if (Status s = Scene::Impl::ready(impl); !s) return s;
  if (Status s = sizes(rays.size(), out.size()); !s) return s;
  std::fill(out.begin(), out.end(), none);
  if (!impl) return {};
  const Scene::Impl& m = *impl;
  const PassOptions pass(options);
  const ScratchLease lease(m);
  Scratch& s = *lease;
  for (size_t c = 0; c < rays.size(); c += kChunk) {
    const std::span<const Ray> chunk = rays.subspan(c, std::min(kChunk, rays.size() - c));
    pairUp(m, chunk, &s);
    answerChunk(m, s.pairs, sources.data() ? sources.data() + c : nullptr, pass, &s, &(s.*answers), &(s.*part), answer);
    combine(c, chunk, s.pairs, s.*answers);
  }
  return {};
}

Status intersectBatch(const Scene::Impl* impl, std::span<const Ray> rays, std::span<const uint32_t> sources,
                      std::span<SceneHit> out, const QueryOptions& options) {
  return runBatch(
      impl, rays, sources, out, SceneHit{}, options, &Scratch::hits, &Scratch::partHits,
      [](const FieldQuery& f, std::span<const Ray> r, std::span<QueryHit> h, const QueryOptions& o) { f.intersect(r, h, o); },
      [&](size_t c, std::span<const Ray> chunk, const Pairs& p, const std::vector<QueryHit>& hits) {
        for (uint32_t i = 0; i < impl->instances.size(); ++i)
          for (uint32_t k = p.first[i]; k < p.first[i] + p.count[i]; ++k) {
            SceneHit& best = out[c + p.ray[k]];
            if (hits[k].hit && hits[k].t < best.t) {
              QueryHit h = hits[k];
              detail::toWorld(impl->instances[i].transform, chunk[p.ray[k]], &h);
              static_cast<QueryHit&>(best) = h;
              best.instance = i;
            }
          }
      });
}

Status occludedBatch(const Scene::Impl* impl, std::span<const Ray> rays, std::span<const uint32_t> sources,
                     std::span<uint8_t> out, const QueryOptions& options) {
  return runBatch(
      impl, rays, sources, out, uint8_t(0), options, &Scratch::blocked, &Scratch::partBlocked,
      [](const FieldQuery& f, std::span<const Ray> r, std::span<uint8_t> o, const QueryOptions& q) { f.occluded(r, o, q); },
      [&](size_t c, std::span<const Ray>, const Pairs& p, const std::vector<uint8_t>& blocked) {
        for (size_t k = 0; k < p.ray.size(); ++k) out[c + p.ray[k]] |= blocked[k];
      });
}

Status visibilityBatch(const Scene::Impl* impl, std::span<const Ray> rays, std::span<const uint32_t> sources,
                       std::span<float> out, const QueryOptions& options) {
  return runBatch(
      impl, rays, sources, out, 1.0f, options, &Scratch::vis, &Scratch::partVis,
      [](const FieldQuery& f, std::span<const Ray> r, std::span<float> o, const QueryOptions& q) { f.visibility(r, o, q); },
      [&](size_t c, std::span<const Ray>, const Pairs& p, const std::vector<float>& vis) {
        for (uint32_t i = 0; i < impl->instances.size(); ++i)  // the product in id order
          for (uint32_t k = p.first[i]; k < p.first[i] + p.count[i]; ++k) out[c + p.ray[k]] *= vis[k];
      });
}

}  // namespace

Status Scene::intersect(std::span<const Ray> rays, std::span<SceneHit> out, const QueryOptions& options) const {
  return intersectBatch(impl_.get(), rays, {}, out, options);
}

Status Scene::occluded(std::span<const Ray> rays, std::span<uint8_t> out, const QueryOptions& options) const {
  return occludedBatch(impl_.get(), rays, {}, out, options);
}

Status Scene::visibility(std::span<const Ray> rays, std::span<float> out, const QueryOptions& options) const {
  return visibilityBatch(impl_.get(), rays, {}, out, options);
}

Status Scene::intersectFrom(std::span<const Ray> rays, std::span<const uint32_t> sources, std::span<SceneHit> out,
                            const QueryOptions& options) const {
  if (Status s = checkSources(impl_.get(), rays.size(), sources); !s) return s;
  return intersectBatch(impl_.get(), rays, sources, out, options);
}

Status Scene::occludedFrom(std::span<const Ray> rays, std::span<const uint32_t> sources, std::span<uint8_t> out,
                           const QueryOptions& options) const {
  if (Status s = checkSources(impl_.get(), rays.size(), sources); !s) return s;
  return occludedBatch(impl_.get(), rays, sources, out, options);
}

Status Scene::visibilityFrom(std::span<const Ray> rays, std::span<const uint32_t> sources, std::span<float> out,
                             const QueryOptions& options) const {
  if (Status s = checkSources(impl_.get(), rays.size(), sources); !s) return s;
  return visibilityBatch(impl_.get(), rays, sources, out, options);
}

}  // namespace vff
