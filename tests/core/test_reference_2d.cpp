// A real 2D laser sequence (MRPT's SENA rawlog, odometry poses) inserted as a planar slab
// equals the reference grid cell for cell, with and without merging.
#include <gtest/gtest.h>

#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3D.h>

#include "test_support.hpp"

using namespace rtog;

namespace {

struct PlanarScan {
  Eigen::Vector3d origin;
  std::vector<Eigen::Vector3f> points;
};

std::vector<PlanarScan> loadSenaScans(std::size_t max_scans) {
  mrpt::obs::CRawlog log;
  const std::string path = std::string(RTOG_MRPT_DATASETS) + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";
  if (!log.loadFromRawLogFile(path)) throw std::runtime_error("cannot read " + path);
  std::vector<PlanarScan> scans;
  mrpt::poses::CPose2D odo;
  for (std::size_t i = 0; i < log.size() && scans.size() < max_scans; ++i) {
    if (log.getType(i) == mrpt::obs::CRawlog::etActionCollection) {
      if (const auto mv = log.getAsAction(i)->getBestMovementEstimation()) odo = odo + mv->poseChange->getMeanVal();
      continue;
    }
    if (log.getType(i) != mrpt::obs::CRawlog::etSensoryFrame) continue;
    const auto sf = log.getAsObservations(i);
    const auto scan = sf->getObservationByClass<mrpt::obs::CObservation2DRangeScan>();
    if (!scan) continue;
    const mrpt::poses::CPose3D sensor = mrpt::poses::CPose3D(odo) + scan->sensorPose;
    PlanarScan ps;
    ps.origin = Eigen::Vector3d(sensor.x(), sensor.y(), sensor.z());
    const std::size_t n = scan->getScanSize();
    const double da = scan->aperture / double(n - 1);
    for (std::size_t j = 0; j < n; ++j) {
      if (!scan->getScanRangeValidity(j)) continue;
      const double a = (scan->rightToLeft ? 1.0 : -1.0) * (-0.5 * scan->aperture + da * double(j));
      const double r = scan->getScanRange(j);
      double gx, gy, gz;
      sensor.composePoint(r * std::cos(a), r * std::sin(a), 0.0, gx, gy, gz);
      ps.points.emplace_back(float(gx), float(gy), float(gz));
    }
    scans.push_back(std::move(ps));
  }
  return scans;
}

TEST(Reference2D, SenaLaserSequenceEqualsReferenceGrid) {
  const auto scans = loadSenaScans(120);
  ASSERT_GE(scans.size(), 100u);
  InsertParams ip;
  ip.max_range = 30.0;
  for (const MergePolicy policy : {MergePolicy::Off, MergePolicy::Clamped, MergePolicy::Equal}) {
    MapParams p;
    p.resolution = 0.05;
    p.merge = policy;
    OccupancyMap map(p);
    test::ReferenceGrid ref(p);
    for (const auto& s : scans) {
      map.insertPointCloud(s.origin, s.points, ip);
      ref.insert(s.origin, s.points, ip);
    }
    ASSERT_EQ(map.checkInvariants(), "");
    test::expectMatchesReference(map, ref, /*exact=*/true);
    std::cout << "[ 2D ] merge " << toString(policy) << ": " << map.leafCount() << " leaves, " << map.cellCount()
              << " cells\n";
    if (policy != MergePolicy::Off) {
      EXPECT_LT(static_cast<std::int64_t>(map.leafCount()), map.cellCount());
    }
  }
}

}  // namespace
