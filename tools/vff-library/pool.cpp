// pool.cpp - the local pool: a few vff-bake processes at a time, each entry installed at its
// output as soon as its field is in the cache.
#include <unistd.h>

#include <atomic>
#include <mutex>
#include <thread>

#include "library.h"
#include "progress.h"

namespace vff::library {

std::vector<EntryOutcome> runPool(const std::vector<Entry>& entries, const std::vector<size_t>& todo,
                                  const WorkerOptions& wo, const PoolOptions& po) {
  std::vector<EntryOutcome> outcomes(todo.size());
  std::atomic<size_t> next{0}, done{0};
  cli::Progress progress(kProg, po.progress, 0, "entries");
  // The largest fields first, so that the last one to start is a small one.
  std::vector<size_t> order(todo);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return entries[a].rays > entries[b].rays; });
  auto work = [&] {
    for (size_t i; (i = next++) < order.size();) {
      const Entry& e = entries[order[i]];
      EntryOutcome& out = outcomes[i];
      out.entry = order[i];
      out.where = "local";
      out.result = bakeEntry(e, wo);
      if (out.result.ok)
        if (auto problem = installOutput(wo.cacheDir, e)) {
          out.result.ok = false;
          out.result.error = *problem;
          out.result.exitCode = 2;
        }
      progress.update(++done, order.size());
    }
  };
  std::vector<std::thread> pool;
  const unsigned n = std::max(1u, std::min<unsigned>(po.workers, unsigned(order.size())));
  for (unsigned t = 0; t < n; ++t) pool.emplace_back(work);
  for (auto& t : pool) t.join();
  return outcomes;
}

}  // namespace vff::library
