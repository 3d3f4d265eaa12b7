#include "grid_tiles.hpp"

#include <algorithm>
#include <cmath>

#include "mrpt_grid.hpp"

namespace rtog {

GridTiles::GridTiles(const TGridFrame2D& frame) : occupied_below_(occupiedBelow()) { setFrame(frame); }

void GridTiles::setFrame(const TGridFrame2D& f) {
  const std::int32_t ox = mrpt_grid::keyOffsetX(f), oy = mrpt_grid::keyOffsetY(f);
  const std::int32_t tx0 = tileCoord(ox), ty0 = tileCoord(oy);
  const std::int32_t tx1 = tileCoord(ox + static_cast<std::int32_t>(std::max(f.size_x, 1u)) - 1);
  const std::int32_t ty1 = tileCoord(oy + static_cast<std::int32_t>(std::max(f.size_y, 1u)) - 1);
  std::vector<Tile> tiles(static_cast<std::size_t>(tx1 - tx0 + 1) * static_cast<std::size_t>(ty1 - ty0 + 1));
  if (tiles_)
    for (std::int32_t ty = std::max(ty0, ty0_); ty <= std::min(ty1, ty0_ + nty_ - 1); ++ty)
      for (std::int32_t tx = std::max(tx0, tx0_); tx <= std::min(tx1, tx0_ + ntx_ - 1); ++tx)
        tiles[static_cast<std::size_t>(ty - ty0) * static_cast<std::size_t>(tx1 - tx0 + 1) + (tx - tx0)] =
            (*tiles_)[static_cast<std::size_t>(ty - ty0_) * static_cast<std::size_t>(ntx_) + (tx - tx0_)];
  // Cells of a tile beyond the old grid were unknown and are still; its kept terms were clipped
  // at the old border, where unknown cells lay anyway: they stand.
  tiles_.reset(std::move(tiles));
  changed_.clear();
  frame_ = f;
  ox_ = ox, oy_ = oy, tx0_ = tx0, ty0_ = ty0, ntx_ = tx1 - tx0 + 1, nty_ = ty1 - ty0 + 1;
  ux0_ = ox - tx0 * kSide, uy0_ = oy - ty0 * kSide;
}

void GridTiles::setCell(std::int32_t kx, std::int32_t ky, std::int8_t v) {
  setOccupied(tileOf(kx, ky), within(kx, ky), static_cast<float>(v) < occupied_below_);
}

void GridTiles::setOccupied(std::size_t t, std::size_t i, bool occupied) {
  const std::uint32_t bit = std::uint32_t{1} << (i & kMask);
  const Occupied* seen = (*tiles_)[t].occupied.get();
  if (((seen && (seen->rows[i >> kBits] & bit)) != 0) == occupied) return;
  std::uint32_t& row = tiles_.write()[t].occupied.write().rows[i >> kBits];
  row = occupied ? row | bit : row & ~bit;
  if (changed_.empty() || changed_.back() != t) changed_.push_back(static_cast<std::uint32_t>(t));
}

void GridTiles::dropStaleTerms(int window) {
  if (changed_.empty()) return;
  // A cell's term reads the cells within `window` of it: the terms of the tiles within that many
  // cells of a changed tile are dropped.
  const std::int32_t reach = (std::max(window, 0) + kSide - 1) / kSide;
  std::sort(changed_.begin(), changed_.end());
  changed_.erase(std::unique(changed_.begin(), changed_.end()), changed_.end());
  std::vector<Tile>& tiles = tiles_.write();
  for (const std::uint32_t t : changed_) {
    const std::int32_t tx = static_cast<std::int32_t>(t % static_cast<std::uint32_t>(ntx_));
    const std::int32_t ty = static_cast<std::int32_t>(t / static_cast<std::uint32_t>(ntx_));
    for (std::int32_t y = std::max(0, ty - reach); y <= std::min(nty_ - 1, ty + reach); ++y)
      for (std::int32_t x = std::max(0, tx - reach); x <= std::min(ntx_ - 1, tx + reach); ++x)
        tiles[static_cast<std::size_t>(y) * static_cast<std::size_t>(ntx_) + static_cast<std::size_t>(x)].terms.drop();
  }
  changed_.clear();
}

void GridTiles::loadDense(const std::int8_t* dense) {
  const std::int32_t sx = static_cast<std::int32_t>(frame_.size_x), sy = static_cast<std::int32_t>(frame_.size_y);
  for (std::int32_t cy = 0; cy < sy; ++cy)
    for (std::int32_t cx = 0; cx < sx; ++cx)
      if (dense[static_cast<std::size_t>(cy) * static_cast<std::size_t>(sx) + static_cast<std::size_t>(cx)] < occupied_below_)
        setOccupied(tileAt(cx, cy), inTile(cx, cy), true);
  changed_.clear();
  for (Tile& t : tiles_.write()) t.terms.drop();
}

void GridTiles::useOptions(const FieldConstants& f, bool logs) {
  if (field_ && (f.capUnits != field_->capUnits || f.window != field_->window))
    for (Tile& t : tiles_.write()) t.terms.drop();  // the kept distances are other distances
  field_ = f;
  logs_ = logs;
  // Distances are capped: one term per distance up to the cap, the same numbers termOfBest gives.
  value_of_best_.clear();
  if (f.capUnits < Terms::kNone) {
    value_of_best_.resize(f.capUnits + 1);
    for (unsigned b = 0; b <= f.capUnits; ++b) {
      const double t = f.termOfBest(b);
      value_of_best_[b] = logs ? std::log(t) : t;
    }
  }
}

double GridTiles::scanLogLikelihood(const FieldGrid& g, const mrpt::obs::CObservation2DRangeScan& scan,
                                    const mrpt::poses::CPose3D& pose) {
  const FieldConstants f(*g.likelihood, g.resolution);
  const bool logs = !g.likelihood->LF_alternateAverageMethod;
  if (!field_ || !(*field_ == f) || logs != logs_) useOptions(f, logs);
  const bool keep = g.likelihood->enableLikelihoodCache && !value_of_best_.empty();
  const int sx = static_cast<int>(frame_.size_x), sy = static_cast<int>(frame_.size_y);
  // The arrays read for every point, held here (the tiles' array is refetched after a write,
  // which may clone it).
  const Tile* tiles = tiles_->data();
  const double* value_of = value_of_best_.data();
  const auto row = [&](int y, int x0, int x1, auto&& visit) {
    for (int x = x0; x <= x1;) {
      const Tile& t = tiles[tileAt(x, y)];
      const int first = (x + ux0_) & kMask;
      const int n = std::min(x1 - x + 1, kSide - first);
      if (t.occupied) {  // else no cell occupied
        std::uint32_t bits = t.occupied->rows[static_cast<std::size_t>((y + uy0_) & kMask)] >> first;
        if (n < kSide) bits &= (std::uint32_t{1} << n) - 1;
        for (; bits; bits &= bits - 1) visit(x + __builtin_ctz(bits));
      }
      x += n;
    }
  };
  return fieldScanLogLikelihood(g, f, scan, pose, [&](int cx, int cy, bool lg) {
    if (!keep) {
      const double t = f.termOfBest(f.bestAt(cx, cy, sx, sy, row));
      return lg ? std::log(t) : t;
    }
    const std::size_t t = tileAt(cx, cy);
    const std::size_t i = inTile(cx, cy);
    if (const Terms* kept = tiles[t].terms.get()) {
      const std::uint16_t b = kept->best[i];
      if (b != Terms::kNone) return value_of[b];
    }
    const unsigned best = f.bestAt(cx, cy, sx, sy, row);
    Tile* own = tiles_.write().data();  // this copy's own array and page
    tiles = own;
    own[t].terms.write().best[i] = static_cast<std::uint16_t>(best);
    return value_of[best];
  });
}

}  // namespace rtog
