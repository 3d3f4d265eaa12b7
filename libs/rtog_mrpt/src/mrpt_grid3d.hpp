// The mrpt_grid preset in 3D: COccupancyGridMap3D's update (MRPT 2.5: COccupancyGridMap3D_insert.cpp),
// reproduced so that an R-tree map holds exactly the voxels that grid holds. The grid turns each
// observation into a point cloud and inserts it ray by ray: every `decimation`-th point is a ray
// from the sensor's cell, a free step in each cell of its fixed-point raster (the sensor's cell
// first, the end's cell not), then an occupied step in the end's cell. Cells are the grid's, of
// its fixed extent (CDynamicGrid3D): a ray stops where it leaves the grid, and one whose sensor
// lies outside is dropped. The steps are the 2D grid's (mrpt_grid.hpp), and a cell takes one step
// per ray that crosses it, in ray order.
// tests/mrpt/test_mrpt_grid3d_fidelity.cpp holds the result against the grid itself.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/maps/CPointsMap.h>
#include <mrpt/math/TPoint3D.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include "rtog/core/occupancy_map.hpp"
#include "rtog/core/range_noise.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog::mrpt_grid3d {

/// COccupancyGridMap3D(corner_min, corner_max, resolution)'s geometry, as CDynamicGrid3D::setSize
/// makes it (doubles from the section's floats). Throws std::invalid_argument for an extent that
/// is not finite and ordered or not inside the lattice's key range.
TGridFrame3D makeFrame(float x_min, float x_max, float y_min, float y_max, float z_min, float z_max, float resolution,
                       double latticeResolution);
/// Throws std::runtime_error unless `f` is a geometry makeFrame() could have made for a map of
/// `latticeResolution` (a loaded map's): finite, positive sizes within the key range.
void checkFrame(const TGridFrame3D& f, double latticeResolution);
/// Lattice key of the grid's cell 0 along each axis (round(min / resolution)).
Key keyOffset(const TGridFrame3D& f);

/// The points the grid makes of `obs` taken at `robotPose` and its sensor's position, in the map
/// frame: a 2D range scan as CSimplePointsMap::loadFromRangeScan (valid ranges only), a depth
/// image as CObservation3DRangeScan::unprojectInto with decimation_3d_range then moved by the
/// sensor pose, as COccupancyGridMap3D does. False for other observation types and for a depth
/// observation without a range image (the grid inserts nothing of it; the map takes its points).
bool gridPoints(const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose, unsigned decimation3d,
                mrpt::maps::CPointsMap& pts, mrpt::math::TPoint3D& sensor);

/// COccupancyGridMap3D's int8 steps: free max(1, p2l(maxFreenessUpdateCertainty, or
/// maxOccupancyUpdateCertainty if 0)), occupied 3 max(1, p2l(maxOccupancyUpdateCertainty)); a
/// cell within a step of +-127 takes the bound (the 2D grid's steps; no no-return beams).
struct Steps3D {
  int free = 1, occupied = 3;
};
Steps3D stepsOf(const CRTreeOccupancyGridMap::TInsertionOptions& io);

/// One pose's rays of a scan: from `sensor` to endOf(0 .. n), in order, with the pose's weight.
struct RaySet {
  double weight = 1.0;
  mrpt::math::TPoint3D sensor;
  std::size_t n = 0;
  std::function<mrpt::math::TPoint3D(std::size_t)> endOf;
};

/// The rays of `sets` step the grid's cells as COccupancyGridMap3D::insertRay steps them (cells
/// outside its extent are not stepped; a ray whose sensor lies outside counts in
/// skipped_out_of_range, a non-finite end in skipped_non_finite, one ending in the sensor's cell
/// in skipped_zero_length, the others in rays_hit: the first set's); the cells stepped then take
/// their values in `map` (OccupancyMap::assignCells). With `noise` (range noise), each ray's band
/// is graded on the grid's raster (mrpt_grid::gradeBeam); several sets (the sigma poses of an
/// uncertain pose) are mixed (mrpt_grid::PoseMixture). One set without noise is the grid's insertion.
InsertStats insertRays(OccupancyMap& map, const TGridFrame3D& f, const std::vector<RaySet>& sets, const Steps3D& steps,
                       const RangeNoiseRule* noise = nullptr);

/// The keys of a 3D section that COccupancyGridMap3D reads otherwise than COccupancyGridMap2D:
/// likelihoodMethod by its numbers (0: the likelihood field, 1: ray tracing), decimation_3d_range
/// not at all (8; told once if given). Throws std::invalid_argument for another number.
void readSectionKeys(const mrpt::config::CConfigFileBase& source, const std::string& prefix,
                     CRTreeOccupancyGridMap::TInsertionOptions& io, CRTreeOccupancyGridMap::TLikelihoodOptions& lo);

}  // namespace rtog::mrpt_grid3d
