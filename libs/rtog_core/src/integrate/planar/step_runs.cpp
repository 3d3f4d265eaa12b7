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

constexpr int F = kStepRunFracBits;
constexpr std::int32_t kCell = 1 << F;
constexpr int kBrickFrac = F + kBrickBits;
constexpr std::int64_t kSpan = std::int64_t{1} << kBrickFrac;  // a brick's width in fixed point

/// Steps that fixed-point coordinate `f`, moving by `d`, takes before it leaves its brick (all
/// of them if it never does): without a division where it can, as a raster's major axis moves
/// a whole cell a step.
std::uint32_t stepsToEdge(std::int32_t f, std::int32_t d) {
  if (d == 0) return std::numeric_limits<std::uint32_t>::max();
  const std::int64_t lo = (std::int64_t{f} >> kBrickFrac) * kSpan, hi = lo + kSpan;  // [lo, hi)
  if (d == kCell) return static_cast<std::uint32_t>((hi - f + kCell - 1) >> F);
  if (d == -kCell) return static_cast<std::uint32_t>(((f - lo) >> F) + 1);
  const auto in = static_cast<std::uint64_t>(d > 0 ? hi - f : f - lo + 1);  // in (0, kSpan]
  const auto step = static_cast<std::uint64_t>(d > 0 ? std::int64_t{d} : -std::int64_t{d});
  if (step < static_cast<std::uint64_t>(kSpan))  // in 32 bits: a 64-bit division takes longer
    return (static_cast<std::uint32_t>(in) + static_cast<std::uint32_t>(step) - 1) / static_cast<std::uint32_t>(step);
  return static_cast<std::uint32_t>((in + step - 1) / step);
}

/// The steps of one stretch of a run in a layer of floats: `n` cells in one brick z-layer
/// (`value`, `known`), from fixed-point (fx, fy) by (dx, dy). Returns the cells left unchanged
/// (saturated).
/// Compiled per kind and per whether the layer is already all known, as the rule's branch would
/// otherwise sit in the loop. The rule is a bit select, not a branch: whether a cell has
/// saturated follows no pattern along a beam. Equal is compared on the bits, as the value is
/// never NaN and the float compare of a NaN-aware `==` costs a parity test.
template <bool Occupied, bool AllKnown>
std::size_t stepStretch(float* value, std::uint64_t* known, std::int32_t fx, std::int32_t fy,
                        std::int32_t dx, std::int32_t dy, std::uint32_t n, float delta, float limit, float bound,
                        std::vector<float>* after) {
  constexpr int M = kBrickSize - 1;
  const std::uint32_t bound_bits = bitsOf(bound);
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
  return same;
}

/// How a stretch's cells are addressed: generically, or along a major axis that moves a whole
/// cell a step (a raster's, as MRPT's), whose part of the index then just counts.
enum class Axis { Any, X, Y };

/// The steps of one stretch in a coded layer: the code after a step is a table lookup (see
/// StepCodec), the unchanged count a bit of the same entry. Returns the entries' sum, whose
/// bits from kSameBit up count the unchanged steps (the codes below them add up to less than
/// one unit of that bit, for n <= kCodedChunk).
constexpr std::uint32_t kCodedChunk = 1u << (StepCodec::kSameBit - 8);

template <Axis A, bool After>
std::uint64_t stepCodedChunk(std::int8_t* code, std::int32_t fx, std::int32_t fy, std::int32_t dx, std::int32_t dy,
                             std::uint32_t n, const std::uint32_t* table, const float* values,
                             std::vector<float>* after) {
  constexpr int M = kBrickSize - 1;
  // Along X the column is the major coordinate and moves by `major` a step; along Y the row.
  const int major = A == Axis::X ? (dx > 0 ? 1 : -1) : (dy > 0 ? kBrickSize : -kBrickSize);
  std::int8_t* p = code;
  if (A == Axis::X) p += (fx >> F) & M;
  if (A == Axis::Y) p += ((fy >> F) & M) << kBrickBits;
  std::uint64_t sum = 0;
  for (; n > 0; --n, fx += dx, fy += dy) {
    std::int8_t* q;
    if (A == Axis::X) {
      q = p + ((fy >> (F - kBrickBits)) & (M << kBrickBits));
      p += major;
    } else if (A == Axis::Y) {
      q = p + ((fx >> F) & M);
      p += major;
    } else {
      q = code + ((((fy >> F) & M) << kBrickBits) | ((fx >> F) & M));
    }
    const std::uint32_t t = table[static_cast<std::uint8_t>(*q)];
    *q = static_cast<std::int8_t>(t & 0xFFu);
    sum += t;
    if (After) after->push_back(values[t & 0xFFu]);
  }
  return sum;
}

/// The unchanged steps of a stretch of any length (a run that stays in one cell may take more
/// steps than a chunk holds).
template <Axis A, bool After>
std::size_t stepCoded(std::int8_t* code, std::int32_t fx, std::int32_t fy, std::int32_t dx, std::int32_t dy,
                      std::uint32_t n, const std::uint32_t* table, const float* values, std::vector<float>* after) {
  std::size_t same = 0;
  for (; n > kCodedChunk; n -= kCodedChunk) {
    same += stepCodedChunk<A, After>(code, fx, fy, dx, dy, kCodedChunk, table, values, after) >> StepCodec::kSameBit;
    fx += static_cast<std::int32_t>(kCodedChunk) * dx, fy += static_cast<std::int32_t>(kCodedChunk) * dy;
  }
  return same + (stepCodedChunk<A, After>(code, fx, fy, dx, dy, n, table, values, after) >> StepCodec::kSameBit);
}

/// The layers under a scan's runs, by brick (made on first use).
struct LayerGrid {
  PlanarLayer** layers;  // row-major, `width` bricks a row, brick (x0, y0) first
  std::size_t width;
  std::int32_t x0, y0;
};

/// One run's walk, cut into the stretches it spends in one brick: the whole cost of a 2D scan.
/// A function of its own, taking the grid by value, so that what a stretch needs stays in
/// registers.
template <Axis A, bool After, class Make, class Floats>
[[gnu::noinline]] std::size_t walkRun(const StepRun& r, const LayerGrid grid, Make& make, Floats& floats,
                                      const std::uint32_t* table, const float* values, std::vector<float>* after) {
  const std::int32_t dx = r.dx, dy = r.dy;
  std::int32_t fx = r.x * kCell + static_cast<std::int32_t>(r.skip) * dx, fy = r.y * kCell + static_cast<std::int32_t>(r.skip) * dy;
  std::size_t same = 0;
  std::uint32_t left = r.count, sx = stepsToEdge(fx, dx), sy = stepsToEdge(fy, dy);
  const auto slotOf = [&] {
    return static_cast<std::ptrdiff_t>((fy >> kBrickFrac) - grid.y0) * static_cast<std::ptrdiff_t>(grid.width) +
           static_cast<std::ptrdiff_t>((fx >> kBrickFrac) - grid.x0);
  };
  // A step of less than a brick leaves a brick for its neighbour: the slot moves by one.
  const bool adjacent = dx > -kSpan && dx < kSpan && dy > -kSpan && dy < kSpan;
  const std::ptrdiff_t next_x = dx > 0 ? 1 : -1;
  const std::ptrdiff_t next_y = dy > 0 ? static_cast<std::ptrdiff_t>(grid.width) : -static_cast<std::ptrdiff_t>(grid.width);
  std::ptrdiff_t slot = slotOf();
  while (left > 0) {
    const std::uint32_t m = std::min(left, std::min(sx, sy));
    PlanarLayer* layer = grid.layers[slot];
    if (!layer) layer = grid.layers[slot] = &make(fx >> F, fy >> F);
    if (layer->form == LayerForm::Codes)
      same += stepCoded<A, After>(layer->code.data(), fx, fy, dx, dy, m, table, values, after);
    else
      same += floats(*layer, fx, fy, dx, dy, m, r.kind);
    left -= m;
    if (left == 0) break;
    fx += static_cast<std::int32_t>(m) * dx, fy += static_cast<std::int32_t>(m) * dy;
    sx -= m, sy -= m;
    if (sx == 0) sx = stepsToEdge(fx, dx), slot += next_x;
    if (sy == 0) sy = stepsToEdge(fy, dy), slot += next_y;
    if (!adjacent) slot = slotOf();
  }
  return same;
}

template <bool After, class Make, class Floats>
std::size_t walkRun(const StepRun& r, const LayerGrid& grid, Make& make, Floats& floats, const StepCodec& codec,
                    std::vector<float>* after) {
  const std::uint32_t* table = codec.table(r.kind);
  const float* values = codec.values();
  if (r.dx == kCell || r.dx == -kCell) return walkRun<Axis::X, After>(r, grid, make, floats, table, values, after);
  if (r.dy == kCell || r.dy == -kCell) return walkRun<Axis::Y, After>(r, grid, make, floats, table, values, after);
  return walkRun<Axis::Any, After>(r, grid, make, floats, table, values, after);
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
    // Scaled by multiplying: a left shift of a negative start cell is undefined before C++20.
    constexpr std::int64_t kOne = std::int64_t{1} << kStepRunFracBits;
    const std::int64_t k0 = r.skip;
    extend((r.x * kOne + k0 * r.dx) >> kStepRunFracBits, (r.y * kOne + k0 * r.dy) >> kStepRunFracBits);
    if (r.count > 0) {
      const std::int64_t k = k0 + r.count - 1;
      extend((r.x * kOne + k * r.dx) >> kStepRunFracBits, (r.y * kOne + k * r.dy) >> kStepRunFracBits);
    }
    if (r.end) extend(r.end_x, r.end_y);
    steps += r.count + (r.end ? 1 : 0);
  }
  if (!keyInRange(Key{x0, y0, z}) || !keyInRange(Key{x1, y1, z}))
    throw std::out_of_range("OccupancyMap::applyStepRuns: z-layer outside the key range");
  if (after) after->reserve(steps);
  useRule(rule, store.model.prior());
  const bool codes = codec_.usable();
  // The layers under the runs' bounding box by arithmetic, found or made on first use: the hash
  // lookups a step would cost otherwise (a beam changes brick every 16 cells).
  const std::int32_t bx0 = x0 >> kBrickBits, by0 = y0 >> kBrickBits;
  const auto bw = static_cast<std::size_t>((x1 >> kBrickBits) - bx0 + 1);
  const auto bh = static_cast<std::size_t>((y1 >> kBrickBits) - by0 + 1);
  std::vector<PlanarLayer*> table(bw * bh, nullptr);
  const std::int32_t bz = z >> kBrickBits;
  const LayerGrid grid{table.data(), bw, bx0, by0};
  // Both called seldom: out of line, so that the walk keeps its values in registers.
  const auto make = [&](std::int32_t x, std::int32_t y) __attribute__((noinline)) -> PlanarLayer& {
    return layerAt(store, Key{x >> kBrickBits, y >> kBrickBits, bz}, z, codes);
  };
  // The steps in forEachRunCell's order, run by run (a beam's end cell as a run of one).
  const auto floats = [&](PlanarLayer& layer, std::int32_t fx, std::int32_t fy, std::int32_t dx, std::int32_t dy,
                          std::uint32_t m, StepKind kind) __attribute__((noinline)) -> std::size_t {
    const auto k = static_cast<std::size_t>(kind);
    const float delta = rule.delta[k], limit = rule.limit[k], bound = rule.bound[k];
    std::uint64_t all = ~std::uint64_t{0};
    for (const std::uint64_t w : layer.known) all &= w;
    float* const v = values(layer);
    std::uint64_t* const kn = layer.known.data();
    const bool full = all == ~std::uint64_t{0};
    if (kind == StepKind::Occupied)
      return full ? stepStretch<true, true>(v, kn, fx, fy, dx, dy, m, delta, limit, bound, after)
                  : stepStretch<true, false>(v, kn, fx, fy, dx, dy, m, delta, limit, bound, after);
    return full ? stepStretch<false, true>(v, kn, fx, fy, dx, dy, m, delta, limit, bound, after)
                : stepStretch<false, false>(v, kn, fx, fy, dx, dy, m, delta, limit, bound, after);
  };
  std::size_t unchanged = 0, free_steps = 0, occupied_steps = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const StepRun& r = runs[i];
    unchanged += after ? walkRun<true>(r, grid, make, floats, codec_, after)
                       : walkRun<false>(r, grid, make, floats, codec_, after);
    (r.kind == StepKind::Occupied ? occupied_steps : free_steps) += r.count;
    if (r.end) {  // a run of one cell, without a run's walk
      const std::int32_t ex = r.end_x * kCell, ey = r.end_y * kCell;
      PlanarLayer*& slot = table[static_cast<std::size_t>((r.end_y >> kBrickBits) - by0) * bw +
                                 static_cast<std::size_t>((r.end_x >> kBrickBits) - bx0)];
      if (!slot) slot = &make(r.end_x, r.end_y);
      const std::uint32_t* t = codec_.table(StepKind::Occupied);
      if (slot->form != LayerForm::Codes)
        unchanged += floats(*slot, ex, ey, 0, 0, 1, StepKind::Occupied);
      else if (after)
        unchanged += stepCoded<Axis::Any, true>(slot->code.data(), ex, ey, 0, 0, 1, t, codec_.values(), after);
      else
        unchanged += stepCoded<Axis::Any, false>(slot->code.data(), ex, ey, 0, 0, 1, t, codec_.values(), after);
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
