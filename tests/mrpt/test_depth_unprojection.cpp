// A depth image's points, decimated, are MRPT's own (CObservation3DRangeScan::unprojectInto)
// float for float, without the projection table MRPT keeps per camera model and sensor pose.
#include <gtest/gtest.h>

#include <malloc.h>

#include <stdexcept>

#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;

namespace {

mrpt::obs::CObservation3DRangeScan::Ptr rgbdFrame() {
  auto d = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(firstObservation(dataset("tests_rgbd.rawlog")));
  if (!d || !d->hasRangeImage) throw std::runtime_error("tests_rgbd.rawlog: no depth image");
  d->load();
  return d;
}

/// MRPT's points of `d` at `decimation`, in the sensor frame.
mrpt::maps::CSimplePointsMap mrptPoints(mrpt::obs::CObservation3DRangeScan& d, int decimation) {
  mrpt::maps::CSimplePointsMap pm;
  mrpt::obs::T3DPointsProjectionParams pp;
  pp.takeIntoAccountSensorPoseOnRobot = false;
  pp.decimation = static_cast<uint8_t>(decimation);
  d.unprojectInto(pm, pp);
  return pm;
}

/// rtog's end points of `d` (sensor and robot at the origin: the sensor frame, exactly).
rtog::ObservationBeams rtogPoints(const mrpt::obs::CObservation3DRangeScan& d, int decimation) {
  CRTreeOccupancyGridMap m(0.05);
  m.insertionOptions.decimation_3d_range = static_cast<uint16_t>(decimation);
  rtog::ObservationBeams beams;
  if (!m.extractBeams(d, mrpt::poses::CPose3D(), beams, true)) throw std::runtime_error("no beams");
  return beams;
}

void expectSamePoints(mrpt::obs::CObservation3DRangeScan& d, int decimation) {
  SCOPED_TRACE("decimation " + std::to_string(decimation) + (d.range_is_depth ? ", depth" : ", range"));
  const auto pm = mrptPoints(d, decimation);
  const auto beams = rtogPoints(d, decimation);
  ASSERT_GT(pm.size(), 100u);
  ASSERT_EQ(beams.points.size(), pm.size());
  const std::size_t blocks = std::size_t(d.rangeImage.rows() / decimation) * std::size_t(d.rangeImage.cols() / decimation);
  EXPECT_EQ(beams.invalid, blocks - pm.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < pm.size(); ++i) {
    float x, y, z;
    pm.getPoint(i, x, y, z);
    differ += beams.points[i] != Eigen::Vector3f(x, y, z);
  }
  EXPECT_EQ(differ, 0u);
}

TEST(DepthUnprojection, DecimatedPointsAreMrptsFloatForFloat) {
  auto d = rgbdFrame();
  d->sensorPose = mrpt::poses::CPose3D();
  for (int dec : {2, 4, 8, 16}) expectSamePoints(*d, dec);
  // Ranges along the ray instead of depths: MRPT's unit rays.
  d->range_is_depth = false;
  for (int dec : {4, 8}) expectSamePoints(*d, dec);
}

TEST(DepthUnprojection, DistortedCameraIsUndistortedAsMrptDoes) {
  auto d = rgbdFrame();
  d->sensorPose = mrpt::poses::CPose3D();
  d->cameraParams.distortion = mrpt::img::DistortionModel::plumb_bob;
  d->cameraParams.dist = {{-0.25, 0.08, 0.001, -0.0005, 0.0, 0.0, 0.0, 0.0}};
  for (int dec : {4, 8}) expectSamePoints(*d, dec);
}

TEST(DepthUnprojection, BlocksWithoutARangeAreCountedNotInserted) {
  auto d = rgbdFrame();
  d->sensorPose = mrpt::poses::CPose3D();
  // The left half of the image without ranges.
  for (int r = 0; r < d->rangeImage.rows(); ++r)
    for (int c = 0; c < d->rangeImage.cols() / 2; ++c) d->rangeImage(r, c) = 0;
  expectSamePoints(*d, 8);
  const auto beams = rtogPoints(*d, 8);
  EXPECT_GE(beams.invalid, std::size_t(d->rangeImage.rows() / 8) * std::size_t(d->rangeImage.cols() / 16));
}

TEST(DepthUnprojection, ImageNotAMultipleOfTheDecimationIsAClearError) {
  auto d = rgbdFrame();
  ASSERT_NE(d->rangeImage.cols() % 7, 0);
  CRTreeOccupancyGridMap m(0.05);
  m.insertionOptions.decimation_3d_range = 7;
  try {
    m.insertObservation(*d);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("not a multiple of decimation_3d_range 7"), std::string::npos) << e.what();
  }
  EXPECT_EQ(m.map().statistics().cells, 0);
}

double heapInUse() {
  const struct mallinfo2 mi = mallinfo2();
  return double(mi.uordblks) + double(mi.hblkhd);
}

// MRPT keeps a table of six floats a pixel for each camera model and sensor pose it unprojects
// (7 MiB at 640 x 480, up to 100 of them): a camera whose pose changes from frame to frame
// would leave one per frame. The map keeps its cells and one frame's points.
TEST(DepthUnprojection, FramesFromChangingSensorPosesLeaveNoTablesBehind) {
  auto d = rgbdFrame();
  const double pixels = double(d->rangeImage.rows()) * double(d->rangeImage.cols());
  ASSERT_GT(pixels, 300000.0);
  CRTreeOccupancyGridMap m(0.05);
  const double before = heapInUse();
  for (int i = 0; i < 5; ++i) {
    d->sensorPose = mrpt::poses::CPose3D(0.1 * i, 0.05 * i, 0.5, 0.02 * i, 0, 0);
    d->rangeImage(240, 320) = static_cast<uint16_t>(1000 + i);  // another frame: not the cached points
    ASSERT_TRUE(m.insertObservation(*d));
  }
  const double held = heapInUse() - before;
  const double own = double(m.map().memoryBytes());
  EXPECT_LT(held - own, 2.0 * 1024 * 1024) << "held " << held << " B, the map's own " << own << " B";
  EXPECT_GT(m.map().statistics().occupied_cells, 1000);
}

}  // namespace

namespace {

/// The points a map decodes for `d` at `decimation`, a fresh map each time (no cached points).
std::vector<Eigen::Vector3f> pointsOf(const mrpt::obs::CObservation3DRangeScan& d, int decimation) {
  return rtogPoints(d, decimation).points;
}

}  // namespace

// Issue #37: MRPT's unprojectInto undistorts every pixel's ray through its camera model's
// distortion (cv::undistortPoints on the table's pixels, whatever the decimation), so rtog does at
// every decimation: the points are MRPT's, and a distorted camera's are not the undistorted one's.
TEST(DepthUnprojection, DistortionIsAppliedAtEveryDecimation) {
  auto d = rgbdFrame();
  d->sensorPose = mrpt::poses::CPose3D();
  mrpt::obs::CObservation3DRangeScan plain = *d;
  plain.cameraParams.dist.fill(0.0);
  d->cameraParams.distortion = mrpt::img::DistortionModel::plumb_bob;
  d->cameraParams.dist = {{-0.25, 0.08, 0.001, -0.0005, 0.0, 0.0, 0.0, 0.0}};
  for (int dec : {1, 2, 4}) {
    SCOPED_TRACE("decimation " + std::to_string(dec));
    const auto pm = mrptPoints(*d, dec);
    const auto distorted = pointsOf(*d, dec), undistorted = pointsOf(plain, dec);
    ASSERT_EQ(distorted.size(), pm.size());
    std::size_t differ = 0, moved = 0;
    for (std::size_t i = 0; i < pm.size(); ++i) {
      float x, y, z;
      pm.getPoint(i, x, y, z);
      differ += distorted[i] != Eigen::Vector3f(x, y, z);
      moved += i < undistorted.size() && (distorted[i] - undistorted[i]).norm() > 1e-3f;
    }
    EXPECT_EQ(differ, 0u);
    EXPECT_GT(moved, pm.size() / 2);
  }
}
