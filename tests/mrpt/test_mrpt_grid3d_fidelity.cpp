// The mrpt_grid preset against MRPT's own COccupancyGridMap3D: a 3D section (min_z/max_z in its
// _creationOpts) pasted under rtreeOccupancyGrid must give that grid's voxels exactly, for the
// observations the grid takes (2D and 3D range scans), and for the points of those it does not
// take (point clouds, Velodyne, rotating scans) inserted into the grid with insertPointCloud.
// Real data: MRPT's tests_rgbd.rawlog, SENA's 2D scans, the TUM frames, the VLP-16 scan.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/COccupancyGridMap3D.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/opengl/COctoMapVoxels.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/io/CMemoryStream.h>

#include <opencv2/imgcodecs.hpp>

#include "rtog/image/tum_dataset.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "grid3d_fidelity.hpp"
#include "test_helpers.hpp"

using mrpt::maps::COccupancyGridMap3D;
using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;

namespace {

/// The stock grid takes `obs`'s points as ours reads them (its own insertPointCloud), ours the
/// observation.
void insertBoth(Pair& p, const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& pose) {
  rtog::ObservationBeams b;
  ASSERT_TRUE(p.ours->extractBeams(obs, pose, b, true));
  mrpt::maps::CSimplePointsMap pts;
  for (const auto& q : b.points) pts.insertPointFast(q.x(), q.y(), q.z());
  // The points are decimated already (by `decimation`, as the grid's insertPointCloud would).
  const auto dec = p.stock->insertionOptions.decimation;
  p.stock->insertionOptions.decimation = 1;
  p.stock->insertPointCloud(mrpt::math::TPoint3D(b.origin.x(), b.origin.y(), b.origin.z()), pts);
  p.stock->insertionOptions.decimation = dec;
  ASSERT_TRUE(p.ours->insertObservation(obs, pose));
}

}  // namespace

TEST(MrptGrid3DFidelity, DepthImagesOfTestsRgbdAsTheStockGrid) {
  // The section: 0.10 m, the certainties of a user's config, decimation_3d_range given
  // (which the 3D grid does not read: both decimate by 8).
  Pair p = makePair("resolution=0.10\nmin_x=-2\nmax_x=6\nmin_y=-4\nmax_y=4\nmin_z=-2\nmax_z=3",
                    "maxOccupancyUpdateCertainty=0.60\nmaxFreenessUpdateCertainty=0.55\ndecimation_3d_range=4");
  const auto obs = observationsOf(dataset("tests_rgbd.rawlog"));
  std::size_t frames = 0;
  for (const auto& o : obs) {
    if (!IS_CLASS(*o, mrpt::obs::CObservation3DRangeScan)) continue;
    const mrpt::poses::CPose3D pose(0.05 * double(frames), 0, 0, 0.02 * double(frames), 0, 0);
    p.stock->insertObservation(*o, pose);
    ASSERT_TRUE(p.ours->insertObservation(*o, pose));
    ++frames;
  }
  ASSERT_GT(frames, 0u);
  EXPECT_EQ(differingCells(p, "tests_rgbd.rawlog, " + std::to_string(frames) + " depth frames"), 0u);
}

TEST(MrptGrid3DFidelity, TumFramesAsDepthImagesAsTheStockGrid) {
  // The TUM frames as the CObservation3DRangeScan a Kinect driver writes: depth in 1/5000 m,
  // fr2's intrinsics, the sensor pose the optical frame turned to MRPT's (x forward, z up).
  Pair p = makePair("resolution=0.05\nmin_x=-3\nmax_x=4\nmin_y=-3\nmax_y=4\nmin_z=-1\nmax_z=3", "");
  const auto seq = rtog::image::readTumSequence(RTOG_TEST_TUM_DIR);
  Eigen::Matrix4d opt_from_mrpt = Eigen::Matrix4d::Zero();
  opt_from_mrpt(0, 1) = -1, opt_from_mrpt(1, 2) = -1, opt_from_mrpt(2, 0) = 1, opt_from_mrpt(3, 3) = 1;
  for (const auto& frame : seq.frames) {
    const cv::Mat depth = cv::imread(frame.depth_path, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(depth.type(), CV_16UC1);
    auto o = mrpt::obs::CObservation3DRangeScan::Create();
    o->hasRangeImage = true;
    o->range_is_depth = true;
    o->rangeUnits = float(1.0 / seq.intrinsics.depth_scale);
    o->rangeImage_setSize(depth.rows, depth.cols);
    for (int r = 0; r < depth.rows; ++r)
      for (int c = 0; c < depth.cols; ++c) o->rangeImage(r, c) = depth.at<std::uint16_t>(r, c);
    o->cameraParams.ncols = std::uint32_t(depth.cols), o->cameraParams.nrows = std::uint32_t(depth.rows);
    o->cameraParams.setIntrinsicParamsFromValues(seq.intrinsics.fx, seq.intrinsics.fy, seq.intrinsics.cx,
                                                 seq.intrinsics.cy);
    o->maxRange = 10.0f;
    const Eigen::Matrix4d m = frame.camera_to_world.matrix() * opt_from_mrpt;
    mrpt::math::CMatrixDouble44 hm;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) hm(i, j) = m(i, j);
    o->sensorPose = mrpt::poses::CPose3D(hm);
    p.stock->insertObservation(*o, mrpt::poses::CPose3D());
    ASSERT_TRUE(p.ours->insertObservation(*o, mrpt::poses::CPose3D()));
  }
  EXPECT_EQ(differingCells(p, "TUM, 10 frames as depth images"), 0u);
}

TEST(MrptGrid3DFidelity, SenaScansInA3DSectionAsTheStockGrid) {
  // The 3D grid's defaults (0.25 m, +-5 m) but x and y widened to hold the loop.
  Pair p = makePair("min_x=-20\nmax_x=40\nmin_y=-25\nmax_y=25\nmin_z=-1\nmax_z=2", "");
  EXPECT_DOUBLE_EQ(p.ours->resolution(), 0.25);  // the 3D grid's default resolution
  for (const auto& f : loadOdometryFrames(dataset(kSena), 60)) {
    f.sf->insertObservationsInto(*p.stock, f.pose);
    f.sf->insertObservationsInto(*p.ours, f.pose);
  }
  EXPECT_EQ(differingCells(p, "SENA, 60 frames of 2D scans in a 3D section"), 0u);
}

TEST(MrptGrid3DFidelity, TumFramesVelodyneAndRotatingScansFollowTheSameRaster) {
  Pair tum = makePair("resolution=0.05\nmin_x=-3\nmax_x=4\nmin_y=-3\nmax_y=4\nmin_z=-1\nmax_z=3", "decimation=3");
  const auto seq = rtog::image::readTumSequence(RTOG_TEST_TUM_DIR);
  for (const auto& frame : seq.frames) {
    const auto scan = rtog::image::loadDepthScan(frame, seq.intrinsics, 4);
    auto pc = mrpt::obs::CObservationPointCloud::Create();
    auto cloud = mrpt::maps::CSimplePointsMap::Create();
    for (const auto& q : scan.points)
      cloud->insertPointFast(q.x() - float(scan.origin.x()), q.y() - float(scan.origin.y()),
                             q.z() - float(scan.origin.z()));
    pc->pointcloud = cloud;
    pc->sensorPose = mrpt::poses::CPose3D(scan.origin.x(), scan.origin.y(), scan.origin.z(), 0, 0, 0);
    insertBoth(tum, *pc, mrpt::poses::CPose3D());
  }
  EXPECT_EQ(differingCells(tum, "TUM, 10 frames as point clouds"), 0u);

  Pair velo = makePair("resolution=0.2\nmin_x=-30\nmax_x=30\nmin_y=-30\nmax_y=30\nmin_z=-3\nmax_z=5", "");
  for (const auto& o : observationsOf(dataset("test_velodyne_VLP16.rawlog"))) insertBoth(velo, *o, {});
  EXPECT_EQ(differingCells(velo, "VLP-16"), 0u);

  Pair rot = makePair("resolution=0.2\nmin_x=-30\nmax_x=30\nmin_y=-30\nmax_y=30\nmin_z=-3\nmax_z=5", "decimation=2");
  for (const auto& o : observationsOf(dataset("rot_scan_velodyne.rawlog"))) insertBoth(rot, *o, {});
  EXPECT_EQ(differingCells(rot, "rot_scan_velodyne"), 0u);
}

TEST(MrptGrid3DFidelity, A3DSectionReadsTheGridsKeysAndDefaults) {
  // Only min_z given: the 3D grid's resolution and x/y extent, its likelihood defaults, and
  // likelihoodMethod by its numbers (0 is the likelihood field there, not lmMeanInformation).
  Pair p = makePair("min_z=-1", "", "likelihoodMethod=0");
  EXPECT_DOUBLE_EQ(p.ours->resolution(), 0.25);
  const rtog::TGridFrame3D& f = p.ours->gridFrame3D();
  EXPECT_EQ(f.x_min, p.stock->m_grid.getXMin());
  EXPECT_EQ(f.size_x, 40u);
  EXPECT_EQ(f.size_z, 24u);  // -1 .. 5
  EXPECT_EQ(p.ours->likelihoodOptions.likelihoodMethod, CRTreeOccupancyGridMap::lmLikelihoodField_Thrun);
  EXPECT_EQ(p.ours->likelihoodOptions.LF_maxRange, p.stock->likelihoodOptions.LF_maxRange);
  EXPECT_EQ(p.ours->likelihoodOptions.LF_decimation, p.stock->likelihoodOptions.LF_decimation);
  EXPECT_EQ(makePair("max_z=2", "", "likelihoodMethod=1").ours->likelihoodOptions.likelihoodMethod,
            CRTreeOccupancyGridMap::lmRayTracing);
  // Numbers only the 2D grid has, and extents the grid cannot hold, are the section's errors.
  const auto error = [](const std::string& creation, const std::string& likelihood) -> std::string {
    try {
      multiMapFromIni("[MappingApplication]\nrtreeOccupancyGrid_count=1\n"
                      "[MappingApplication_rtreeOccupancyGrid_00_creationOpts]\n" + creation +
                      "\n[MappingApplication_rtreeOccupancyGrid_00_likelihoodOpts]\n" + likelihood + "\n");
    } catch (const mrpt::ExceptionWithCallBackBase& e) {
      return e.originalWhat;
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error("max_z=2", "likelihoodMethod=4").find("0 (lmLikelihoodField_Thrun) or 1 (lmRayTracing), got 4"),
            std::string::npos);
  EXPECT_NE(error("min_z=3\nmax_z=2", "").find("min_z/max_z"), std::string::npos);
  EXPECT_NE(error("min_z=-1\nmax_x=nan", "").find("min_x/max_x"), std::string::npos);
  EXPECT_NE(error("min_z=-1\nresolution=0.0001\nmax_x=1000", "").find("beyond the key range"), std::string::npos);
  EXPECT_EQ(error("min_z=-1", "likelihoodMethod=lmConsensus"), "");  // names as in every section
  // A 2D section has no 3D grid, and the 3D grid's API says so.
  const auto flat = mapFromSections("resolution=0.1", "");
  EXPECT_FALSE(flat->gridFrame3D().defined);
  EXPECT_THROW(flat->getCellFreeness(0, 0, 0), std::logic_error);
}

TEST(MrptGrid3DFidelity, TheGridsApiClearAndArchiveOnA3DSection) {
  Pair p = makePair("resolution=0.2\nmin_x=-30\nmax_x=30\nmin_y=-30\nmax_y=30\nmin_z=-3\nmax_z=5", "");
  for (const auto& o : observationsOf(dataset("test_velodyne_VLP16.rawlog"))) insertBoth(p, *o, {});
  // insertRay: one more ray, as the grid takes it.
  const mrpt::math::TPoint3D s(0.5, 0.25, 1.0), e(12.3, -7.7, -1.9);
  p.stock->insertRay(s, e);
  p.ours->insertRay(s, e);
  EXPECT_EQ(differingCells(p, "VLP-16 and one insertRay"), 0u);
  const auto& g = p.stock->m_grid;
  std::size_t checked = 0;
  for (unsigned cz = 0; cz < g.getSizeZ(); cz += 3)
    for (unsigned cy = 0; cy < g.getSizeY(); cy += 7)
      for (unsigned cx = 0; cx < g.getSizeX(); cx += 7, ++checked)
        ASSERT_EQ(p.ours->getCellFreeness(cx, cy, cz), p.stock->getCellFreeness(cx, cy, cz)) << cx << "," << cy << "," << cz;
  EXPECT_EQ(p.ours->getCellFreeness(9999, 0, 0), 0.5f);
  // The voxels the grid draws: as many occupied and free ones.
  // (Made by Create(): MRPT's class wants an alignment the stack does not give it.)
  const auto a = mrpt::opengl::COctoMapVoxels::Create(), b = mrpt::opengl::COctoMapVoxels::Create();
  p.stock->getAsOctoMapVoxels(*a);
  p.ours->getAsOctoMapVoxels(*b);
  for (const auto set : {mrpt::opengl::VOXEL_SET_OCCUPIED, mrpt::opengl::VOXEL_SET_FREESPACE})
    EXPECT_EQ(a->getVoxelCount(set), b->getVoxelCount(set));
  EXPECT_GT(a->getVoxelCount(mrpt::opengl::VOXEL_SET_OCCUPIED), 1000u);
  // The archive keeps the 3D grid: the loaded map steps the same cells.
  mrpt::io::CMemoryStream buf;
  auto ar = mrpt::serialization::archiveFrom(buf);
  ar << *p.ours;
  buf.Seek(0);
  auto back = std::dynamic_pointer_cast<CRTreeOccupancyGridMap>(ar.ReadObject());
  ASSERT_TRUE(back);
  EXPECT_TRUE(back->gridFrame3D() == p.ours->gridFrame3D());
  // clear(), as the grid's: its default extent (-5 .. 5) at its resolution.
  p.ours->clear();
  p.stock->clear();
  EXPECT_EQ(p.ours->gridFrame3D().size_x, p.stock->m_grid.getSizeX());
  EXPECT_EQ(p.ours->gridFrame3D().x_min, p.stock->m_grid.getXMin());
}

TEST(MrptGrid3DFidelity, BadPointsAreCountedSkipsAndABadStoredGeometryIsRefused) {
  Pair p = makePair("resolution=0.5\nmin_x=-30\nmax_x=30\nmin_y=-30\nmax_y=30\nmin_z=-3\nmax_z=5", "");
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const mrpt::math::TPoint3D s(0.2, 0.1, 0.3);
  p.ours->insertRay(mrpt::math::TPoint3D(nan, 0, 0), mrpt::math::TPoint3D(1, 1, 1));
  EXPECT_EQ(p.ours->lastInsertStats.skipped_out_of_range, 1u);  // as the grid: no sensor cell, no ray
  p.ours->insertRay(s, mrpt::math::TPoint3D(1, nan, 1));
  EXPECT_EQ(p.ours->lastInsertStats.skipped_non_finite, 1u);
  p.ours->insertRay(s, mrpt::math::TPoint3D(1e30, 0, 0));  // beyond any index: the grid's ints overflow
  EXPECT_EQ(p.ours->lastInsertStats.skipped_out_of_range, 1u);
  p.ours->insertRay(s, mrpt::math::TPoint3D(0.3, 0.2, 0.4));  // the sensor's own cell
  EXPECT_EQ(p.ours->lastInsertStats.skipped_zero_length, 1u);
  EXPECT_TRUE(p.ours->isEmpty());
  mrpt::maps::CSimplePointsMap pts;
  pts.insertPointFast(float(inf), 0, 0);
  pts.insertPointFast(5, 5, 1);
  pts.insertPointFast(0, float(nan), 0);
  p.ours->insertPointCloud(s, pts);
  // (MRPT's own grid casts them to indices, undefined behaviour: not given to it.)
  EXPECT_EQ(p.ours->lastInsertStats.skipped_non_finite, 2u);
  EXPECT_EQ(p.ours->lastInsertStats.rays_hit, 1u);
  EXPECT_FALSE(p.ours->isEmpty());

  // A depth observation holding only its points (no range image), which the grid would drop
  // without a word: its points are rays by the same rule.
  auto only_points = mrpt::obs::CObservation3DRangeScan::Create();
  only_points->hasPoints3D = true;
  only_points->points3D_x = {4.0f, 0.0f}, only_points->points3D_y = {0.0f, 0.0f}, only_points->points3D_z = {0.0f, 0.0f};
  ASSERT_TRUE(p.ours->insertObservation(*only_points, mrpt::poses::CPose3D(0.2, 0.1, 0.3, 0, 0, 0)));
  EXPECT_EQ(p.ours->lastInsertStats.rays_hit, 1u);  // (0, 0, 0) is a point a depth camera did not get
  EXPECT_EQ(p.ours->invalidRangesSkipped, 1u);

  // A stored 3D geometry that no section makes (no cells along x) is a corrupt stream.
  mrpt::io::CMemoryStream buf;
  auto ar = mrpt::serialization::archiveFrom(buf);
  ar << *p.ours;
  std::string bytes(static_cast<const char*>(buf.getRawBufferData()), buf.getTotalBytesCount());
  const double x_min = -30.0;
  const std::string pattern(reinterpret_cast<const char*>(&x_min), sizeof x_min);
  const std::size_t at = bytes.find(pattern);
  ASSERT_NE(at, std::string::npos);
  const std::size_t size_x_at = at + 4 * sizeof(double);  // x_min, y_min, z_min, resolution, size_x
  std::uint32_t size_x = 0;
  std::memcpy(&size_x, bytes.data() + size_x_at, sizeof size_x);
  ASSERT_EQ(size_x, 120u);
  std::memset(bytes.data() + size_x_at, 0, sizeof size_x);
  mrpt::io::CMemoryStream in;
  in.assignMemoryNotOwn(bytes.data(), bytes.size());
  auto rd = mrpt::serialization::archiveFrom(in);
  try {
    rd.ReadObject();
    ADD_FAILURE() << "a corrupt 3D geometry was read";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("3D grid geometry"), std::string::npos) << e.what();
  }
}
