// Likelihood, matching and 2D-view behaviour that MRPT's filters and ICP rely on, on SENA scans.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/tfest/TMatchingPair.h>

#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;
using mrpt::obs::CObservation2DRangeScan;
using mrpt::poses::CPose3D;

namespace {

struct SenaMap {
  CRTreeOccupancyGridMap map{0.05};
  std::vector<PosedFrame> frames;
};

// Map of the first 30 SENA frames.
const SenaMap& sena() {
  static SenaMap s = [] {
    SenaMap m;
    m.frames = loadOdometryFrames(dataset(kSena), 30);
    for (const auto& f : m.frames) f.sf->insertObservationsInto(m.map, f.pose);
    return m;
  }();
  return s;
}

CObservation2DRangeScan::Ptr scanOf(const PosedFrame& f) { return f.sf->getObservationByClass<CObservation2DRangeScan>(); }

}  // namespace

// A NaN or Inf pose is impossible for every method: below every valid pose's score, and finite
// (MRPT's particle filters assert finite log-likelihoods).
TEST(MapFixes, NonFinitePoseIsImpossibleForEveryMethod) {
  const auto& s = sena();
  const auto scan = scanOf(s.frames[15]);
  ASSERT_TRUE(scan);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const CPose3D good = s.frames[15].pose;
  const std::vector<CPose3D> bad = {CPose3D(nan, 0, 0, 0, 0, 0), CPose3D(0, inf, 0, 0, 0, 0),
                                    CPose3D(0, 0, -inf, 0, 0, 0), CPose3D(1, 1, 0, nan, 0, 0),
                                    CPose3D(1, 1, 0, 0, nan, 0), CPose3D(nan, nan, nan, nan, nan, nan)};
  struct Method {
    const char* name;
    CRTreeOccupancyGridMap::TLikelihoodMethod method;
    bool cache, squareDist;
  };
  for (const Method& m : {Method{"field", CRTreeOccupancyGridMap::lmLikelihoodField_Thrun, true, false},
                          Method{"field, no cache", CRTreeOccupancyGridMap::lmLikelihoodField_Thrun, false, false},
                          Method{"field, square distance", CRTreeOccupancyGridMap::lmLikelihoodField_Thrun, true, true},
                          Method{"ray tracing", CRTreeOccupancyGridMap::lmRayTracing, true, false}}) {
    CRTreeOccupancyGridMap map = s.map;
    map.likelihoodOptions.likelihoodMethod = m.method;
    map.likelihoodOptions.enableLikelihoodCache = m.cache;
    map.likelihoodOptions.LF_useSquareDist = m.squareDist;
    // The worst of some valid poses, far off included.
    double worstValid = map.computeObservationLikelihood(*scan, good);
    for (const CPose3D& q : {CPose3D(50, 50, 0, 1, 0, 0), CPose3D(-1e4, 3e3, 5, 2, 0, 0), good + CPose3D(0.5, 0, 0, 0.3, 0, 0)})
      worstValid = std::min(worstValid, map.computeObservationLikelihood(*scan, q));
    for (const CPose3D& q : bad) {
      const double l = map.computeObservationLikelihood(*scan, q);
      EXPECT_TRUE(std::isfinite(l)) << m.name << " at " << q.asString();
      EXPECT_LE(l, -1e29) << m.name << " at " << q.asString();
      EXPECT_LT(l, worstValid) << m.name << " at " << q.asString();
    }
    // A non-finite sensor pose on the robot is as impossible.
    CObservation2DRangeScan broken = *scan;
    broken.sensorPose = CPose3D(nan, 0, 0, 0, 0, 0);
    EXPECT_LE(map.computeObservationLikelihood(broken, good), -1e29) << m.name;
  }
}

namespace {

// A 3D map holding the SENA scans twice: at their height and, turned and shifted, 2 m above (a
// second level whose walls are not the first level's).
CRTreeOccupancyGridMap::Ptr twoLevelMap(const std::string& matchingSection) {
  mrpt::config::CConfigFileMemory cfg(
      "[map]\nrtreeOccupancyGrid_count=1\n[map_rtreeOccupancyGrid_00_creationOpts]\nresolution=0.05\n"
      // OctoMap's rule keeps each scan at its height (mrpt_grid, as the 2D grid, holds one plane).
      "[map_rtreeOccupancyGrid_00_insertOpts]\nsensorModelPreset=octomap\n" +
      matchingSection);
  mrpt::maps::TSetOfMetricMapInitializers inits;
  inits.loadFromConfigFile(cfg, "map");
  auto mm = std::make_shared<mrpt::maps::CMultiMetricMap>();
  mm->setListOfMaps(inits);
  auto m = mm->mapByClass<CRTreeOccupancyGridMap>();
  const auto& s = sena();
  const CPose3D upper(0.7, -0.4, 2.0, 0.6, 0, 0);
  for (std::size_t i = 0; i < 10; ++i) {
    s.frames[i].sf->insertObservationsInto(*m, s.frames[i].pose);
    s.frames[i].sf->insertObservationsInto(*m, upper + s.frames[i].pose);
  }
  return m;
}

}  // namespace

TEST(MapFixes, Matching2DUsesOnlyTheHeightBand) {
  const auto& s = sena();
  const auto scan = scanOf(s.frames[5]);
  const double zs = scan->sensorPose.z();
  ASSERT_LT(std::abs(zs), 0.5);
  auto m = twoLevelMap("[map_rtreeOccupancyGrid_00_matchingOpts]\nmatching2D_minZ=-1\nmatching2D_maxZ=1\n");
  ASSERT_EQ(m->map().keyBounds().extent(2) > 1, true);  // two levels
  EXPECT_FLOAT_EQ(m->matchingOptions.matching2D_maxZ, 1.0f);

  mrpt::maps::CSimplePointsMap local;
  local.insertObservation(*scan);
  mrpt::tfest::TMatchingPairList pairs;
  mrpt::maps::TMatchingParams params;
  params.maxDistForCorrespondence = 0.5f;
  mrpt::maps::TMatchingExtraResults extra;
  m->determineMatching2D(&local, mrpt::poses::CPose2D(s.frames[5].pose), pairs, params, extra);
  ASSERT_GT(pairs.size(), 50u);
  const auto outside = [&] {
    std::size_t n = 0;
    for (const auto& p : pairs) n += !(p.global.z >= -1 && p.global.z <= 1);
    return n;
  };
  EXPECT_EQ(outside(), 0u) << "of " << pairs.size() << " pairs";
  // Where the scan lies on the upper level's walls: still only cells of the band.
  const CPose3D upper(0.7, -0.4, 2.0, 0.6, 0, 0);
  m->determineMatching2D(&local, mrpt::poses::CPose2D(upper + s.frames[5].pose), pairs, params, extra);
  EXPECT_EQ(outside(), 0u) << "of " << pairs.size() << " pairs";

  // A wall of the upper level, far from every wall of the lower one, is no correspondence.
  mrpt::maps::CSimplePointsMap lower;
  const auto& occ = m->occupiedCellCenters();
  for (std::size_t i = 0; i < occ.size(); ++i) {
    mrpt::math::TPoint3D p;
    occ.getPoint(i, p);
    if (p.z < 1) lower.insertPoint(p.x, p.y, p.z);
  }
  std::size_t probes = 0;
  for (std::size_t i = 0; i < occ.size() && probes < 20; i += 7) {
    mrpt::math::TPoint3D p;
    occ.getPoint(i, p);
    if (p.z < 1) continue;
    const float dLower = lower.squareDistanceToClosestCorrespondence(float(p.x), float(p.y));
    if (dLower < 1.0f) continue;
    ++probes;
    EXPECT_FLOAT_EQ(m->squareDistanceToClosestCorrespondence(float(p.x), float(p.y)), dLower);
  }
  EXPECT_GT(probes, 5u);

  // The band is stored with the map.
  mrpt::io::CMemoryStream buf;
  auto ar = mrpt::serialization::archiveFrom(buf);
  ar << *m;
  buf.Seek(0);
  CRTreeOccupancyGridMap back;
  ar >> back;
  EXPECT_FLOAT_EQ(back.matchingOptions.matching2D_minZ, -1.0f);
  EXPECT_FLOAT_EQ(back.matchingOptions.matching2D_maxZ, 1.0f);
}

// On a flat 2D log the default band holds every cell: matching is what it was on all of them.
TEST(MapFixes, Matching2DDefaultsKeepFlatLogs) {
  const auto& s = sena();
  const auto scan = scanOf(s.frames[5]);
  mrpt::maps::CSimplePointsMap local;
  local.insertObservation(*scan);
  mrpt::tfest::TMatchingPairList a, b;
  mrpt::maps::TMatchingParams params;
  params.maxDistForCorrespondence = 0.5f;
  mrpt::maps::TMatchingExtraResults ea, eb;
  const mrpt::poses::CPose2D pose(s.frames[5].pose);
  s.map.determineMatching2D(&local, pose, a, params, ea);
  s.map.occupiedCellCenters().determineMatching2D(&local, pose, b, params, eb);
  ASSERT_GT(a.size(), 50u);
  EXPECT_EQ(a.size(), b.size());
  EXPECT_DOUBLE_EQ(ea.sumSqrDist, eb.sumSqrDist);
  EXPECT_FLOAT_EQ(s.map.squareDistanceToClosestCorrespondence(1.0f, 2.0f),
                  s.map.occupiedCellCenters().squareDistanceToClosestCorrespondence(1.0f, 2.0f));
}

// A planar scan from a sensor a hair off a cell face: origin and end points in one z-layer (the
// origin is double, the end points float).
TEST(MapFixes, PlanarScanStaysInOneLayerAtACellFace) {
  const auto& s = sena();
  CObservation2DRangeScan scan = *scanOf(s.frames[3]);
  scan.sensorPose = CPose3D(0.1, 0, 0, 0, 0, 0);
  for (double face : {0.3, 0.7, -0.7}) {
    for (double hair : {-1e-9, 1e-9}) {
      const double z = face + hair;
      CRTreeOccupancyGridMap m(0.1);
      const CPose3D pose(1.0, 2.0, z, 0.4, 0, 0);
      rtog::ObservationBeams b;
      ASSERT_TRUE(m.extractBeams(scan, pose, b, true));
      std::size_t other = 0;
      for (const auto& p : b.points) other += double(p.z()) != b.origin.z();
      EXPECT_EQ(other, 0u) << "z " << z;
      ASSERT_TRUE(m.insertObservation(scan, pose));
      EXPECT_EQ(m.map().keyBounds().extent(2), 1) << "z " << z;
    }
  }
}

// TMatchingExtraResults::sumSqrDist is, as CPointsMap::determineMatching3D fills it, the mean of
// the pairs' squared distances.
TEST(MapFixes, Matching3DReportsTheMeanSquaredDistanceAsMrpt) {
  const auto& s = sena();
  // The scan's points at the height of the cell centres (MRPT's matcher first requires the
  // bounding boxes to overlap, flat ones too).
  mrpt::maps::CSimplePointsMap scanPts, local;
  scanPts.insertObservation(*scanOf(s.frames[7]));
  const float zc = s.map.occupiedCellCenters().getPointsBufferRef_z()[0];
  for (std::size_t i = 0; i < scanPts.size(); ++i) {
    mrpt::math::TPoint3D p;
    scanPts.getPoint(i, p);
    local.insertPoint(float(p.x), float(p.y), zc);
  }
  const CPose3D pose = s.frames[7].pose + CPose3D(0.05, -0.03, 0, 0.02, 0, 0);
  mrpt::maps::TMatchingParams params;
  params.maxDistForCorrespondence = 0.3f;
  mrpt::tfest::TMatchingPairList pairs, mrptPairs;
  mrpt::maps::TMatchingExtraResults extra, mrptExtra;
  s.map.determineMatching3D(&local, pose, pairs, params, extra);
  ASSERT_GT(pairs.size(), 50u);
  double sum = 0;
  for (const auto& p : pairs) sum += p.errorSquareAfterTransformation;
  EXPECT_NEAR(extra.sumSqrDist, sum / double(pairs.size()), 1e-9 + 1e-6 * sum);
  // MRPT's matcher on the same cell centres reports the same kind of figure. (On a copy: MRPT
  // 2.5.8 keeps one "up to date" flag for its 2D and 3D KD-trees, so a points map searched in 2D
  // before has no 3D tree.)
  const mrpt::maps::CSimplePointsMap centres = s.map.occupiedCellCenters();
  centres.determineMatching3D(&local, pose, mrptPairs, params, mrptExtra);
  ASSERT_GT(mrptPairs.size(), 50u);
  EXPECT_NEAR(extra.sumSqrDist, mrptExtra.sumSqrDist, 0.5 * mrptExtra.sumSqrDist);
  EXPECT_LT(extra.sumSqrDist, params.maxDistForCorrespondence * params.maxDistForCorrespondence);
}

// A 1-beam scan (MRPT's getScanAngle() is NaN for it) in the octomap preset: its ray goes where
// COccupancyGridMap2D casts it, the first ray's angle, and marks that end cell occupied.
TEST(MapFixes, OneBeamScanIsInsertedWhereTheStockGridCastsIt) {
  for (const bool right_to_left : {true, false})
    for (const float aperture : {float(M_PI), 0.5f, float(2 * M_PI)}) {
      SCOPED_TRACE(std::string(right_to_left ? "right to left" : "left to right") + ", aperture " +
                   std::to_string(aperture));
      CObservation2DRangeScan scan;
      scan.aperture = aperture;
      scan.rightToLeft = right_to_left;
      scan.resizeScan(1);
      scan.setScanRange(0, 3.0f);
      scan.setScanRangeValidity(0, true);
      const CPose3D robot(0.05, 0.05, 0, 0.3, 0, 0);
      mrpt::maps::COccupancyGridMap2D grid(-10, 10, -10, 10, 0.1f);
      ASSERT_TRUE(grid.insertObservation(scan, robot));
      // The stock grid's occupied end cell: its most certain one.
      int bx = 0, by = 0;
      for (int y = 0; y < int(grid.getSizeY()); ++y)
        for (int x = 0; x < int(grid.getSizeX()); ++x)
          if (grid.getCell(x, y) < grid.getCell(bx, by)) bx = x, by = y;
      ASSERT_LT(grid.getCell(bx, by), 0.5f);
      CRTreeOccupancyGridMap m(0.1);
      m.insertionOptions.sensorModelPreset = "octomap";
      ASSERT_TRUE(m.insertObservation(scan, robot));
      EXPECT_EQ(m.lastInsertStats.rays_hit, 1u);
      EXPECT_EQ(m.lastInsertStats.skipped_non_finite, 0u);
      EXPECT_EQ(m.map().stateAt(Eigen::Vector3d(grid.idx2x(bx), grid.idx2y(by), 0.0)), rtog::CellState::Occupied);
      EXPECT_EQ(m.map().statistics().occupied_cells, 1);
    }
}

// Issue #37: a NaN or infinite angle in the sensor pose on the observation (not only in its
// position, or in the robot pose) is as impossible, for every method, on the native path and on
// the 2D view, for planar scans and point clouds, and on the rtreeGridMap2D map too. Before, a
// NaN sensor yaw or pitch made every end point NaN, and ray tracing skipped them all: 0, the best.
TEST(MapFixes, NonFiniteAngleOfAnyPoseIsImpossibleForEveryMethod) {
  const auto& s = sena();
  const auto scan = scanOf(s.frames[15]);
  ASSERT_TRUE(scan);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const CPose3D good = s.frames[15].pose;
  std::vector<CPose3D> badRobot, badSensor;
  for (int k = 0; k < 6; ++k)
    for (double v : {nan, inf}) {
      double c[6] = {1, 1, 0, 0.2, 0, 0};
      c[k] = v;
      badRobot.emplace_back(c[0], c[1], c[2], c[3], c[4], c[5]);
      double d[6] = {0.1, 0, 0, 0, 0, 0};
      d[k] = v;
      badSensor.emplace_back(d[0], d[1], d[2], d[3], d[4], d[5]);
    }
  mrpt::maps::CSimplePointsMap pts;
  pts.insertObservation(*scan);
  auto cloud = mrpt::obs::CObservationPointCloud::Create();
  cloud->pointcloud = std::make_shared<mrpt::maps::CSimplePointsMap>(pts);
  cloud->sensorPose = CPose3D();
  const auto check = [&](const mrpt::maps::CMetricMap& map, const std::string& name) {
    for (const mrpt::obs::CObservation* o : {static_cast<const mrpt::obs::CObservation*>(scan.get()),
                                             static_cast<const mrpt::obs::CObservation*>(cloud.get())}) {
      const std::string what = name + (o == scan.get() ? ", 2D scan" : ", point cloud");
      if (!map.canComputeObservationLikelihood(*o)) continue;
      for (const CPose3D& q : badRobot) {
        const double l = map.computeObservationLikelihood(*o, q);
        EXPECT_TRUE(std::isfinite(l)) << what << ", robot at " << q.asString();
        EXPECT_LE(l, -1e29) << what << ", robot at " << q.asString();
      }
      for (const CPose3D& sp : badSensor) {
        mrpt::obs::CObservation::Ptr broken = std::dynamic_pointer_cast<mrpt::obs::CObservation>(o->duplicateGetSmartPtr());
        broken->setSensorPose(sp);
        EXPECT_LE(map.computeObservationLikelihood(*broken, good), -1e29) << what << ", sensor at " << sp.asString();
      }
    }
  };
  for (int method = 0; method <= 6; ++method)
    for (bool view : {true, false}) {
      CRTreeOccupancyGridMap map = s.map;
      map.likelihoodOptions.likelihoodMethod = static_cast<CRTreeOccupancyGridMap::TLikelihoodMethod>(method);
      map.likelihoodOptions.scanLikelihoodOnGridView = view;
      check(map, "method " + std::to_string(method) + (view ? ", 2D view" : ", native"));
    }
  for (int method = 0; method <= 6; ++method) {
    rtog::CRTreeBackedGridMap2D backed(0.05);
    for (std::size_t i = 0; i < 30; ++i) s.frames[i].sf->insertObservationsInto(backed, s.frames[i].pose);
    backed.likelihoodOptions.likelihoodMethod = static_cast<mrpt::maps::COccupancyGridMap2D::TLikelihoodMethod>(method);
    check(backed, "rtreeGridMap2D, method " + std::to_string(method));
    // A finite pose: the stock grid's score, as before. (Not for consensus: MRPT's reads the cells
    // of end points beyond the grid without a bounds check, a crash of the stock grid too.)
    if (method == 2) continue;
    const mrpt::maps::COccupancyGridMap2D stock = backed;
    EXPECT_DOUBLE_EQ(backed.computeObservationLikelihood(*scan, good), stock.computeObservationLikelihood(*scan, good))
        << "method " << method;
  }
}
