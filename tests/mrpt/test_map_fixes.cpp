// Likelihood, matching and 2D-view behaviour that MRPT's filters and ICP rely on, on SENA scans.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/tfest/TMatchingPair.h>

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
