// CObservationRotatingScan decoding: MRPT's fromVelodyne layout (rows by laser ID, columns by
// firing sequence) read with the lidar's calibration, checked against the raw Velodyne scan.
#include <gtest/gtest.h>

#include <unordered_set>

#include <mrpt/obs/CObservationRotatingScan.h>
#include <mrpt/obs/CObservationVelodyneScan.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;

namespace {

std::unordered_set<std::uint64_t> occupiedKeys(const CRTreeOccupancyGridMap& m) {
  std::unordered_set<std::uint64_t> out;
  m.map().forEachLeaf([&](const rtog::Box& b, float v) {
    if (m.map().logOddsModel().classify(v) != rtog::CellState::Occupied) return;
    rtog::forEachCell(b, [&](const rtog::Key& k) { out.insert(rtog::packKey(k)); });
  });
  return out;
}

double jaccard(const std::unordered_set<std::uint64_t>& a, const std::unordered_set<std::uint64_t>& b) {
  std::size_t both = 0;
  for (auto k : a) both += b.count(k);
  const std::size_t either = a.size() + b.size() - both;
  return either ? double(both) / double(either) : 1.0;
}

// Share of the cells of `a` with a cell of `b` among their 27 neighbours (same geometry up to
// a cell of shift).
double nearShare(const std::unordered_set<std::uint64_t>& a, const std::unordered_set<std::uint64_t>& b) {
  std::size_t near = 0;
  for (auto p : a) {
    const rtog::Key k = rtog::unpackKey(p);
    bool found = false;
    for (int dz = -1; dz <= 1 && !found; ++dz)
      for (int dy = -1; dy <= 1 && !found; ++dy)
        for (int dx = -1; dx <= 1 && !found; ++dx) found = b.count(rtog::packKey(rtog::Key{k.x + dx, k.y + dy, k.z + dz}));
    near += found;
  }
  return a.empty() ? 0.0 : double(near) / double(a.size());
}

}  // namespace

// rot_scan_velodyne.rawlog is MRPT's fromVelodyne() of the sweep in test_velodyne_VLP16.rawlog.
TEST(MapRotatingScan, SameSweepAsTheVelodyneScan) {
  auto rot = std::dynamic_pointer_cast<mrpt::obs::CObservationRotatingScan>(
      firstObservation(dataset("rot_scan_velodyne.rawlog")));
  auto velo = std::dynamic_pointer_cast<mrpt::obs::CObservationVelodyneScan>(
      firstObservation(dataset("test_velodyne_VLP16.rawlog")));
  ASSERT_TRUE(rot && velo);
  const mrpt::poses::CPose3D robot(1.0, -2.0, 0.5, 0.3, 0.0, 0.0);
  CRTreeOccupancyGridMap a(0.1), b(0.1);
  ASSERT_TRUE(a.insertObservation(*rot, robot));
  ASSERT_TRUE(b.insertObservation(*velo, robot));
  const auto ka = occupiedKeys(a), kb = occupiedKeys(b);
  ASSERT_GT(kb.size(), 5000u);
  const double j = jaccard(ka, kb);
  std::cout << "occupied cells: rotating " << ka.size() << ", velodyne " << kb.size() << ", Jaccard " << j
            << ", within a cell " << nearShare(ka, kb) << " / " << nearShare(kb, ka) << "\n";
  // The range image keeps no per-packet azimuth: columns are spread evenly over azimuthSpan, while
  // the encoder's packet azimuths wander by up to ~0.13 deg from that line over this sweep, which
  // moves points across 0.1 m cell faces (with the raw block azimuths the same decoding gives 0.98).
  EXPECT_GE(j, 0.75);
  EXPECT_GE(nearShare(ka, kb), 0.99);
  EXPECT_GE(nearShare(kb, ka), 0.99);
}

// Its own fromVelodyne() of the raw scan agrees as well (the conversion, not only the stored file).
TEST(MapRotatingScan, FromVelodyneAgreesWithTheRawScan) {
  auto velo = std::dynamic_pointer_cast<mrpt::obs::CObservationVelodyneScan>(
      firstObservation(dataset("test_velodyne_VLP16.rawlog")));
  ASSERT_TRUE(velo);
  mrpt::obs::CObservationRotatingScan rot;
  rot.fromVelodyne(*velo);
  CRTreeOccupancyGridMap a(0.1), b(0.1);
  ASSERT_TRUE(a.insertObservation(rot));
  ASSERT_TRUE(b.insertObservation(*velo));
  const auto ka = occupiedKeys(a), kb = occupiedKeys(b);
  EXPECT_GE(jaccard(ka, kb), 0.75);
  EXPECT_GE(nearShare(ka, kb), 0.99);
}

TEST(MapRotatingScan, UnknownLidarWithoutCalibrationIsRefused) {
  auto rot = std::dynamic_pointer_cast<mrpt::obs::CObservationRotatingScan>(
      firstObservation(dataset("rot_scan_velodyne.rawlog")));
  ASSERT_TRUE(rot);
  rot->lidarModel = "SOME-LIDAR";
  CRTreeOccupancyGridMap m(0.1);
  try {
    m.insertObservation(*rot);
    FAIL() << "an unknown lidar model was decoded";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("SOME-LIDAR"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(m.isEmpty());
  // An explicit elevation range is taken as the ring geometry.
  m.insertionOptions.rotatingScan_minElevation_deg = -15;
  m.insertionOptions.rotatingScan_maxElevation_deg = 15;
  EXPECT_TRUE(m.insertObservation(*rot));
  EXPECT_FALSE(m.isEmpty());
}
