#include "integrate/range_noise_integrator.hpp"

#include <algorithm>

#include "integrate/beam_integrator.hpp"
#include "integrate/insert_scratch.hpp"
#include "parallel/parallel.hpp"
#include "storage/map_store.hpp"

namespace rtog {

UpdateSet RangeNoiseIntegrator::trace(const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                                      std::size_t count, const InsertParams& ip, const std::uint8_t* is_hit) {
  const MapStore& store = ctx_.store;
  (void)store.lattice.key(origin);  // throws for a bad origin, before any thread starts
  InsertScratch& scratch = ctx_.scratch;
  const std::size_t threads = traceThreads(count, ip);
  if (scratch.graded.size() < threads) scratch.graded.resize(threads);
  std::vector<InsertStats> part(threads);
  scratch.shared_ends.count(store.lattice, origin, points, count, ip, is_hit);
  // The union of the threads' scans does not depend on the split (per cell the largest change,
  // miss masks or-ed).
  parallel::traceChunks(
      count, std::clamp<std::size_t>(count / (16 * threads), 256, 2048), part,
      [&](std::size_t t) { scratch.graded[t].clear(); },
      [&](std::size_t t, std::size_t first, std::size_t n, InsertStats& own) {
        scratch.graded[t].traceRangeNoise(store.lattice, store.model, origin, points + first, n, ip,
                                          is_hit ? is_hit + first : nullptr, &scratch.shared_ends, first, own);
        return true;
      },
      [&](std::size_t t) { scratch.graded[t].finalize(); });
  UpdateSet set;
  set.kind = UpdateSet::Kind::Graded;
  set.planar_ok = ip.planar_cache;
  for (std::size_t t = 0; t < threads; ++t) {
    set.stats += part[t];
    set.graded.push_back(&scratch.graded[t]);
  }
  set.threads = static_cast<int>(threads);
  return set;
}

}  // namespace rtog
