#include "integrate/planar/step_clip.hpp"

#include <algorithm>
#include <stdexcept>

namespace rtog {
namespace {

constexpr std::int64_t kOne = std::int64_t{1} << kStepRunFracBits;

/// Cell k of a run (k counted from its first walked cell), as forEachRunCell walks it (scaled by
/// multiplying: a left shift of a negative cell is undefined before C++20).
void runCell(const StepRun& r, std::int64_t k, std::int32_t& x, std::int32_t& y) {
  x = static_cast<std::int32_t>((r.x * kOne + (r.skip + k) * r.dx) >> kStepRunFracBits);
  y = static_cast<std::int32_t>((r.y * kOne + (r.skip + k) * r.dy) >> kStepRunFracBits);
}

/// The steps k in [0, count) whose cell's coordinate on one axis lies in [lo, hi]: an interval,
/// the coordinate being monotone in k (found by bisection). Empty: first > last.
void axisInterval(const StepRun& r, int axis, std::int64_t lo, std::int64_t hi, std::int64_t& first, std::int64_t& last) {
  const auto at = [&](std::int64_t k) {
    std::int32_t x, y;
    runCell(r, k, x, y);
    return std::int64_t{axis == 0 ? x : y};
  };
  const std::int64_t n = r.count;
  const bool up = (axis == 0 ? r.dx : r.dy) >= 0;
  // The first k of the part at or past the bound in the run's direction, by bisection.
  const auto firstWhere = [&](auto&& pred) {
    std::int64_t a = 0, b = n;  // pred false before a... true from b
    while (a < b) {
      const std::int64_t m = a + (b - a) / 2;
      if (pred(at(m))) b = m;
      else a = m + 1;
    }
    return a;
  };
  if (up) {
    first = firstWhere([&](std::int64_t v) { return v >= lo; });
    last = firstWhere([&](std::int64_t v) { return v > hi; }) - 1;
  } else {
    first = firstWhere([&](std::int64_t v) { return v <= hi; });
    last = firstWhere([&](std::int64_t v) { return v < lo; }) - 1;
  }
}

void checkKey(std::int32_t x, std::int32_t y, std::int32_t z) {
  if (!keyInRange(Key{x, y, z}))
    throw std::out_of_range("OccupancyMap::applyStepRuns: a cell lies outside the key range");
}

}  // namespace

void clipStepRuns(const MapStore& store, std::int32_t z, const StepRun* runs, std::size_t n, std::vector<StepRun>& out,
                  std::vector<std::uint8_t>& kept) {
  out.clear();
  kept.clear();
  const std::int32_t bz = z >> kBrickBits;
  const auto owns = [&](std::int32_t x, std::int32_t y) {
    return store.ownsBrick(Key{x >> kBrickBits, y >> kBrickBits, bz});
  };
  for (std::size_t i = 0; i < n; ++i) {
    const StepRun& r = runs[i];
    if (r.count > 0) {
      // The walk is monotone in x and y: its cells lie in the box of its first and last.
      std::int32_t x0, y0, x1, y1;
      runCell(r, 0, x0, y0);
      runCell(r, r.count - 1, x1, y1);
      checkKey(x0, y0, z);
      checkKey(x1, y1, z);
      const Key lo{std::min(x0, x1) >> kBrickBits, std::min(y0, y1) >> kBrickBits, bz};
      const Key hi{std::max(x0, x1) >> kBrickBits, std::max(y0, y1) >> kBrickBits, bz};
      const Box bricks{lo, hi};
      if (store.region.contains(bricks)) {
        StepRun whole = r;
        whole.end = false;
        out.push_back(whole);
        kept.insert(kept.end(), r.count, 1);
      } else if (!store.region.intersects(bricks)) {
        kept.insert(kept.end(), r.count, 0);
      } else {
        // The part inside: an interval of steps (monotone on each axis, a box on both), kept as a
        // run of the same raster from a later step.
        // A brick's first cell by multiplying: a left shift of a negative brick is undefined.
        const auto first = [](std::int32_t brick) { return std::int64_t{brick} * (std::int64_t{1} << kBrickBits); };
        const std::int64_t last = (std::int64_t{1} << kBrickBits) - 1;
        std::int64_t a0, a1, b0, b1;
        axisInterval(r, 0, first(store.region.min.x), first(store.region.max.x) + last, a0, a1);
        axisInterval(r, 1, first(store.region.min.y), first(store.region.max.y) + last, b0, b1);
        const std::int64_t k0 = std::max(a0, b0), k1 = std::min(a1, b1);
        const bool layer_in = bz >= store.region.min.z && bz <= store.region.max.z;
        if (!layer_in || k0 > k1) {
          kept.insert(kept.end(), r.count, 0);
        } else {
          kept.insert(kept.end(), static_cast<std::size_t>(k0), 0);
          kept.insert(kept.end(), static_cast<std::size_t>(k1 - k0 + 1), 1);
          kept.insert(kept.end(), static_cast<std::size_t>(r.count - 1 - k1), 0);
          StepRun part = r;
          part.end = false;
          part.skip = r.skip + static_cast<std::uint32_t>(k0);
          part.count = static_cast<std::uint32_t>(k1 - k0 + 1);
          out.push_back(part);
        }
      }
    }
    if (r.end) {
      checkKey(r.end_x, r.end_y, z);
      const bool in = owns(r.end_x, r.end_y);
      kept.push_back(in);
      if (in) out.push_back(StepRun{r.end_x, r.end_y, 0, 0, 0, StepKind::Occupied, true, r.end_x, r.end_y});
    }
  }
}

}  // namespace rtog
