// Observation likelihood and ICP support on real SENA scans.
#include <gtest/gtest.h>

#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/tfest/TMatchingPair.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;
using mrpt::poses::CPose3D;

namespace {

struct Fixture {
  CRTreeOccupancyGridMap map{0.05};
  mrpt::obs::CObservation2DRangeScan::Ptr scan;  // a scan NOT inserted into the map
  CPose3D pose;
};

// Map from every second frame of the first 40; the probe is frame 21 (odometry pose).
const Fixture& fixture() {
  static Fixture f = [] {
    Fixture fx;
    auto frames = loadOdometryFrames(dataset(kSena), 40);
    for (std::size_t i = 0; i < frames.size(); i += 2) frames[i].sf->insertObservationsInto(fx.map, frames[i].pose);
    fx.scan = frames[21].sf->getObservationByClass<mrpt::obs::CObservation2DRangeScan>();
    fx.pose = frames[21].pose;
    return fx;
  }();
  return f;
}

std::vector<CPose3D> shifted(const CPose3D& p) {
  std::vector<CPose3D> out;
  for (double d : {-0.4, 0.4}) {
    out.push_back(p + CPose3D(d, 0, 0, 0, 0, 0));
    out.push_back(p + CPose3D(0, d, 0, 0, 0, 0));
  }
  for (double a : {-0.15, 0.15}) out.push_back(p + CPose3D(0, 0, 0, a, 0, 0));
  return out;
}

void expectPeak(CRTreeOccupancyGridMap& m, const Fixture& f) {
  ASSERT_TRUE(m.canComputeObservationLikelihood(*f.scan));
  const double at = m.computeObservationLikelihood(*f.scan, f.pose);
  EXPECT_TRUE(std::isfinite(at));
  for (const auto& q : shifted(f.pose)) {
    const double l = m.computeObservationLikelihood(*f.scan, q);
    EXPECT_LT(l, at) << "shifted pose " << q.asString();
  }
}

}  // namespace

TEST(MapLikelihood, LikelihoodFieldPeaksAtTruePose) {
  const Fixture& f = fixture();
  CRTreeOccupancyGridMap m = f.map;
  m.likelihoodOptions.likelihoodMethod = CRTreeOccupancyGridMap::lmLikelihoodField_Thrun;
  m.likelihoodOptions.LF_decimation = 2;
  expectPeak(m, f);
  // The cache returns the same value.
  const double a = m.computeObservationLikelihood(*f.scan, f.pose);
  const double b = m.computeObservationLikelihood(*f.scan, f.pose);
  EXPECT_DOUBLE_EQ(a, b);
  // Without the kept terms: the same double (each term computed afresh, as the stock grid does).
  // (Not so on the native 3D path, whose cache keeps the term at the cell's centre.)
  m.likelihoodOptions.enableLikelihoodCache = false;
  EXPECT_EQ(m.computeObservationLikelihood(*f.scan, f.pose), a);
}

TEST(MapLikelihood, RayTracingPeaksAtTruePose) {
  const Fixture& f = fixture();
  CRTreeOccupancyGridMap m = f.map;
  m.likelihoodOptions.likelihoodMethod = CRTreeOccupancyGridMap::lmRayTracing;
  m.likelihoodOptions.rayTracing_decimation = 2;
  m.likelihoodOptions.rayTracing_stdHit = 0.3f;
  expectPeak(m, f);
}

TEST(MapLikelihood, PointCloud3DLikelihood) {
  // A 3D cloud (the scan as points) scores higher at the true pose too.
  const Fixture& f = fixture();
  CRTreeOccupancyGridMap m = f.map;
  mrpt::maps::CSimplePointsMap pts;
  pts.insertObservation(*f.scan);
  mrpt::obs::CObservationPointCloud pc;
  pc.pointcloud = mrpt::maps::CSimplePointsMap::Create(pts);
  m.likelihoodOptions.LF_decimation = 1;
  expectPeak(m, Fixture{f.map, f.scan, f.pose});
  const double at = m.computeObservationLikelihood(pc, f.pose);
  EXPECT_LT(m.computeObservationLikelihood(pc, f.pose + CPose3D(0.4, 0, 0, 0, 0, 0)), at);
}

TEST(MapLikelihood, IcpMatchingAgainstOccupiedCells) {
  const Fixture& f = fixture();
  mrpt::maps::CSimplePointsMap pts;
  pts.insertObservation(*f.scan);
  mrpt::maps::TMatchingParams mp;
  mp.maxDistForCorrespondence = 0.3f;
  mrpt::maps::TMatchingExtraResults er;
  mrpt::tfest::TMatchingPairList corrs;
  const mrpt::poses::CPose2D p2(f.pose);
  f.map.determineMatching2D(&pts, p2, corrs, mp, er);
  EXPECT_GT(er.correspondencesRatio, 0.5f);
  EXPECT_GT(corrs.size(), pts.size() / 2);
  f.map.determineMatching3D(&pts, f.pose, corrs, mp, er);
  EXPECT_GT(corrs.size(), pts.size() / 2);

  mrpt::maps::TMatchingRatioParams rp;
  rp.maxDistForCorr = 0.1f;
  const float at = f.map.compute3DMatchingRatio(&pts, f.pose, rp);
  const float off = f.map.compute3DMatchingRatio(&pts, f.pose + CPose3D(0.5, 0.3, 0, 0.2, 0, 0), rp);
  EXPECT_GT(at, 0.5f);
  EXPECT_LT(off, at);
  // squareDistanceToClosestCorrespondence: a scan point at the true pose is near an occupied cell.
  mrpt::math::TPoint3D q;
  pts.getPoint(pts.size() / 2, q);
  double gx, gy, gz;
  f.pose.composePoint(q.x, q.y, q.z, gx, gy, gz);
  EXPECT_LT(f.map.squareDistanceToClosestCorrespondence(float(gx), float(gy)), 0.3f * 0.3f);
}

TEST(MapLikelihood, VelodyneCloudPeaksAtTruePose) {
  auto obs = firstObservation(dataset("test_velodyne_VLP16.rawlog"));
  CRTreeOccupancyGridMap m(0.2);
  m.insertionOptions.maxDistanceInsertion = 40;
  const CPose3D truth(2.0, -1.0, 0.0, 0.3, 0.0, 0.0);
  ASSERT_TRUE(m.insertObservation(*obs, truth));
  for (auto method : {CRTreeOccupancyGridMap::lmLikelihoodField_Thrun, CRTreeOccupancyGridMap::lmRayTracing}) {
    m.likelihoodOptions.likelihoodMethod = method;
    m.likelihoodOptions.LF_decimation = 10;
    m.likelihoodOptions.rayTracing_decimation = 20;
    m.likelihoodOptions.rayTracing_stdHit = 0.5f;
    m.likelihoodOptions.LF_stdHit = 0.3f;
    const double at = m.computeObservationLikelihood(*obs, truth);
    for (const CPose3D& d : {CPose3D(0.6, 0, 0, 0, 0, 0), CPose3D(0, -0.6, 0, 0, 0, 0), CPose3D(0, 0, 0.5, 0, 0, 0),
                             CPose3D(0, 0, 0, 0.1, 0, 0)})
      EXPECT_LT(m.computeObservationLikelihood(*obs, truth + d), at) << "method " << int(method) << " " << d.asString();
  }
}
