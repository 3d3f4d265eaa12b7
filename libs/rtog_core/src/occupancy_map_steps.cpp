// Ordered per-beam steps (StepRule) into the planar cache: the update rule of grids that step
// every cell a beam touches, beam by beam (MRPT's COccupancyGridMap2D).
#include <algorithm>
#include <stdexcept>

#include "rtog/core/occupancy_map.hpp"

namespace rtog {

InsertStats OccupancyMap::applyStepRuns(std::int32_t z, const StepRun* runs, std::size_t n, const StepRule& rule,
                                        std::vector<float>* after) {
  InsertStats stats;
  if (after) after->clear();
  if (n == 0) return stats;
  // Every key checked before the first change (a run's cells lie between its first and last,
  // the walk being monotone): a throw leaves the map as it was.
  std::int32_t x0 = runs[0].x, x1 = x0, y0 = runs[0].y, y1 = y0;
  std::size_t steps = 0;
  const auto extend = [&](std::int64_t x, std::int64_t y) {
    if (x < kKeyMin || x > kKeyMax || y < kKeyMin || y > kKeyMax)
      throw std::out_of_range("OccupancyMap::applyStepRuns: a cell lies outside the key range");
    x0 = std::min(x0, static_cast<std::int32_t>(x)), x1 = std::max(x1, static_cast<std::int32_t>(x));
    y0 = std::min(y0, static_cast<std::int32_t>(y)), y1 = std::max(y1, static_cast<std::int32_t>(y));
  };
  for (std::size_t i = 0; i < n; ++i) {
    const StepRun& r = runs[i];
    extend(r.x, r.y);
    if (r.count > 0) {
      // Scaled by multiplying: a left shift of a negative start cell is undefined before C++20.
      constexpr std::int64_t kOne = std::int64_t{1} << kRunFracBits;
      const std::int64_t k = r.count - 1;
      extend((r.x * kOne + k * r.dx) >> kRunFracBits, (r.y * kOne + k * r.dy) >> kRunFracBits);
    }
    if (r.end) extend(r.end_x, r.end_y);
    steps += r.count + (r.end ? 1 : 0);
  }
  if (!keyInRange(Key{x0, y0, z}) || !keyInRange(Key{x1, y1, z}))
    throw std::out_of_range("OccupancyMap::applyStepRuns: z-layer outside the key range");
  if (after) after->reserve(steps);
  // The layers under the runs' bounding box by arithmetic, found or made on first use: the hash
  // lookups a step would cost otherwise (a beam changes brick every 16 cells).
  const std::int32_t bx0 = x0 >> kBrickBits, by0 = y0 >> kBrickBits;
  const auto bw = static_cast<std::size_t>((x1 >> kBrickBits) - bx0 + 1);
  const auto bh = static_cast<std::size_t>((y1 >> kBrickBits) - by0 + 1);
  std::vector<PlanarLayer*> table(bw * bh, nullptr);
  const int local_z = z & (kBrickSize - 1);
  const std::int32_t bz = z >> kBrickBits;
  const auto layerAt = [&](std::int32_t x, std::int32_t y) {
    PlanarLayer*& l = table[static_cast<std::size_t>((y >> kBrickBits) - by0) * bw +
                            static_cast<std::size_t>((x >> kBrickBits) - bx0)];
    if (!l) {
      const Key brick{x >> kBrickBits, y >> kBrickBits, bz};
      l = &planar_layers_[recent_layers_.get(packKey(Key{brick.x, brick.y, z}),
                                             [&] { return planarLayer(brickSlot(brick), local_z); })];
    }
    return l;
  };
  // The walk of forEachRunCell, with the rule's constants of the run's kind hoisted and the
  // layer kept while the walk stays in its brick: this loop is the whole cost of a 2D scan.
  std::int32_t cur_bx = 0, cur_by = 0;
  PlanarLayer* layer = nullptr;
  std::size_t unchanged = 0, free_steps = 0, occupied_steps = 0;
  const auto step = [&](std::int32_t x, std::int32_t y, bool occupied, float delta, float limit, float bound) {
    if (!layer || (x >> kBrickBits) != cur_bx || (y >> kBrickBits) != cur_by) {
      cur_bx = x >> kBrickBits, cur_by = y >> kBrickBits;
      layer = layerAt(x, y);
    }
    const int cell = ((y & (kBrickSize - 1)) << kBrickBits) | (x & (kBrickSize - 1));
    float& v = layer->value[static_cast<std::size_t>(cell)];
    const float prev = v;
    v = (occupied ? prev < limit : prev > limit) ? prev + delta : bound;  // StepRule::apply
    layer->known[static_cast<std::size_t>(cell >> 6)] |= std::uint64_t{1} << (cell & 63);
    unchanged += v == prev;
    if (after) after->push_back(v);
  };
  for (std::size_t i = 0; i < n; ++i) {
    const StepRun& r = runs[i];
    const auto k = static_cast<std::size_t>(r.kind);
    const float delta = rule.delta[k], limit = rule.limit[k], bound = rule.bound[k];
    const bool occ = r.kind == StepKind::Occupied;
    std::int32_t fx = r.x * (1 << kRunFracBits), fy = r.y * (1 << kRunFracBits);
    for (std::uint32_t c = 0; c < r.count; ++c, fx += r.dx, fy += r.dy)
      step(fx >> kRunFracBits, fy >> kRunFracBits, occ, delta, limit, bound);
    (occ ? occupied_steps : free_steps) += r.count;
    if (r.end) {
      const auto o = static_cast<std::size_t>(StepKind::Occupied);
      step(r.end_x, r.end_y, true, rule.delta[o], rule.limit[o], rule.bound[o]);
      ++occupied_steps;
    }
  }
  // Changed steps by kind; unchanged ones (saturated cells) are not told apart by kind.
  stats.cells_unchanged = unchanged;
  stats.cells_free = free_steps;
  stats.cells_occupied = occupied_steps;
  cover_pending_.store(true, std::memory_order_release);
  return stats;
}

}  // namespace rtog
