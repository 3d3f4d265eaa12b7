#include "integrate/planar/step_clip.hpp"

#include <algorithm>
#include <stdexcept>

namespace rtog {
namespace {

constexpr std::int64_t kOne = std::int64_t{1} << kStepRunFracBits;

/// Cell k of a run, as forEachRunCell walks it (scaled by multiplying: a left shift of a negative
/// cell is undefined before C++20).
void runCell(const StepRun& r, std::int64_t k, std::int32_t& x, std::int32_t& y) {
  x = static_cast<std::int32_t>((r.x * kOne + k * r.dx) >> kStepRunFracBits);
  y = static_cast<std::int32_t>((r.y * kOne + k * r.dy) >> kStepRunFracBits);
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
        for (std::uint32_t k = 0; k < r.count; ++k) {
          std::int32_t x, y;
          runCell(r, k, x, y);
          const bool in = owns(x, y);
          kept.push_back(in);
          if (in) out.push_back(StepRun{x, y, 0, 0, 1, r.kind, false, 0, 0});
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
