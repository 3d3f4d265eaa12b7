// The cache of decoded sensor-frame points must follow the observation's content: addresses and
// timestamps are reused by different scans.
#include <gtest/gtest.h>

#include <functional>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
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

// Issue #37: the depth image's decoded points depend on the whole camera model (intrinsics,
// distortion and its model, size), the range units and range_is_depth, not only on the image:
// one object changed in place is decoded anew, at every decimation.
TEST(MapPointCache, DepthCameraModelChangedInPlace) {
  auto base = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(firstObservation(dataset("tests_rgbd.rawlog")));
  ASSERT_TRUE(base && base->hasRangeImage);
  base->load();
  base->sensorPose = mrpt::poses::CPose3D();
  using Change = std::function<void(mrpt::obs::CObservation3DRangeScan&)>;
  const std::vector<std::pair<std::string, Change>> changes = {
      {"dist", [](auto& d) { d.cameraParams.dist = {{-0.25, 0.08, 0.001, -0.0005, 0.0, 0.0, 0.0, 0.0}}; }},
      {"dist k3", [](auto& d) { d.cameraParams.dist[4] = 0.3; }},
      {"fx", [](auto& d) { d.cameraParams.intrinsicParams(0, 0) *= 1.1; }},
      {"cy", [](auto& d) { d.cameraParams.intrinsicParams(1, 2) += 7; }},
      {"rangeUnits", [](auto& d) { d.rangeUnits *= 2; }},
      {"range_is_depth", [](auto& d) { d.range_is_depth = !d.range_is_depth; }}};
  for (int dec : {1, 2, 4})
    for (const auto& [name, change] : changes) {
      SCOPED_TRACE(name + ", decimation " + std::to_string(dec));
      mrpt::obs::CObservation3DRangeScan d = *base;
      CRTreeOccupancyGridMap m(0.05), fresh(0.05);
      m.insertionOptions.decimation_3d_range = fresh.insertionOptions.decimation_3d_range = static_cast<uint16_t>(dec);
      rtog::ObservationBeams before, after, expected;
      ASSERT_TRUE(m.extractBeams(d, mrpt::poses::CPose3D(), before, true));
      change(d);
      ASSERT_TRUE(m.extractBeams(d, mrpt::poses::CPose3D(), after, true));
      ASSERT_TRUE(fresh.extractBeams(d, mrpt::poses::CPose3D(), expected, true));
      ASSERT_EQ(after.points.size(), expected.points.size());
      EXPECT_TRUE(after.points == expected.points);
      EXPECT_FALSE(after.points == before.points);
    }
}
