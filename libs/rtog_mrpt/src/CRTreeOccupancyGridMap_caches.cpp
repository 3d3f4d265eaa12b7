// The caches' owner: copy and assignment keep Caches' own rules (a copy or an assignment shares
// the source's view tiles and drops the rest, each under the locks it needs).
#include "CRTreeOccupancyGridMap_caches.hpp"

#include "CRTreeOccupancyGridMap_grid2d.hpp"  // GridView complete for the shared_ptr's deleter

namespace rtog {

CRTreeOccupancyGridMap::CachesHolder::CachesHolder() : p_(std::make_unique<Caches>()) {}
CRTreeOccupancyGridMap::CachesHolder::~CachesHolder() = default;
CRTreeOccupancyGridMap::CachesHolder::CachesHolder(const CachesHolder& o) : p_(std::make_unique<Caches>(*o.p_)) {}
CRTreeOccupancyGridMap::CachesHolder& CRTreeOccupancyGridMap::CachesHolder::operator=(const CachesHolder& o) {
  *p_ = *o.p_;
  return *this;
}

}  // namespace rtog
