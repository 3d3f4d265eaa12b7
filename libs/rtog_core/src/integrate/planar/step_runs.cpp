// Ordered per-beam steps (StepRule) into the planar cache: the update rule of grids that step
// every cell a beam touches, beam by beam (MRPT's COccupancyGridMap2D).
#include <algorithm>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "integrate/planar/planar_cache.hpp"

namespace rtog {
namespace {

std::uint32_t bitsOf(float v) {
  std::uint32_t u;
  std::memcpy(&u, &v, sizeof u);
  return u;
}

/// The steps of one stretch of a run: `n` cells in one brick z-layer (`value`, `known`), from
/// fixed-point (fx, fy) by (dx, dy). Returns the cells left unchanged (saturated).
/// Compiled per kind and per whether the layer is already all known, as the rule's branch would
/// otherwise sit in the loop. The rule is a bit select, not a branch: whether a cell has
/// saturated follows no pattern along a beam. Equal is compared on the bits, as the value is
/// never NaN and the float compare of a NaN-aware `==` costs a parity test.
template <bool Occupied, bool AllKnown>
std::size_t stepStretch(float* value, std::uint64_t* known, std::int32_t& fx_io, std::int32_t& fy_io,
                        std::int32_t dx, std::int32_t dy, std::uint32_t n, float delta, float limit, float bound,
                        std::vector<float>* after) {
  constexpr int F = kStepRunFracBits;
  constexpr int M = kBrickSize - 1;
  const std::uint32_t bound_bits = bitsOf(bound);
  std::int32_t fx = fx_io, fy = fy_io;
  int word = -1;
  std::uint64_t mask = 0;
  std::size_t same = 0;
  for (std::uint32_t c = 0; c < n; ++c, fx += dx, fy += dy) {
    const int cell = (((fy >> F) & M) << kBrickBits) | ((fx >> F) & M);
    const float prev = value[cell];
    const std::uint32_t take = 0u - static_cast<std::uint32_t>(Occupied ? prev < limit : prev > limit);
    const std::uint32_t prev_bits = bitsOf(prev);
    const std::uint32_t v_bits = (bitsOf(prev + delta) & take) | (bound_bits & ~take);  // StepRule::apply
    float v;
    std::memcpy(&v, &v_bits, sizeof v);
    value[cell] = v;
    same += v_bits == prev_bits;
    if (after) after->push_back(v);
    if (!AllKnown) {
      if ((cell >> 6) != word) {
        if (word >= 0) known[word] |= mask;
        word = cell >> 6, mask = 0;
      }
      mask |= std::uint64_t{1} << (cell & 63);
    }
  }
  if (!AllKnown && word >= 0) known[word] |= mask;
  fx_io = fx, fy_io = fy;
  return same;
}

}  // namespace

InsertStats PlanarCache::applyStepRuns(MapStore& store, std::int32_t z, const StepRun* runs, std::size_t n,
                                       const StepRule& rule, std::vector<float>* after) {
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
      constexpr std::int64_t kOne = std::int64_t{1} << kStepRunFracBits;
      const std::int64_t k = r.count - 1;
      extend((r.x * kOne + k * r.dx) >> kStepRunFracBits, (r.y * kOne + k * r.dy) >> kStepRunFracBits);
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
  const std::int32_t bz = z >> kBrickBits;
  const auto layerOf = [&](std::int32_t x, std::int32_t y) {
    PlanarLayer*& l = table[static_cast<std::size_t>((y >> kBrickBits) - by0) * bw +
                            static_cast<std::size_t>((x >> kBrickBits) - bx0)];
    if (!l) l = &layerAt(store, Key{x >> kBrickBits, y >> kBrickBits, bz}, z);
    return l;
  };
  // The walk of forEachRunCell, cut into the stretches a run spends in one brick: this loop is
  // the whole cost of a 2D scan. Within a stretch the layer is fixed, and the known bits and the
  // count of unchanged cells stay in registers: as memory read-modify-writes, one per step, they
  // would chain every step to the store of the step before.
  std::size_t unchanged = 0, free_steps = 0, occupied_steps = 0;
  constexpr std::int32_t kBrickFrac = kStepRunFracBits + kBrickBits;
  // Steps that fixed-point coordinate `f`, moving by `d`, takes before it leaves its brick, if
  // fewer than `m`: without a division where it can (a division costs tens of cycles, and a
  // raster's major axis moves a whole cell a step; its minor one mostly stays in the brick).
  constexpr std::int64_t kSpan = std::int64_t{1} << kBrickFrac;
  const auto stepsInBrick = [](std::int32_t f, std::int32_t d, std::int64_t m) -> std::int64_t {
    if (d == 0) return m;
    const std::int64_t b = f >> kBrickFrac, lo = b * kSpan, hi = lo + kSpan;  // [lo, hi)
    constexpr std::int32_t kCell = 1 << kStepRunFracBits;
    if (d == kCell) return std::min<std::int64_t>(m, (hi - f + kCell - 1) >> kStepRunFracBits);
    if (d == -kCell) return std::min<std::int64_t>(m, ((f - lo) >> kStepRunFracBits) + 1);
    const std::int64_t last = f + (m - 1) * std::int64_t{d};
    if (last >= lo && last < hi) return m;
    return d > 0 ? (hi - f + d - 1) / d : (f - lo) / -d + 1;
  };
  const auto stretch = [&](std::int32_t& fx, std::int32_t& fy, std::int32_t dx, std::int32_t dy, std::uint32_t m,
                           bool occupied, float delta, float limit, float bound) {
    PlanarLayer& layer = *layerOf(fx >> kStepRunFracBits, fy >> kStepRunFracBits);
    std::uint64_t all = ~std::uint64_t{0};
    for (const std::uint64_t w : layer.known) all &= w;
    float* const v = layer.value.data();
    std::uint64_t* const k = layer.known.data();
    const bool full = all == ~std::uint64_t{0};
    if (occupied)
      unchanged += full ? stepStretch<true, true>(v, k, fx, fy, dx, dy, m, delta, limit, bound, after)
                        : stepStretch<true, false>(v, k, fx, fy, dx, dy, m, delta, limit, bound, after);
    else
      unchanged += full ? stepStretch<false, true>(v, k, fx, fy, dx, dy, m, delta, limit, bound, after)
                        : stepStretch<false, false>(v, k, fx, fy, dx, dy, m, delta, limit, bound, after);
  };
  for (std::size_t i = 0; i < n; ++i) {
    const StepRun& r = runs[i];
    const auto k = static_cast<std::size_t>(r.kind);
    const float delta = rule.delta[k], limit = rule.limit[k], bound = rule.bound[k];
    const bool occ = r.kind == StepKind::Occupied;
    std::int32_t fx = r.x * (1 << kStepRunFracBits), fy = r.y * (1 << kStepRunFracBits);
    for (std::uint32_t left = r.count; left > 0;) {
      const auto m = static_cast<std::uint32_t>(stepsInBrick(fy, r.dy, stepsInBrick(fx, r.dx, left)));
      stretch(fx, fy, r.dx, r.dy, m, occ, delta, limit, bound);
      left -= m;
    }
    (occ ? occupied_steps : free_steps) += r.count;
    if (r.end) {
      const auto o = static_cast<std::size_t>(StepKind::Occupied);
      std::int32_t ex = r.end_x * (1 << kStepRunFracBits), ey = r.end_y * (1 << kStepRunFracBits);
      stretch(ex, ey, 0, 0, 1, true, rule.delta[o], rule.limit[o], rule.bound[o]);
      ++occupied_steps;
    }
  }
  // Changed steps by kind; unchanged ones (saturated cells) are not told apart by kind.
  stats.cells_unchanged = unchanged;
  stats.cells_free = free_steps;
  stats.cells_occupied = occupied_steps;
  return stats;
}

}  // namespace rtog
