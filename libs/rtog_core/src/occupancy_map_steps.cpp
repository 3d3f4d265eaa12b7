// Ordered per-beam steps (StepRule) into the planar cache: the update rule of grids that step
// every cell a beam touches, beam by beam (MRPT's COccupancyGridMap2D).
#include <limits>
#include <stdexcept>

#include "rtog/core/occupancy_map.hpp"

namespace rtog {

InsertStats OccupancyMap::applySteps(std::int32_t z, const CellStep* steps, std::size_t n, const StepRule& rule,
                                     float* after) {
  InsertStats stats;
  if (n == 0) return stats;
  // Every key checked before the first change: a throw leaves the map as it was.
  std::int32_t x0 = steps[0].x, x1 = x0, y0 = steps[0].y, y1 = y0;
  for (std::size_t i = 1; i < n; ++i) {
    x0 = std::min(x0, steps[i].x), x1 = std::max(x1, steps[i].x);
    y0 = std::min(y0, steps[i].y), y1 = std::max(y1, steps[i].y);
  }
  if (!keyInRange(Key{x0, y0, z}) || !keyInRange(Key{x1, y1, z}))
    throw std::out_of_range("OccupancyMap::applySteps: cells " + toString(Box{Key{x0, y0, z}, Key{x1, y1, z}}) +
                            " lie outside the key range");
  const int local_z = z & (kBrickSize - 1);
  const std::int32_t bz = z >> kBrickBits;
  // Consecutive steps of a beam mostly stay in one brick: its layer is looked up once for them.
  std::int32_t bx = std::numeric_limits<std::int32_t>::min(), by = bx;
  PlanarLayer* layer = nullptr;
  for (std::size_t i = 0; i < n; ++i) {
    const CellStep& s = steps[i];
    if ((s.x >> kBrickBits) != bx || (s.y >> kBrickBits) != by) {
      bx = s.x >> kBrickBits;
      by = s.y >> kBrickBits;
      layer = &planar_layers_[recent_layers_.get(packKey(Key{bx, by, z}), [&] {
        return planarLayer(brickSlot(Key{bx, by, bz}), local_z);
      })];
    }
    const int cell = ((s.y & (kBrickSize - 1)) << kBrickBits) | (s.x & (kBrickSize - 1));
    float& v = layer->value[static_cast<std::size_t>(cell)];
    const float prev = v;
    v = rule.apply(prev, s.kind);
    layer->known[static_cast<std::size_t>(cell >> 6)] |= std::uint64_t{1} << (cell & 63);
    if (after) after[i] = v;
    if (v == prev) ++stats.cells_unchanged;
    else if (s.kind == StepKind::Occupied) ++stats.cells_occupied;
    else ++stats.cells_free;
  }
  cover_pending_.store(true, std::memory_order_release);
  return stats;
}

}  // namespace rtog
