// pool.cpp - the local pool: a few vff-bake processes at a time, each entry installed at its
// output as soon as its field is in the cache. Each worker thread (platform/parallel.h, one unit
// per chunk) runs one vff-bake at a time and waits for it.
#include <unistd.h>

#include <algorithm>
#include <atomic>

#include "library.h"
#include "platform/parallel.h"
#include "progress.h"

namespace vff::library {

uint64_t unitRays(const std::vector<Entry>& entries, const Unit& u) {
  const Entry& e = entries[u.entry];
  return u.part() && e.maps ? e.rays / e.maps * (u.end - u.begin) : e.rays;
}

std::vector<EntryOutcome> runPool(const std::vector<Entry>& entries, const std::vector<Unit>& todo,
                                  const WorkerOptions& wo, const PoolOptions& po) {
  std::vector<EntryOutcome> outcomes(todo.size());
  std::atomic<size_t> done{0};
  cli::Progress progress(kProg, po.progress, 0, "entries");
  // The largest bakes first, so that the last one to start is a small one.
  std::vector<Unit> order(todo);
  std::stable_sort(order.begin(), order.end(),
                   [&](const Unit& a, const Unit& b) { return unitRays(entries, a) > unitRays(entries, b); });
  // Each outcome at its unit's place in `order`, whichever worker baked it.
  parallel::parallelFor(order.size(), 1, std::max(1u, po.workers), [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      const Entry& e = entries[order[i].entry];
      EntryOutcome& out = outcomes[i];
      out.entry = order[i].entry;
      out.unit = order[i];
      out.where = "local";
      out.result = bakeUnit(e, order[i], wo);
      if (out.result.ok && !order[i].part())
        if (auto problem = installOutput(wo.cacheDir, e)) {
          out.result.ok = false;
          out.result.error = *problem;
          out.result.exitCode = 2;
        }
      progress.update(++done, order.size());
    }
  });
  return outcomes;
}

}  // namespace vff::library
