// rtog::CRTreeOccupancyGridMap: a COccupancyGridMap2D (.gridmap file, bitmap, object) as the
// initial map, its cells becoming R-tree cells with the grid's values.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/serialization/CArchive.h>

#include "CRTreeOccupancyGridMap_grid2d.hpp"

namespace rtog {

namespace {

/// A float probability whose float log-odds (as LogOddsModel computes it) is v, or else lies
/// just beyond v in direction dir (-1: below, +1: above), so that v is within the bound.
float boundProbability(float v, int dir) {
  const float p0 = static_cast<float>(probability(v));
  const auto l = [](float p) { return static_cast<float>(logit(p)); };
  float p = p0;
  for (int i = 0; i < 4; ++i, p = std::nextafter(p, 0.0f))  // exact if a nearby float gives it
    if (l(p) == v) return p;
  p = p0;
  for (int i = 0; i < 4; ++i, p = std::nextafter(p, 1.0f))
    if (l(p) == v) return p;
  p = p0;
  while (dir < 0 ? l(p) > v : l(p) < v) p = std::nextafter(p, dir < 0 ? 0.0f : 1.0f);
  return p;
}

}  // namespace

void CRTreeOccupancyGridMap::loadFromGrid(const mrpt::maps::COccupancyGridMap2D& grid) {
  loadGridLayer(grid, 1.0);
  prior_.reset();
}

void CRTreeOccupancyGridMap::loadPrior(const mrpt::maps::COccupancyGridMap2D& grid, double confidence) {
  if (!(confidence > 0.5 && confidence <= 1.0))
    throw std::invalid_argument("rtog::CRTreeOccupancyGridMap::loadPrior: the confidence must lie in (0.5, 1], got " +
                                std::to_string(confidence));
  loadGridLayer(grid, confidence);
  prior_ = std::make_shared<const Prior>(Prior{map_, frame_});
}

void CRTreeOccupancyGridMap::loadGridLayer(const mrpt::maps::COccupancyGridMap2D& grid, double confidence) {
  const double res = grid.getResolution();
  const auto& cells = grid.getRawMap();
  const std::size_t sx = grid.getSizeX(), sy = grid.getSizeY();
  // A cell's value: the grid's own (-l/16, exact) or, trusted less, its P(occupied) drawn
  // towards 0.5 (monotone in l, so the extremes below are the extremes of the values).
  const auto valueOf = [confidence](int l) {
    const float v = -static_cast<float>(l) / 16.0f;
    if (confidence == 1.0) return v;
    return static_cast<float>(logit(0.5 + (2.0 * confidence - 1.0) * (probability(v) - 0.5)));
  };
  int lmin = 0, lmax = 0;
  for (const auto c : cells) lmin = std::min<int>(lmin, std::max<int>(c, -127)), lmax = std::max<int>(lmax, c);
  // Widen the clamping only as far as the grid's most certain cells need, so that they keep
  // their values (MRPT's grid saturates at +-127 only).
  TInsertionOptions io = insertionOptions;
  io.validate();  // before toMapParams(), which must not see a NaN (see validated())
  const LogOddsModel before(io.toMapParams(res).log_odds);
  const float vmin = valueOf(lmax), vmax = valueOf(lmin);
  if (vmin < before.clampMin()) io.clampingMin = boundProbability(vmin, -1);
  if (vmax > before.clampMax()) io.clampingMax = boundProbability(vmax, +1);
  io.validate();
  MapParams p = io.toMapParams(res);
  p.rtree = map_.params().rtree;
  const LogOddsModel model(p.log_odds);
  const auto mergeable = [&](float v) {
    return p.merge == MergePolicy::Equal || (p.merge == MergePolicy::Clamped && model.isClamped(v));
  };
  const Lattice lat(res);
  const double zc = std::min<double>(std::max<double>(0.0, gridViewOptions.gridView_minZ), gridViewOptions.gridView_maxZ);
  Key k0;
  if (!lat.tryKey(Eigen::Vector3d(grid.idx2x(0), grid.idx2y(0), zc), k0))
    throw std::out_of_range("rtog::CRTreeOccupancyGridMap::loadFromGrid: grid outside the key range");
  if (k0.x + static_cast<std::int64_t>(sx) - 1 > kKeyMax || k0.y + static_cast<std::int64_t>(sy) - 1 > kKeyMax)
    throw std::out_of_range("rtog::CRTreeOccupancyGridMap::loadFromGrid: grid outside the key range");
  std::vector<Box> boxes;
  std::vector<float> values;
  for (std::size_t cy = 0; cy < sy; ++cy)
    for (std::size_t cx = 0; cx < sx;) {
      // An int8 cell may hold -128, which MRPT reads as -127 (its bound): the mrpt_grid preset's too.
      const int l = std::max<int>(cells[cy * sx + cx], -127);
      if (l == 0) {  // never observed: unknown, as in MRPT
        ++cx;
        continue;
      }
      const float v = valueOf(l);
      const auto kx = static_cast<std::int32_t>(k0.x + static_cast<std::int64_t>(cx));
      const auto ky = static_cast<std::int32_t>(k0.y + static_cast<std::int64_t>(cy));
      // Runs of equal mergeable values along x, within one brick.
      std::size_t end = cx + 1;
      if (mergeable(v))
        while (end < sx && std::max<int>(cells[cy * sx + end], -127) == l && ((kx + std::int32_t(end - cx)) >> kBrickBits) == (kx >> kBrickBits))
          ++end;
      boxes.push_back(Box{Key{kx, ky, k0.z}, Key{kx + std::int32_t(end - cx) - 1, ky, k0.z}});
      values.push_back(v);
      cx = end;
    }
  OccupancyMap imported(p);
  imported.assignCells(boxes.data(), values.data(), boxes.size());
  map_ = std::move(imported);
  insertionOptions = io;
  // Scans inserted later continue on the grid's geometry and plane, as in the grid itself.
  frame_.x_min = grid.getXMin(), frame_.x_max = grid.getXMax();
  frame_.y_min = grid.getYMin(), frame_.y_max = grid.getYMax();
  frame_.resolution = grid.getResolution();
  frame_.size_x = grid.getSizeX(), frame_.size_y = grid.getSizeY();
  frame_.has_layer = true;
  frame_.layer = k0.z;
  lastInsertStats = totalInsertStats = InsertStats{};
  invalidRangesSkipped = 0;
  notifyMapChanged();
}

bool CRTreeOccupancyGridMap::loadFromBitmapFile(const std::string& file, float resolution,
                                                const mrpt::math::TPoint2D& origin) {
  mrpt::maps::COccupancyGridMap2D g;
  if (!g.loadFromBitmapFile(file, resolution, origin)) return false;
  loadFromGrid(g);
  return true;
}

bool readGridmapFile(const std::string& file, mrpt::maps::COccupancyGridMap2D& g) {
  try {
    mrpt::io::CFileGZInputStream f;  // zlib reads plain files too
    if (!f.open(file)) return false;
    auto ar = mrpt::serialization::archiveFrom(f);
    ar >> g;
  } catch (const std::exception&) {
    return false;  // not a serialized COccupancyGridMap2D
  }
  return true;
}

bool CRTreeOccupancyGridMap::loadFromGridmapFile(const std::string& file) {
  mrpt::maps::COccupancyGridMap2D g;
  if (!readGridmapFile(file, g)) return false;
  loadFromGrid(g);
  return true;
}

}  // namespace rtog
