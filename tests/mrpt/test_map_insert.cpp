// Insertion of every supported observation type from MRPT's own rawlogs.
#include <gtest/gtest.h>

#include <limits>
#include <utility>
#include <vector>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRotatingScan.h>
#include <mrpt/obs/CObservationVelodyneScan.h>
#include <mrpt/maps/CSimplePointsMap.h>

#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;

namespace {
void expectSound(const CRTreeOccupancyGridMap& m) { EXPECT_EQ(m.map().checkInvariants(), ""); }
}  // namespace

TEST(MapInsert, Velodyne) {
  auto obs = firstObservation(dataset("test_velodyne_VLP16.rawlog"));
  ASSERT_TRUE(std::dynamic_pointer_cast<mrpt::obs::CObservationVelodyneScan>(obs));
  CRTreeOccupancyGridMap m(0.2);
  m.insertionOptions.maxDistanceInsertion = 30;
  EXPECT_TRUE(m.insertObservation(*obs, mrpt::poses::CPose3D(1, 2, 0.5, 0.3, 0, 0)));
  EXPECT_GT(m.lastInsertStats.rays_hit + m.lastInsertStats.rays_truncated, 10000u);
  EXPECT_GT(m.map().statistics().occupied_cells, 1000);
  EXPECT_GT(m.map().statistics().free_cells, 1000);
  // Sensor pose from the observation, robot pose from the call: the origin cell is free.
  obs->load();
  mrpt::poses::CPose3D sp;
  obs->getSensorPose(sp);
  const auto o = mrpt::poses::CPose3D(1, 2, 0.5, 0.3, 0, 0) + sp;
  EXPECT_EQ(m.map().stateAt(Eigen::Vector3d(o.x(), o.y(), o.z())), rtog::CellState::Free);
  expectSound(m);
}

TEST(MapInsert, RotatingScan) {
  auto obs = firstObservation(dataset("rot_scan_velodyne.rawlog"));
  auto rot = std::dynamic_pointer_cast<mrpt::obs::CObservationRotatingScan>(obs);
  ASSERT_TRUE(rot);
  CRTreeOccupancyGridMap m(0.2);
  m.insertionOptions.decimation = 4;
  EXPECT_TRUE(m.insertObservation(*obs));
  const std::size_t beams = m.lastInsertStats.raysTotal() + m.invalidRangesSkipped;
  // fromVelodyne fills columnCount/rowCount columns, one per firing sequence.
  EXPECT_EQ(beams, std::size_t(rot->rowCount) * ((rot->columnCount / rot->rowCount + 3) / 4));
  EXPECT_GT(m.lastInsertStats.rays_hit, 3000u);
  EXPECT_GT(m.invalidRangesSkipped, 0u);  // zero ranges are counted, not inserted
  EXPECT_GT(m.map().statistics().occupied_cells, 1000);
  expectSound(m);
}

TEST(MapInsert, DepthImage) {
  auto obs = firstObservation(dataset("tests_rgbd.rawlog"));
  auto d = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(obs);
  ASSERT_TRUE(d);
  CRTreeOccupancyGridMap m(0.05);
  m.insertionOptions.decimation_3d_range = 4;
  EXPECT_TRUE(m.insertObservation(*obs));
  EXPECT_GT(m.lastInsertStats.rays_hit, 2000u);
  // The end points are MRPT's own unprojection through the camera model.
  mrpt::maps::CSimplePointsMap pm;
  mrpt::obs::T3DPointsProjectionParams pp;
  pp.takeIntoAccountSensorPoseOnRobot = true;
  pp.decimation = 4;
  d->unprojectInto(pm, pp);
  EXPECT_EQ(m.lastInsertStats.raysTotal(), pm.size());
  // Every end point within the insertion range lies in an occupied cell (one update per cell
  // and scan, occupied winning); the others were cut there, free.
  std::size_t occupied = 0, within = 0;
  for (std::size_t i = 0; i < pm.size(); ++i) {
    mrpt::math::TPoint3D p;
    pm.getPoint(i, p);
    const mrpt::poses::CPose3D& s = d->sensorPose;
    if (std::hypot(p.x - s.x(), p.y - s.y(), p.z - s.z()) >= m.insertionOptions.maxDistanceInsertion) continue;
    ++within;
    occupied += m.map().stateAt(Eigen::Vector3d(p.x, p.y, p.z)) == rtog::CellState::Occupied;
  }
  EXPECT_GT(within, pm.size() / 2);
  EXPECT_EQ(occupied, within);
  expectSound(m);

  // Exactly MRPT's points, also with a robot pose (sensor pose from the observation).
  const mrpt::poses::CPose3D robot(0.5, -1.0, 0.2, 0.4, 0.1, -0.05);
  mrpt::maps::CSimplePointsMap pg;
  pp.robotPoseInTheWorld = robot;
  d->unprojectInto(pg, pp);
  rtog::ObservationBeams beams;
  ASSERT_TRUE(m.extractBeams(*obs, robot, beams, true));
  ASSERT_EQ(beams.points.size(), pg.size());
  double worst = 0;
  for (std::size_t i = 0; i < pg.size(); ++i) {
    mrpt::math::TPoint3D p;
    pg.getPoint(i, p);
    worst = std::max(worst, (beams.points[i].cast<double>() - Eigen::Vector3d(p.x, p.y, p.z)).norm());
  }
  EXPECT_LT(worst, 1e-3);
  const auto sensor = robot + d->sensorPose;
  EXPECT_NEAR((beams.origin - Eigen::Vector3d(sensor.x(), sensor.y(), sensor.z())).norm(), 0.0, 1e-9);
}

TEST(MapInsert, DepthObservationWithOnlyPoints) {
  auto d = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(firstObservation(dataset("tests_rgbd.rawlog")));
  ASSERT_TRUE(d);
  mrpt::maps::CSimplePointsMap pm;
  mrpt::obs::T3DPointsProjectionParams pp;
  pp.decimation = 4;
  d->unprojectInto(pm, pp);  // sensor frame
  mrpt::obs::CObservation3DRangeScan only;
  only.sensorPose = d->sensorPose;
  only.hasPoints3D = true;
  only.points3D_x.assign(pm.getPointsBufferRef_x().begin(), pm.getPointsBufferRef_x().end());
  only.points3D_y.assign(pm.getPointsBufferRef_y().begin(), pm.getPointsBufferRef_y().end());
  only.points3D_z.assign(pm.getPointsBufferRef_z().begin(), pm.getPointsBufferRef_z().end());
  CRTreeOccupancyGridMap a(0.05), b(0.05);
  a.insertionOptions.decimation_3d_range = 4;
  ASSERT_TRUE(a.insertObservation(*d));
  ASSERT_TRUE(b.insertObservation(only));
  EXPECT_EQ(b.lastInsertStats.raysTotal(), pm.size());
  EXPECT_EQ(a.map().statistics().occupied_cells, b.map().statistics().occupied_cells);
  EXPECT_FALSE(CRTreeOccupancyGridMap().insertObservation(mrpt::obs::CObservation3DRangeScan()));
}

TEST(MapInsert, PointCloudObservation) {
  auto velo = std::dynamic_pointer_cast<mrpt::obs::CObservationVelodyneScan>(
      firstObservation(dataset("test_velodyne_VLP16.rawlog")));
  ASSERT_TRUE(velo);
  velo->generatePointCloud();
  mrpt::obs::CObservationPointCloud pc;
  auto pts = mrpt::maps::CSimplePointsMap::Create();
  for (std::size_t i = 0; i < velo->point_cloud.x.size(); ++i)
    pts->insertPoint(velo->point_cloud.x[i], velo->point_cloud.y[i], velo->point_cloud.z[i]);
  pc.pointcloud = pts;
  pc.sensorPose = mrpt::poses::CPose3D(0, 0, 1.0, 0, 0, 0);
  CRTreeOccupancyGridMap a(0.2), b(0.2);
  a.insertionOptions.maxDistanceInsertion = b.insertionOptions.maxDistanceInsertion = 30;
  EXPECT_TRUE(a.insertObservation(pc));
  velo->sensorPose = pc.sensorPose;
  EXPECT_TRUE(b.insertObservation(*velo));
  // Same points, same sensor pose: the same map.
  EXPECT_EQ(a.map().statistics().cells, b.map().statistics().cells);
  EXPECT_EQ(a.map().statistics().occupied_cells, b.map().statistics().occupied_cells);
  expectSound(a);
}

TEST(MapInsert, SenaScansAndSensoryFrames) {
  auto frames = loadOdometryFrames(dataset(kSena), 60);
  ASSERT_EQ(frames.size(), 60u);
  CRTreeOccupancyGridMap m(0.05);
  for (const auto& f : frames) EXPECT_TRUE(f.sf->insertObservationsInto(m, f.pose));
  const auto s = m.map().statistics();
  EXPECT_GT(s.occupied_cells, 1000);
  EXPECT_GT(s.free_cells, 50000);
  // 2D scans go into one planar slab of the 3D map.
  const rtog::Box kb = m.map().keyBounds();
  EXPECT_EQ(kb.extent(2), 1);
  EXPECT_GT(m.totalInsertStats.rays_hit, 60u * 100u);
  expectSound(m);
}

TEST(MapInsert, InvalidRangesCountedAndSkipped) {
  auto frames = loadOdometryFrames(dataset(kSena), 1);
  auto scan = frames[0].sf->getObservationByClass<mrpt::obs::CObservation2DRangeScan>();
  ASSERT_TRUE(scan);
  mrpt::obs::CObservation2DRangeScan s = *scan;
  std::size_t invalid = 0;
  for (std::size_t i = 0; i < s.getScanSize(); ++i) {
    if (i % 3 == 0) s.setScanRangeValidity(i, false);
    if (!s.getScanRangeValidity(i)) ++invalid;
  }
  CRTreeOccupancyGridMap::TInsertionOptions io;
  io.sensorModelPreset = "octomap";
  CRTreeOccupancyGridMap m(0.05, io);
  EXPECT_TRUE(m.insertObservation(s));
  EXPECT_EQ(m.invalidRangesSkipped, invalid);
  EXPECT_EQ(m.lastInsertStats.raysTotal() + invalid, s.getScanSize());
  // mrpt_grid, as COccupancyGridMap2D: no-return beams clear space (considerInvalidRangesAsFreeSpace)
  // and count as truncated, or are skipped and counted as such.
  CRTreeOccupancyGridMap g(0.05);
  EXPECT_TRUE(g.insertObservation(s));
  EXPECT_EQ(g.invalidRangesSkipped, 0u);
  EXPECT_EQ(g.lastInsertStats.raysTotal(), s.getScanSize());
  EXPECT_GE(g.lastInsertStats.rays_truncated, invalid);
  CRTreeOccupancyGridMap h(0.05);
  h.insertionOptions.considerInvalidRangesAsFreeSpace = false;
  EXPECT_TRUE(h.insertObservation(s));
  EXPECT_EQ(h.invalidRangesSkipped, invalid);
  EXPECT_EQ(h.lastInsertStats.raysTotal(), s.getScanSize());
}

TEST(MapInsert, UnsupportedObservationReturnsFalse) {
  mrpt::obs::CObservationOdometry odo;
  CRTreeOccupancyGridMap m;
  EXPECT_FALSE(m.insertObservation(odo));
  EXPECT_TRUE(m.isEmpty());
  EXPECT_FALSE(m.canComputeObservationLikelihood(odo));
}

TEST(MapInsert, BackedGridFollowsTheRTree) {
  auto frames = loadOdometryFrames(dataset(kSena), 30);
  rtog::CRTreeBackedGridMap2D g(0.05);
  for (const auto& f : frames) EXPECT_TRUE(f.sf->insertObservationsInto(g, f.pose));
  const auto& rm = g.rtreeMap().map();
  // Every cell of the R-tree (one plane, the mrpt_grid preset's -l / 16) is the grid's int8 cell
  // l at its place, and the grid knows no other cell (a cell stepped back to 0 is known to the
  // R-tree, unknown to the grid: the same value).
  std::size_t checked = 0, agree = 0, nonzero = 0;
  rm.forEachLeaf([&](const rtog::Box& b, float v) {
    rtog::forEachCell(b, [&](const rtog::Key& k) {
      ++checked, nonzero += v != 0.0f;
      const Eigen::Vector3d c = rm.lattice().cellCenter(k);
      const int cx = g.x2idx(static_cast<float>(c.x())), cy = g.y2idx(static_cast<float>(c.y()));
      if (cx < 0 || cy < 0 || cx >= int(g.getSizeX()) || cy >= int(g.getSizeY())) return;
      agree += -16.0f * v == float(g.getRawMap()[std::size_t(cy) * g.getSizeX() + std::size_t(cx)]);
    });
  });
  std::size_t known = 0;
  for (const auto l : g.getRawMap()) known += l != 0;
  ASSERT_GT(checked, 1000u);
  EXPECT_EQ(agree, checked);
  EXPECT_EQ(known, nonzero);
}

namespace {

// The map an observation makes through insertObservation (its points read piece by piece by the
// insertion threads) is the map of extractBeams' points given whole to the core, with the same
// counts.
void expectInsertionIsItsBeams(CRTreeOccupancyGridMap& m, const mrpt::obs::CObservation& obs,
                               const mrpt::poses::CPose3D& robot) {
  ASSERT_TRUE(m.insertObservation(obs, robot));
  rtog::ObservationBeams beams;
  ASSERT_TRUE(m.extractBeams(obs, robot, beams, true));
  rtog::OccupancyMap whole(m.map().params());
  const rtog::InsertStats stats = whole.insertPointCloud(beams.origin, beams.points.data(), beams.points.size(),
                                                         m.insertionOptions.toInsertParams(), beams.is_hit.data());
  EXPECT_TRUE(stats == m.lastInsertStats);
  EXPECT_EQ(beams.invalid, m.invalidRangesSkipped);
  EXPECT_GT(stats.raysTotal(), 300u);
  std::vector<std::pair<rtog::Box, float>> a, b;
  m.map().forEachLeaf([&](const rtog::Box& box, float v) { a.emplace_back(box, v); });
  whole.forEachLeaf([&](const rtog::Box& box, float v) { b.emplace_back(box, v); });
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].first.min, b[i].first.min);
    ASSERT_EQ(a[i].first.max, b[i].first.max);
    ASSERT_EQ(a[i].second, b[i].second);
  }
  expectSound(m);
}

}  // namespace

TEST(MapInsert, EveryTypeInsertsTheBeamsExtractBeamsGives) {
  const mrpt::poses::CPose3D robot(1, 2, 0.5, 0.3, 0.05, -0.02);
  {
    SCOPED_TRACE("Velodyne");
    CRTreeOccupancyGridMap m(0.2);
    expectInsertionIsItsBeams(m, *firstObservation(dataset("test_velodyne_VLP16.rawlog")), robot);
  }
  {
    SCOPED_TRACE("rotating scan");
    CRTreeOccupancyGridMap m(0.2);
    m.insertionOptions.decimation = 3;
    expectInsertionIsItsBeams(m, *firstObservation(dataset("rot_scan_velodyne.rawlog")), robot);
    EXPECT_GT(m.invalidRangesSkipped, 0u);
  }
  auto depth =
      std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(firstObservation(dataset("tests_rgbd.rawlog")));
  ASSERT_TRUE(depth);
  {
    SCOPED_TRACE("depth image");
    CRTreeOccupancyGridMap m(0.05);
    m.insertionOptions.decimation_3d_range = 2;
    expectInsertionIsItsBeams(m, *depth, robot);
  }
  // Points only, some without depth (0, 0, 0) or not finite; every second one taken.
  mrpt::obs::CObservation3DRangeScan points = *depth;
  points.unprojectInto(points);
  points.hasRangeImage = false;
  for (std::size_t i = 0; i < points.points3D_x.size(); i += 11)
    points.points3D_x[i] = points.points3D_y[i] = points.points3D_z[i] = 0;
  for (std::size_t i = 5; i < points.points3D_x.size(); i += 13)
    points.points3D_y[i] = std::numeric_limits<float>::quiet_NaN();
  {
    SCOPED_TRACE("depth points");
    CRTreeOccupancyGridMap m(0.05);
    m.insertionOptions.decimation = 2;
    expectInsertionIsItsBeams(m, points, robot);
    EXPECT_GT(m.invalidRangesSkipped, points.points3D_x.size() / 2 / 13);
  }
  {
    SCOPED_TRACE("point cloud");
    auto cloud = mrpt::obs::CObservationPointCloud::Create();
    auto pm = mrpt::maps::CSimplePointsMap::Create();
    for (std::size_t i = 0; i < points.points3D_x.size(); ++i)
      pm->insertPointFast(points.points3D_x[i], points.points3D_y[i], points.points3D_z[i]);
    cloud->pointcloud = pm;
    cloud->sensorPose = mrpt::poses::CPose3D(0.1, 0, 0.3, 0, 0, 0);
    CRTreeOccupancyGridMap m(0.05);
    expectInsertionIsItsBeams(m, *cloud, robot);
    EXPECT_GT(m.invalidRangesSkipped, 0u);
  }
  {
    SCOPED_TRACE("2D scan, octomap preset");
    auto frames = loadOdometryFrames(dataset(kSena), 1);
    auto scan = frames[0].sf->getObservationByClass<mrpt::obs::CObservation2DRangeScan>();
    ASSERT_TRUE(scan);
    CRTreeOccupancyGridMap::TInsertionOptions io;
    io.sensorModelPreset = "octomap";
    CRTreeOccupancyGridMap m(0.05, io);
    expectInsertionIsItsBeams(m, *scan, frames[0].pose);
  }
}
