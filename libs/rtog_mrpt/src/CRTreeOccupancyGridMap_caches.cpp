// The caches' owner: copy and assignment keep Caches' own rules (a copy or an assignment shares
// the source's view tiles and drops the rest, each under the locks it needs).
#include "CRTreeOccupancyGridMap_caches.hpp"

#include "CRTreeOccupancyGridMap_grid2d.hpp"  // GridView complete for the shared_ptr's deleter

#include <atomic>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace rtog {

// A map's cells are many small blocks (bricks, layers, tiles) that glibc keeps resident after
// they are freed. An app that drops its maps and then does more (rbpf-slam saves and exits,
// running every library's destructors) would carry them in its peak RSS: when the last map goes,
// the free heap is given back. Maps alive (a particle filter's) never pay for it. The holder
// counts the maps: one a map, destroyed after the map's cells.
namespace {
std::atomic<long> live_maps{0};
}  // namespace

CRTreeOccupancyGridMap::CachesHolder::CachesHolder() : p_(std::make_unique<Caches>()) {
  live_maps.fetch_add(1, std::memory_order_relaxed);
}
CRTreeOccupancyGridMap::CachesHolder::~CachesHolder() {
  p_.reset();
  if (live_maps.fetch_sub(1, std::memory_order_acq_rel) != 1) return;
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}
CRTreeOccupancyGridMap::CachesHolder::CachesHolder(const CachesHolder& o) : p_(std::make_unique<Caches>(*o.p_)) {
  live_maps.fetch_add(1, std::memory_order_relaxed);
}
CRTreeOccupancyGridMap::CachesHolder& CRTreeOccupancyGridMap::CachesHolder::operator=(const CachesHolder& o) {
  *p_ = *o.p_;
  return *this;
}

}  // namespace rtog
