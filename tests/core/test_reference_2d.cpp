// A real 2D laser sequence (MRPT's SENA rawlog, odometry poses) inserted as a planar slab
// equals the reference grid cell for cell, with and without merging.
#include <gtest/gtest.h>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/poses/CPose3D.h>

#include "rtog/mrpt/rawlog_poses.h"

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
  rtog::forEachOdometryObservation(log, [&](const mrpt::obs::CObservation::Ptr& obs, const mrpt::poses::CPose3D& robot,
                                           std::size_t) {
    const auto scan = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(obs);
    if (!scan || scans.size() >= max_scans) return;
    const mrpt::poses::CPose3D sensor = robot + scan->sensorPose;
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
  });
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
