#include "rtog/core/band.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace rtog {

Box bandRegion(const OccupancyMap& m, const Box& columns, double zmin, double zmax) {
  const Box kb = m.keyBounds();
  if (kb.isEmpty() || columns.isEmpty() || !(zmin <= zmax)) return Box::empty();
  const double res = m.resolution();
  const double z0 = std::max<double>(kb.min.z, std::floor(zmin / res)), z1 = std::min<double>(kb.max.z, std::floor(zmax / res));
  if (!(z0 <= z1)) return Box::empty();
  return Box{Key{columns.min.x, columns.min.y, static_cast<std::int32_t>(z0)},
             Key{columns.max.x, columns.max.y, static_cast<std::int32_t>(z1)}};
}

void forEachBandRun(const OccupancyMap& m, const Box& region,
                    const std::function<void(std::int32_t y, std::int32_t x0, std::int32_t x1, const float* best)>& f) {
  if (region.isEmpty()) return;
  // Whole rows where a row fits a tile (one query per band of rows), else pieces of one row.
  const std::int64_t nx = region.extent(0), ny = region.extent(1);
  const std::int64_t tw = std::min(nx, kBandTileColumns);
  const std::int64_t th = std::max<std::int64_t>(1, std::min(ny, kBandTileColumns / tw));
  constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> best;
  std::vector<std::pair<std::int64_t, std::int64_t>> span;  // per tile row: the columns touched
  for (std::int64_t y0 = region.min.y; y0 <= region.max.y; y0 += th)
    for (std::int64_t x0 = region.min.x; x0 <= region.max.x; x0 += tw) {
      const Box tile{Key{static_cast<std::int32_t>(x0), static_cast<std::int32_t>(y0), region.min.z},
                     Key{static_cast<std::int32_t>(std::min<std::int64_t>(x0 + tw - 1, region.max.x)),
                         static_cast<std::int32_t>(std::min<std::int64_t>(y0 + th - 1, region.max.y)), region.max.z}};
      const std::int64_t w = tile.extent(0), h = tile.extent(1);
      bool any = false;  // filled on the first leaf: a sparse map's wide view is mostly empty tiles
      m.forEachLeafIn(tile, [&](const Box& b, float v) {
        if (!any) {
          best.assign(static_cast<std::size_t>(w * h), kUnknown);
          span.assign(static_cast<std::size_t>(h), {w, -1});
          any = true;
        }
        const Box c = b.intersection(tile);
        for (std::int64_t y = c.min.y - tile.min.y; y <= c.max.y - tile.min.y; ++y) {
          auto& [lo, hi] = span[static_cast<std::size_t>(y)];
          lo = std::min<std::int64_t>(lo, c.min.x - tile.min.x), hi = std::max<std::int64_t>(hi, c.max.x - tile.min.x);
          float* row = best.data() + y * w;
          for (std::int64_t x = c.min.x - tile.min.x; x <= c.max.x - tile.min.x; ++x)
            if (!(row[x] >= v)) row[x] = v;  // NaN (unknown) or lower
        }
      });
      if (!any) continue;
      for (std::int64_t y = 0; y < h; ++y) {
        const auto [lo, hi] = span[static_cast<std::size_t>(y)];
        if (lo <= hi)
          f(static_cast<std::int32_t>(tile.min.y + y), static_cast<std::int32_t>(tile.min.x + lo),
            static_cast<std::int32_t>(tile.min.x + hi), best.data() + y * w + lo);
      }
    }
}

}  // namespace rtog
