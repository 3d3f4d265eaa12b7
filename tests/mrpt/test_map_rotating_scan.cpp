// CObservationRotatingScan decoding: MRPT's fromVelodyne layout (rows by laser ID, columns by
// firing sequence) read with the lidar's calibration, checked against the raw Velodyne scan.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_set>
#include <utility>

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

/// rot_scan_velodyne.rawlog's rotating scan and test_velodyne_VLP16.rawlog's raw scan: one sweep.
std::pair<mrpt::obs::CObservationRotatingScan::Ptr, mrpt::obs::CObservationVelodyneScan::Ptr> theSweep() {
  return {std::dynamic_pointer_cast<mrpt::obs::CObservationRotatingScan>(
              firstObservation(dataset("rot_scan_velodyne.rawlog"))),
          std::dynamic_pointer_cast<mrpt::obs::CObservationVelodyneScan>(
              firstObservation(dataset("test_velodyne_VLP16.rawlog")))};
}

/// The occupied cells of the rotating scan's map and of the Velodyne scan's, both taken from
/// one robot pose at 0.1 m.
struct SweepMaps {
  std::unordered_set<std::uint64_t> rotating, velodyne;
};

SweepMaps sweepMaps(const mrpt::obs::CObservationRotatingScan& rot, const mrpt::obs::CObservationVelodyneScan& velo) {
  const mrpt::poses::CPose3D robot(1.0, -2.0, 0.5, 0.3, 0.0, 0.0);
  CRTreeOccupancyGridMap a(0.1), b(0.1);
  EXPECT_TRUE(a.insertObservation(rot, robot));
  EXPECT_TRUE(b.insertObservation(velo, robot));
  return {occupiedKeys(a), occupiedKeys(b)};
}

}  // namespace

// rot_scan_velodyne.rawlog is MRPT's fromVelodyne() of the sweep in test_velodyne_VLP16.rawlog.
TEST(MapRotatingScan, SameSweepAsTheVelodyneScan) {
  auto [rot, velo] = theSweep();
  ASSERT_TRUE(rot && velo);
  const SweepMaps maps = sweepMaps(*rot, *velo);
  const auto &ka = maps.rotating, &kb = maps.velodyne;
  ASSERT_GT(kb.size(), 5000u);
  const double j = jaccard(ka, kb);
  std::cout << "occupied cells: rotating " << ka.size() << ", velodyne " << kb.size() << ", Jaccard " << j
            << ", within a cell " << nearShare(ka, kb) << " / " << nearShare(kb, ka) << "\n";
  // The range image keeps no per-packet azimuth: columns are spread evenly over azimuthSpan, while
  // the encoder's packet azimuths wander by up to 0.18 deg from that line over this sweep, which
  // moves points across 0.1 m cell faces (WithTheImagesEvenAzimuthsTheRawScanGivesTheSameCells:
  // with the packets moved onto that line, 0.985).
  EXPECT_GE(j, 0.75);
  EXPECT_GE(nearShare(ka, kb), 0.99);
  EXPECT_GE(nearShare(kb, ka), 0.99);
}

// The decoding is exact up to what the image does not keep: with the raw scan's packet azimuths
// moved onto the even spread the image's columns assume (startAzimuth + azimuthSpan * c / columns
// for the first firing sequence of each block), the raw scan and the image give the same cells.
TEST(MapRotatingScan, WithTheImagesEvenAzimuthsTheRawScanGivesTheSameCells) {
  auto [rot, velo] = theSweep();
  ASSERT_TRUE(rot && velo);
  ASSERT_EQ(rot->lidarModel, "VLP-16");
  ASSERT_TRUE(rot->rangeOtherLayers.empty());  // single return: two firing sequences a block
  using Velo = mrpt::obs::CObservationVelodyneScan;
  const std::size_t columns = rot->columnCount / rot->rowCount;
  const double step_deg = rot->azimuthSpan * 180.0 / M_PI / double(columns);
  const double start_deg = rot->startAzimuth * 180.0 / M_PI;
  double moved = 0;  // the largest azimuth change, in degrees
  for (std::size_t k = 0; k < velo->scan_packets.size(); ++k)
    for (int b = 0; b < Velo::BLOCKS_PER_PACKET; ++b) {
      auto& block = velo->scan_packets[k].blocks[b];
      const double column = 2.0 * double(k * Velo::BLOCKS_PER_PACKET + std::size_t(b));
      const double az = std::fmod(start_deg + step_deg * column + 720.0, 360.0);
      const auto even = static_cast<std::uint16_t>(std::lround(az * 100.0) % 36000);
      double d = std::abs(double(even) - double(block.rotation())) / 100.0;
      moved = std::max(moved, std::min(d, 360.0 - d));
      // The block's azimuth is private: its bytes follow the 2-byte header (a raw packet's
      // layout), in the packet's little-endian order; read back through rotation() to be sure.
      static_assert(sizeof(block) == 4 + 3 * Velo::SCANS_PER_BLOCK, "a raw Velodyne block");
      const std::uint8_t le[2] = {static_cast<std::uint8_t>(even & 0xFF), static_cast<std::uint8_t>(even >> 8)};
      std::memcpy(reinterpret_cast<std::uint8_t*>(&block) + 2, le, 2);
      ASSERT_EQ(block.rotation(), even);
    }
  velo->point_cloud.clear();  // decoded from the moved packets
  const SweepMaps maps = sweepMaps(*rot, *velo);
  const auto &ka = maps.rotating, &kb = maps.velodyne;
  ASSERT_GT(kb.size(), 5000u);
  const double j = jaccard(ka, kb);
  std::cout << "azimuths moved by up to " << moved << " deg; occupied cells: rotating " << ka.size()
            << ", velodyne " << kb.size() << ", Jaccard " << j << "\n";
  EXPECT_GT(moved, 0.05);  // the packets did wander from the even spread
  EXPECT_LT(moved, 1.0);   // ...but are the same sweep
  EXPECT_GE(j, 0.9);
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
