// rtog::CRTreeBackedGridMap2D: an mrpt::maps::COccupancyGridMap2D whose cells are a view of an
// R-tree occupancy map. Observations go into the R-tree map (the source of truth, and what is
// serialized); after each insertion the 2D cells the observation touched are refreshed from it.
// Every code path that needs a COccupancyGridMap2D (mapByClass<COccupancyGridMap2D>(): ICP
// against the grid, the optimal-proposal RBPF, pf-localization's uniform init over free space,
// .gridmap outputs) therefore works, with MRPT's own grid algorithms on the derived 2D view.
#pragma once

#include <mrpt/maps/COccupancyGridMap2D.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog {

class CRTreeBackedGridMap2D : public mrpt::maps::COccupancyGridMap2D {
  DEFINE_SERIALIZABLE(CRTreeBackedGridMap2D, rtog)

 public:
  explicit CRTreeBackedGridMap2D(double resolution = 0.10);

  /// The source of truth. After changing it directly, call refreshGrid().
  CRTreeOccupancyGridMap& rtreeMap() { return rtree_; }
  const CRTreeOccupancyGridMap& rtreeMap() const { return rtree_; }

  /// Height band [m] of R-tree cells that decide a 2D cell: a 2D cell takes the highest
  /// log-odds among the observed cells of its column within the band; unknown if none.
  float gridView_minZ{-1000.0f};  ///< (Default: -1000)
  float gridView_maxZ{1000.0f};   ///< (Default: 1000)

  /// Rebuilds every 2D cell from the R-tree map (e.g. after deserialization or direct edits).
  void refreshGrid();

  /// Writes the COccupancyGridMap2D outputs (<prefix>.png, <prefix>_limits.txt) and the R-tree
  /// map (<prefix>.rtog).
  void saveMetricMapRepresentationToFile(const std::string& filNamePrefix) const override;
  std::string asString() const override;

  MAP_DEFINITION_START(CRTreeBackedGridMap2D)
  /// Cell edge length [m] of both the R-tree map and its 2D view. (Default: 0.10)
  double resolution{0.10};
  /// The grid's initial extent, as COccupancyGridMap2D's. (Default: -10, 10, -10, 10)
  float min_x{-10.0f}, max_x{10.0f}, min_y{-10.0f}, max_y{10.0f};
  float gridView_minZ{-1000.0f};  ///< see CRTreeBackedGridMap2D::gridView_minZ (Default: -1000)
  float gridView_maxZ{1000.0f};   ///< (Default: 1000)
  rtog::CRTreeOccupancyGridMap::TInsertionOptions insertionOpts;
  /// The stock grid's likelihood options: the likelihood is computed on the 2D view.
  mrpt::maps::COccupancyGridMap2D::TLikelihoodOptions likelihoodOpts;
  std::string loadError;  ///< see CRTreeOccupancyGridMap::TMapDefinition::loadError
  MAP_DEFINITION_END(CRTreeBackedGridMap2D)

 protected:
  void internal_clear() override;
  bool internal_insertObservation(const mrpt::obs::CObservation& obs,
                                  const std::optional<const mrpt::poses::CPose3D>& robotPose) override;
  /// The stock grid's likelihood, except for a robot or sensor pose with a non-finite component
  /// (angles included): -1e30, the impossible score, as CRTreeOccupancyGridMap gives it.
  double internal_computeObservationLikelihood(const mrpt::obs::CObservation& obs,
                                               const mrpt::poses::CPose3D& takenFrom) const override;

 private:
  /// Refreshes the 2D cells within the metric rectangle (grows the grid to contain it).
  void refreshRegion(double x0, double y0, double x1, double y1);
  /// mrpt_grid preset, 2D scans: grows the grid as COccupancyGridMap2D does and writes the int8
  /// values the R-tree map's cells took, step by step (the R-tree map decided them).
  bool insertGridScan(const mrpt::obs::CObservation2DRangeScan& scan, const mrpt::poses::CPose3D& pose);
  /// Drops the kept likelihood-field values that the cells of the marked blocks (block x block
  /// cells, bx blocks a row) can have changed.
  void forgetKeptFieldNear(const std::vector<std::uint8_t>& touched, std::size_t bx, int block);
  /// Size the grid and the R-tree map's grid geometry alike (COccupancyGridMap2D::setSize).
  void setExtent(float x_min, float x_max, float y_min, float y_max);

  CRTreeOccupancyGridMap rtree_;
};

}  // namespace rtog
