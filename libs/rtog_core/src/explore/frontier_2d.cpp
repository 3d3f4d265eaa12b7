// 2D frontiers of a height band (rtog/core/explore.hpp): the band's columns as its 2D view shows
// them (forEachBandRun), kept per row as intervals of known columns of one class; a free
// interval's frontier is its ends next to unknown columns and the parts above or below which the
// next row knows nothing, found by interval arithmetic, not column by column.
#include <algorithm>
#include <cmath>

#include "explore/frontier.hpp"
#include "rtog/core/band.hpp"

namespace rtog::explore_detail {
namespace {

struct Segment {
  std::int32_t x0, x1;
  bool free;
};

/// The parts of [a, b] that no segment of `row` covers, appended to out.
void unknownParts(const std::vector<Segment>* row, std::int32_t a, std::int32_t b,
                  std::vector<std::pair<std::int32_t, std::int32_t>>& out) {
  std::int32_t at = a;
  if (row) {
    auto it = std::lower_bound(row->begin(), row->end(), a, [](const Segment& s, std::int32_t x) { return s.x1 < x; });
    for (; it != row->end() && it->x0 <= b; ++it) {
      if (it->x0 > at) out.push_back({at, it->x0 - 1});
      at = std::max(at, it->x1 + 1);
    }
  }
  if (at <= b) out.push_back({at, b});
}

}  // namespace

void frontier2D(const OccupancyMap& map, const Box& region, std::vector<FrontierPiece>& pieces, std::vector<Box>& boxes) {
  const float occ = map.logOddsModel().occupiedThreshold();
  if (region.isEmpty()) return;
  // A row of segments per y of the band's rectangle (rows without known columns stay empty).
  std::vector<std::vector<Segment>> rows(static_cast<std::size_t>(region.extent(1)));
  forEachBandRun(map, region, [&](std::int32_t y, std::int32_t x0, std::int32_t x1, const float* best) {
    std::vector<Segment>& row = rows[static_cast<std::size_t>(y - region.min.y)];
    for (std::int32_t x = x0; x <= x1; ++x) {
      const float v = best[x - x0];
      if (std::isnan(v)) continue;
      const bool free = v < occ;
      if (!row.empty() && row.back().x1 == x - 1 && row.back().free == free)
        row.back().x1 = x;
      else
        row.push_back(Segment{x, x, free});
    }
  });
  for (auto& row : rows) std::sort(row.begin(), row.end(), [](const Segment& a, const Segment& b) { return a.x0 < b.x0; });
  const auto rowAt = [&](std::int64_t y) -> const std::vector<Segment>* {
    if (y < region.min.y || y > region.max.y) return nullptr;
    return &rows[static_cast<std::size_t>(y - region.min.y)];
  };
  const auto box = [&](std::int32_t y, std::int32_t x0, std::int32_t x1) {
    return Box{Key{x0, y, region.min.z}, Key{x1, y, region.max.z}};
  };
  std::vector<std::pair<std::int32_t, std::int32_t>> parts;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const std::vector<Segment>& row = rows[r];
    const auto y = static_cast<std::int32_t>(region.min.y + static_cast<std::int64_t>(r));
    for (std::size_t i = 0; i < row.size(); ++i) {
      const Segment& s = row[i];
      if (!s.free) continue;
      parts.clear();
      // The ends: a neighbour column no segment holds is unknown (one beyond the keys is not).
      if (s.x0 > kKeyMin && !(i > 0 && row[i - 1].x1 == s.x0 - 1)) {
        parts.push_back({s.x0, s.x0});
        pieces.push_back(FrontierPiece{box(y, s.x0, s.x0), Eigen::Vector3d(-1, 0, 0)});
      }
      if (s.x1 < kKeyMax && !(i + 1 < row.size() && row[i + 1].x0 == s.x1 + 1)) {
        parts.push_back({s.x1, s.x1});
        pieces.push_back(FrontierPiece{box(y, s.x1, s.x1), Eigen::Vector3d(1, 0, 0)});
      }
      for (const int dy : {-1, 1}) {
        if (std::int64_t{y} + dy < kKeyMin || std::int64_t{y} + dy > kKeyMax) continue;
        const std::size_t first = parts.size();
        unknownParts(rowAt(std::int64_t{y} + dy), s.x0, s.x1, parts);
        for (std::size_t p = first; p < parts.size(); ++p)
          pieces.push_back(FrontierPiece{box(y, parts[p].first, parts[p].second),
                                         Eigen::Vector3d(0, dy, 0) * double(parts[p].second - parts[p].first + 1)});
      }
      // Their union, as disjoint runs.
      std::sort(parts.begin(), parts.end());
      for (std::size_t p = 0; p < parts.size();) {
        std::int32_t lo = parts[p].first, hi = parts[p].second;
        for (++p; p < parts.size() && parts[p].first <= hi + 1; ++p) hi = std::max(hi, parts[p].second);
        boxes.push_back(box(y, lo, hi));
      }
    }
  }
}

}  // namespace rtog::explore_detail
