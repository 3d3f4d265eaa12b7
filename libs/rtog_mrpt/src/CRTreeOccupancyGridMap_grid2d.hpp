// Private to librtog_mrpt: the 2D view of CRTreeOccupancyGridMap and the likelihood-method names.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <mutex>
#include <string>

#include <mrpt/maps/COccupancyGridMap2D.h>

#include "likelihood_field_2d.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog {

/// The accepted likelihoodMethod values, for error messages.
extern const char* const kLikelihoodMethodNames;
/// COccupancyGridMap2D's name of m; nullptr if m is none of the seven.
const char* likelihoodMethodName(CRTreeOccupancyGridMap::TLikelihoodMethod m);
/// A name or COccupancyGridMap2D's number ("0".."6"); false if neither.
bool likelihoodMethodFromString(const std::string& s, CRTreeOccupancyGridMap::TLikelihoodMethod& out);
/// The keys of COccupancyGridMap2D's methods (MI_*, consensus_*, OWA_weights, ...).
void loadGridLikelihoodKeys(CRTreeOccupancyGridMap::TLikelihoodOptions& o, const mrpt::config::CConfigFileBase& s,
                            const std::string& sec);
void saveGridLikelihoodKeys(const CRTreeOccupancyGridMap::TLikelihoodOptions& o, mrpt::config::CConfigFileBase& c,
                            const std::string& sec);

/// MRPT's int8 cell (log-odds of P(free), x16) of a core log-odds v (of P(occupied)): exactly
/// -16 v when that is an MRPT value, else MRPT's own p2l of P(free).
int8_t toMrptCell(float v);

/// Copies the options to COccupancyGridMap2D's struct; true if the likelihood field's changed.
bool toGridLikelihoodOptions(const CRTreeOccupancyGridMap::TLikelihoodOptions& o,
                             mrpt::maps::COccupancyGridMap2D::TLikelihoodOptions& g);

/// Reads a .gridmap / .gridmap.gz (a CArchive of a COccupancyGridMap2D, gzip or not) into `g`;
/// false if the file cannot be read as one.
bool readGridmapFile(const std::string& file, mrpt::maps::COccupancyGridMap2D& g);

struct CRTreeOccupancyGridMap::Prior {
  OccupancyMap map;
  TGridFrame2D frame;
};

struct CRTreeOccupancyGridMap::GridView {
  /// A COccupancyGridMap2D whose cells and caches the view may set directly.
  class Grid : public mrpt::maps::COccupancyGridMap2D {
   public:
    /// Two cells: the view sets its own geometry at once. (MRPT's default grid, 800 x 800 cells,
    /// was zero-filled and thrown away by every new view.)
    Grid() : COccupancyGridMap2D(0.0f, 1.0f, 0.0f, 0.5f, 0.5f) {}
    std::vector<cellType>& cells() { return m_map; }
    void setNonEmpty() { m_is_empty = false; }
    void invalidateLikelihoodCache() { m_likelihoodCacheOutDated = true; }
    /// The geometry as is (setSize() would round it again), all cells unknown.
    void setGeometry(const TGridFrame2D& f) {
      m_resolution = f.resolution;
      m_xMin = f.x_min, m_xMax = f.x_max, m_yMin = f.y_min, m_yMax = f.y_max;
      m_size_x = f.size_x, m_size_y = f.size_y;
      m_map.assign(std::size_t{f.size_x} * f.size_y, 0);
      m_likelihoodCacheOutDated = true;
    }
  };
  /// A metric rectangle [m]: x0, y0, x1, y1.
  using Rect = std::array<double, 4>;
  /// Built from the map's cells within [minZ, maxZ], covering the known cells and `extra`; on
  /// `frame`'s geometry (the grid the mrpt_grid preset follows) if given and it holds them.
  GridView(const OccupancyMap& m, float minZ, float maxZ, const std::optional<Rect>& extra,
           const TGridFrame2D* frame = nullptr);
  bool covers(const Rect& r) const {
    return r[0] >= grid.getXMin() && r[1] >= grid.getYMin() && r[2] <= grid.getXMax() && r[3] <= grid.getYMax();
  }
  /// Writes the band's cells of the known columns `kb`, lattice column gx0/gy0 being grid cell 0.
  void fillCells(const OccupancyMap& m, const Box& kb, double gx0, double gy0);
  /// Copies the likelihood (and the insertion options MRPT's methods read) to the grid, dropping
  /// MRPT's likelihood-field cache when its parameters changed. The caller holds `mutex`.
  void setOptions(const TLikelihoodOptions& lo, const TInsertionOptions& io);

  /// Serializes the calls into `grid`: MRPT's likelihood methods fill mutable caches.
  std::mutex mutex;
  Grid grid;
  /// lmLikelihoodField_Thrun on `grid`, its terms kept (the stock grid's value, faster).
  LikelihoodField2D field;
  float minZ, maxZ;
  std::optional<Rect> extra;
};

}  // namespace rtog
