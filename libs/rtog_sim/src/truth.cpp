// Ground truth of a synthetic world on a lattice: which cells its solids occupy.
#include <algorithm>
#include <cmath>

#include "rtog/sim/world.hpp"

namespace rtog::sim {

namespace {
// Cells k with k*r < hi and (k+1)*r > lo: the open cell overlaps (lo, hi).
void cellRange(double lo, double hi, double inv_r, std::int32_t& k0, std::int32_t& k1) {
  k0 = static_cast<std::int32_t>(std::floor(lo * inv_r));
  k1 = static_cast<std::int32_t>(std::ceil(hi * inv_r)) - 1;
}
}  // namespace

TruthGrid TruthGrid::rasterize(const World& w, const Lattice& lat, const Box& region) {
  if (region.isEmpty()) throw std::invalid_argument("rtog::sim::TruthGrid: empty region");
  TruthGrid g;
  g.region_ = region;
  g.occ_.assign(static_cast<std::size_t>(region.volume()), 0);
  const double inv = 1.0 / lat.resolution();
  for (const auto& b : w.boxes()) {
    Box kb;
    cellRange(b.min.x(), b.max.x(), inv, kb.min.x, kb.max.x);
    cellRange(b.min.y(), b.max.y(), inv, kb.min.y, kb.max.y);
    cellRange(b.min.z(), b.max.z(), inv, kb.min.z, kb.max.z);
    const Box c = kb.intersection(region);
    if (c.isEmpty()) continue;
    forEachCell(c, [&](const Key& k) { g.occ_[g.index(k)] = 1; });
  }
  return g;
}

TruthGrid TruthGrid::rasterizeSlice(const World& w, const Lattice& lat, const Box& region, double plane_z) {
  if (region.isEmpty() || region.min.z != region.max.z)
    throw std::invalid_argument("rtog::sim::TruthGrid: a slice region must be one layer thick");
  TruthGrid g;
  g.region_ = region;
  g.occ_.assign(static_cast<std::size_t>(region.volume()), 0);
  const double inv = 1.0 / lat.resolution();
  for (const auto& b : w.boxes()) {
    if (plane_z < b.min.z() || plane_z > b.max.z()) continue;
    Box kb;
    cellRange(b.min.x(), b.max.x(), inv, kb.min.x, kb.max.x);
    cellRange(b.min.y(), b.max.y(), inv, kb.min.y, kb.max.y);
    kb.min.z = kb.max.z = region.min.z;
    const Box c = kb.intersection(region);
    if (c.isEmpty()) continue;
    forEachCell(c, [&](const Key& k) { g.occ_[g.index(k)] = 1; });
  }
  return g;
}

std::size_t TruthGrid::occupiedCount() const {
  return static_cast<std::size_t>(std::count(occ_.begin(), occ_.end(), std::uint8_t{1}));
}

Box worldKeyBox(const World& w, const Lattice& lat, int margin) {
  const Key lo = lat.key(w.boundsMin()), hi = lat.key(w.boundsMax());
  return Box{Key{lo.x - margin, lo.y - margin, lo.z - margin}, Key{hi.x + margin, hi.y + margin, hi.z + margin}};
}

}  // namespace rtog::sim
