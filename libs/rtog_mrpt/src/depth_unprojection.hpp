// A depth (or range) image's points at a decimation above 1, as MRPT's unprojectInto gives them,
// without MRPT's projection table.
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace mrpt::obs {
class CObservation3DRangeScan;
}

namespace rtog::detail {

/// The sensor-frame points (x forward) of `depth`'s range image read one block of
/// `decimation` x `decimation` pixels at a time, appended to `pts`: in each block the least
/// positive range, along the ray of the block's centre pixel (MRPT's decimated unprojection,
/// float for float: its camera model undistorted by cv::undistortPoints, unit rays if the
/// image holds ranges instead of depths). A block without a positive range counts in `invalid`.
///
/// MRPT's CObservation3DRangeScan::unprojectInto reads the same rays from a table of every
/// pixel it keeps for the process, one per camera model and sensor pose: six floats a pixel
/// (7 MiB for 640 x 480), up to 100 tables when the sensor pose changes from frame to frame.
/// Only the centre pixels of the blocks are needed here; they are undistorted per call.
///
/// Throws std::invalid_argument naming the sizes where MRPT's own assertions would throw: an image
/// whose size is not a multiple of the decimation or differs from the camera model's;
/// `decimation` must be at least 2.
void unprojectDecimated(const mrpt::obs::CObservation3DRangeScan& depth, std::size_t decimation,
                        std::vector<Eigen::Vector3f>& pts, std::size_t& invalid);

}  // namespace rtog::detail
