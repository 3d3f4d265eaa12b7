// Decoding a CObservationRotatingScan's range image into sensor-frame points.
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace mrpt::obs {
class CObservationRotatingScan;
}

namespace rtog::detail {

/// Sensor-frame end points of the valid ranges of `rot` (every `decimation`-th column), appended
/// to `pts`; invalid ranges are counted in `invalid`.
///
/// A range image made by MRPT's CObservationRotatingScan::fromVelodyne (lidarModel VLP-16,
/// HDL-32E, ...) has one row per laser ID (not by elevation) and fills only columnCount/rowCount
/// columns, one per firing sequence, its azimuth growing clockwise as the Velodyne's: it is
/// decoded with the laser's calibration (MRPT's default table for the model) and placed as
/// CObservationVelodyneScan::generatePointCloud places the raw scan. Any other range image is
/// read as the class documents it (columns evenly over azimuthSpan, counter-clockwise); a single
/// row is planar.
///
/// If `minElevation_deg` and `maxElevation_deg` are both finite they override the ring
/// elevations: row r at min + r*(max-min)/(rows-1). Otherwise a multi-row image whose lidar has
/// no known calibration throws std::invalid_argument naming the model.
void decodeRotatingScan(const mrpt::obs::CObservationRotatingScan& rot, std::size_t decimation,
                        float minElevation_deg, float maxElevation_deg, std::vector<Eigen::Vector3f>& pts,
                        std::size_t& invalid);

}  // namespace rtog::detail
