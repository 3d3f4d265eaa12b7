// The cache of decoded sensor-frame points must follow the observation's content: addresses and
// timestamps are reused by different scans.
#include <gtest/gtest.h>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationVelodyneScan.h>
#include <mrpt/serialization/CArchive.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;
using mrpt::obs::CObservation2DRangeScan;

namespace {

std::vector<CObservation2DRangeScan::Ptr> senaScans(std::size_t n) {
  std::vector<CObservation2DRangeScan::Ptr> out;
  for (const auto& f : loadOdometryFrames(dataset(kSena), n))
    if (auto s = f.sf->getObservationByClass<CObservation2DRangeScan>()) out.push_back(s);
  return out;
}

void expectSameMap(const CRTreeOccupancyGridMap& a, const CRTreeOccupancyGridMap& b) {
  const auto sa = a.map().statistics(), sb = b.map().statistics();
  EXPECT_EQ(sa.leaves, sb.leaves);
  EXPECT_EQ(sa.occupied_cells, sb.occupied_cells);
  EXPECT_EQ(sa.free_cells, sb.free_cells);
}

}  // namespace

TEST(MapPointCache, ScanChangedInPlaceWithoutNewTimestamp) {
  const auto scans = senaScans(2);
  ASSERT_EQ(scans.size(), 2u);
  const mrpt::poses::CPose3D pose(0.2, 0.1, 0, 0.05, 0, 0);
  // Insertion: the second insertion of the same object holds the other scan's ranges.
  CObservation2DRangeScan obs = *scans[0];
  CRTreeOccupancyGridMap m(0.05), ref(0.05);
  ASSERT_TRUE(m.insertObservation(obs, pose));
  obs = *scans[1];
  obs.timestamp = scans[0]->timestamp;
  ASSERT_TRUE(m.insertObservation(obs, pose));
  ASSERT_TRUE(ref.insertObservation(*scans[0], pose));
  ASSERT_TRUE(ref.insertObservation(*scans[1], pose));
  expectSameMap(m, ref);

  // Likelihood: ranges scaled in place, as a filter might. On the native path: MRPT's grid
  // methods on the 2D view read the points MRPT caches inside the observation itself.
  ref.likelihoodOptions.scanLikelihoodOnGridView = false;
  CObservation2DRangeScan probe = *scans[0];
  const double before = ref.computeObservationLikelihood(probe, pose);
  for (std::size_t i = 0; i < probe.getScanSize(); ++i) probe.setScanRange(i, probe.getScanRange(i) * 0.7f);
  const double after = ref.computeObservationLikelihood(probe, pose);
  CObservation2DRangeScan fresh = probe;  // another object: cannot hit the cache
  EXPECT_NE(before, after);
  EXPECT_DOUBLE_EQ(after, ref.computeObservationLikelihood(fresh, pose));

  // Fewer beams, same object and timestamp.
  probe.resizeScan(probe.getScanSize() / 2);
  fresh = probe;
  EXPECT_DOUBLE_EQ(ref.computeObservationLikelihood(probe, pose), ref.computeObservationLikelihood(fresh, pose));
}

TEST(MapPointCache, VelodynePacketsChangedInPlace) {
  auto velo = std::dynamic_pointer_cast<mrpt::obs::CObservationVelodyneScan>(
      firstObservation(dataset("test_velodyne_VLP16.rawlog")));
  ASSERT_TRUE(velo && velo->point_cloud.size() == 0);  // raw packets only: decoded by MRPT
  CRTreeOccupancyGridMap m(0.2);
  ASSERT_TRUE(m.insertObservation(*velo));
  const mrpt::poses::CPose3D pose(0.3, 0, 0, 0.1, 0, 0);
  const double before = m.computeObservationLikelihood(*velo, pose);
  velo->scan_packets.resize(velo->scan_packets.size() / 2);  // half the sweep, same timestamp
  const double after = m.computeObservationLikelihood(*velo, pose);
  mrpt::obs::CObservationVelodyneScan fresh = *velo;
  EXPECT_NE(before, after);
  EXPECT_DOUBLE_EQ(after, m.computeObservationLikelihood(fresh, pose));
}

// A rawlog whose scans all carry one timestamp, read entry by entry as MRPT's apps read it: each
// observation is freed before the next is read, so the next one often gets its address.
TEST(MapPointCache, DistinctScansWithOneTimestampReadOneByOne) {
  const auto scans = senaScans(40);
  ASSERT_EQ(scans.size(), 40u);
  const std::string file = ::testing::TempDir() + "/rtog_one_timestamp.rawlog";
  {
    mrpt::io::CFileGZOutputStream f(file);
    auto ar = mrpt::serialization::archiveFrom(f);
    for (const auto& s : scans) {
      CObservation2DRangeScan copy = *s;
      copy.timestamp = scans[0]->timestamp;
      ar << copy;
    }
  }
  const mrpt::poses::CPose3D pose(1.0, 0.5, 0, 0.2, 0, 0);
  CRTreeOccupancyGridMap m(0.05), ref(0.05);
  {
    mrpt::io::CFileGZInputStream f(file);
    auto ar = mrpt::serialization::archiveFrom(f);
    mrpt::obs::CActionCollection::Ptr acts;
    mrpt::obs::CSensoryFrame::Ptr sf;
    mrpt::obs::CObservation::Ptr obs;
    std::size_t entry = 0, read = 0;
    while (mrpt::obs::CRawlog::getActionObservationPairOrObservation(ar, acts, sf, obs, entry)) {
      ASSERT_TRUE(obs);
      ASSERT_TRUE(m.insertObservation(*obs, pose));
      obs.reset();
      ++read;
    }
    EXPECT_EQ(read, 40u);
  }
  for (const auto& s : scans) ASSERT_TRUE(ref.insertObservation(*s, pose));  // all alive: distinct addresses
  EXPECT_GT(ref.map().statistics().leaves, 1000u);
  expectSameMap(m, ref);

  // Freshly allocated copies, one at a time, freed before the next: the same.
  CRTreeOccupancyGridMap n(0.05);
  for (const auto& s : scans) {
    auto o = std::make_shared<CObservation2DRangeScan>(*s);
    o->timestamp = mrpt::Clock::time_point();  // no timestamp at all
    ASSERT_TRUE(n.insertObservation(*o, pose));
  }
  expectSameMap(n, ref);
}

TEST(MapPointCache, ClearForgetsDecodedPoints) {
  const auto scans = senaScans(2);
  CObservation2DRangeScan obs = *scans[0];
  CRTreeOccupancyGridMap m(0.05), ref(0.05);
  ASSERT_TRUE(m.insertObservation(obs));
  m.clear();
  obs = *scans[1];
  obs.timestamp = scans[0]->timestamp;
  ASSERT_TRUE(m.insertObservation(obs));
  ASSERT_TRUE(ref.insertObservation(*scans[1]));
  expectSameMap(m, ref);
}
