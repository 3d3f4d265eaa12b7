// Inputs the fuzz targets (fuzz/, doc/reliability.md) found to misbehave, one case each.
// Some misbehaved only as undefined behaviour: those cases fail before their fix in the
// sanitizer builds (.ci/asan, .ci/fuzz), which report it, and pass silently elsewhere.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>
#include <stdexcept>
#include <string>

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/serialization/CArchive.h>

#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

using rtog::CRTreeOccupancyGridMap;

namespace {
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
}

// rtog_fuzz_insert: a NaN probability reached MRPT's int8 quantization (a float to integer
// cast: undefined) in the constructor, before the options were validated.
TEST(FuzzRegressions, NaNProbabilityIsRefusedBeforeItIsQuantized) {
  for (const char* preset : {"mrpt_grid", "octomap"}) {
    CRTreeOccupancyGridMap::TInsertionOptions io;
    io.sensorModelPreset = preset;
    io.maxOccupancyUpdateCertainty = kNaN;
    EXPECT_THROW(CRTreeOccupancyGridMap(0.1, io), std::invalid_argument) << preset;
    io.maxOccupancyUpdateCertainty = 0.7f;
    io.maxFreenessUpdateCertainty = kNaN;
    EXPECT_THROW(CRTreeOccupancyGridMap(0.1, io), std::invalid_argument) << preset;
  }
  // The same options set on a map and then used by loadFromGrid.
  mrpt::maps::COccupancyGridMap2D grid(-1.0f, 1.0f, -1.0f, 1.0f, 0.1f);
  CRTreeOccupancyGridMap m(0.1);
  m.insertionOptions.maxOccupancyUpdateCertainty = kNaN;
  EXPECT_THROW(m.loadFromGrid(grid), std::invalid_argument);
}

// rtog_fuzz_insert: the mrpt_grid preset's 2D scan runs were range-checked with a left shift of
// the (negative) start cell, undefined before C++20; a scan taken at negative coordinates.
TEST(FuzzRegressions, GridScanAtNegativeCoordinates) {
  CRTreeOccupancyGridMap m(0.1);
  ASSERT_TRUE(m.insertionOptions.mrptGrid());
  mrpt::obs::CObservation2DRangeScan scan;
  scan.aperture = static_cast<float>(M_PI);
  scan.resizeScan(5);
  for (std::size_t i = 0; i < 5; ++i) scan.setScanRange(i, 2.0f), scan.setScanRangeValidity(i, true);
  EXPECT_TRUE(m.insertObservation(scan, mrpt::poses::CPose3D(-2.31, -1.72, 0, 0.4, 0, 0)));
  EXPECT_GT(m.map().leafCount(), 0u);
  EXPECT_EQ(m.map().checkInvariants(), "");
}

// rtog_fuzz_insert: CRTreeBackedGridMap2D grew its 2D cells over the beams' bounding box, in
// which an end point with an infinite coordinate, cut at maxDistanceInsertion, became NaN:
// MRPT's resizeGrid then failed an assertion (abort). End points the R-tree map skips are left
// out of the box.
TEST(FuzzRegressions, BackedGridIgnoresNonFiniteEndPoints) {
  for (const bool range_limit : {true, false}) {
    rtog::CRTreeOccupancyGridMap::TInsertionOptions io;
    io.sensorModelPreset = "octomap";
    io.maxDistanceInsertion = range_limit ? 5.0f : 0.0f;
    rtog::CRTreeBackedGridMap2D g(0.1);
    g.rtreeMap() = CRTreeOccupancyGridMap(0.1, io);
    auto pts = mrpt::maps::CSimplePointsMap::Create();
    pts->insertPoint(1.0f, 1.0f, 0.0f);
    pts->insertPoint(std::numeric_limits<float>::infinity(), 0.5f, 0.0f);
    pts->insertPoint(0.5f, -std::numeric_limits<float>::infinity(), 0.0f);
    pts->insertPoint(kNaN, 0.5f, 0.0f);
    pts->insertPoint(1e30f, 2.0f, 0.0f);  // finite, without a key
    mrpt::obs::CObservationPointCloud obs;
    obs.pointcloud = pts;
    EXPECT_TRUE(g.insertObservation(obs, mrpt::poses::CPose3D(0.2, 0.3, 0.0, 0, 0, 0)));
    EXPECT_GT(g.rtreeMap().map().leafCount(), 0u);
    EXPECT_LT(g.getSizeX() * g.getSizeY(), 1000000u);  // the grid holds the finite beam, not more
    EXPECT_NE(g.getPos(1.05f, 1.05f), 0.5f);  // the finite beam's end is in the 2D view
  }
}

// rtog_fuzz_mrpt_archive: a stored bool whose byte is neither 0 nor 1 was copied into a bool by
// MRPT's operator>> (undefined behaviour when read: UBSan "load of value 114, which is not a valid
// value for type 'bool'"). Every byte of the options set to 114 in turn: each load either fails
// with a message or loads a map, and (in the sanitizer builds) reads no invalid bool.
TEST(FuzzRegressions, StoredBoolsOtherThanZeroOrOneAreRefused) {
  for (const bool backed : {false, true}) {
    mrpt::io::CMemoryStream buf;
    auto ar = mrpt::serialization::archiveFrom(buf);
    if (backed) ar << rtog::CRTreeBackedGridMap2D(0.1);
    else ar << CRTreeOccupancyGridMap(0.1);
    const auto* p = static_cast<const unsigned char*>(buf.getRawBufferData());
    const std::vector<unsigned char> bytes(p, p + buf.getTotalBytesCount());
    std::size_t as_bool = 0;
    for (std::size_t i = 0; i < std::min<std::size_t>(bytes.size(), 4000); ++i) {
      if (bytes[i] > 1) continue;  // only the bytes a bool could be
      std::vector<unsigned char> bad = bytes;
      bad[i] = 114;
      mrpt::io::CMemoryStream in;
      in.assignMemoryNotOwn(bad.data(), bad.size());
      auto ar2 = mrpt::serialization::archiveFrom(in);
      try {
        ar2.ReadObject();
      } catch (const std::exception& e) {
        as_bool += std::string(e.what()).find("a bool stored as 114") != std::string::npos;
      }
    }
    // Refused as a bool (not only by a later check, nor loaded): fails before the fix in any build.
    // The backed grid's flips land elsewhere first (its grid part), so only the sanitizer builds
    // check it.
    if (!backed) {
      EXPECT_GT(as_bool, 5u);
    }
  }
}

// rtog_fuzz_insert: scored on the 2D view, MRPT's cells-difference (and mean-information) method
// inserts the scan into a grid that it grows to every valid end point: a pose 6e8 m away (or a
// valid range of 1e9 m) made MRPT's resizeGrid abort (an assertion), and a valid range of -1e9 m
// made it write out of bounds (SEGV). Such poses go to the native path, such ranges are no returns
// for those methods. Later (2026-12-03) the same for consensus, which reads the cell of every valid
// end point unchecked: the view is grown to the end points, but not to one 1e9 m behind the
// sensor (SEGV in computeObservationLikelihood_Consensus; fuzz/regressions/insert-consensus-bad-range.bin).
TEST(FuzzRegressions, GridViewLikelihoodOfAHugeRange) {
  CRTreeOccupancyGridMap m(0.1);
  mrpt::obs::CObservation2DRangeScan scan;
  scan.aperture = static_cast<float>(M_PI);
  scan.maxRange = 8.0f;
  scan.resizeScan(7);
  for (std::size_t i = 0; i < 7; ++i) scan.setScanRange(i, 2.0f), scan.setScanRangeValidity(i, true);
  ASSERT_TRUE(m.insertObservation(scan, mrpt::poses::CPose3D()));
  scan.setScanRange(3, 1e9f);
  scan.setScanRange(4, std::numeric_limits<float>::infinity());
  scan.setScanRangeValidity(5, false);  // a no-return beam, stepped up to maxRange
  scan.setScanRange(6, -1e9f);          // "valid", behind the sensor: MRPT wrote beyond its grid
  scan.maxRange = 1e9f;                  // a driver's "no limit"
  for (const auto method : {CRTreeOccupancyGridMap::lmCellsDifference, CRTreeOccupancyGridMap::lmMeanInformation,
                            CRTreeOccupancyGridMap::lmConsensus}) {
    m.likelihoodOptions.likelihoodMethod = method;
    ASSERT_TRUE(m.likelihoodOptions.scanLikelihoodOnGridView);
    (void)m.computeObservationLikelihood(scan, mrpt::poses::CPose3D(0.05, 0.0, 0.0, 0.01, 0, 0));
    (void)m.computeObservationLikelihood(scan, mrpt::poses::CPose3D(-6e8, 3.0, 0.0, 0.01, 0, 0));  // far away
    auto offset = scan;
    offset.sensorPose = mrpt::poses::CPose3D(0.0, 1e9, 0.0, 0, 0, 0);  // a sensor "mounted" far off
    (void)m.computeObservationLikelihood(offset, mrpt::poses::CPose3D(0.05, 0.0, 0.0, 0.01, 0, 0));
  }
  EXPECT_EQ(m.map().checkInvariants(), "");
}

// rtog_fuzz_insert: in the mrpt_grid preset a 2D scan with a NaN aperture gave NaN beam angles,
// and the grid raster cast the NaN end cells to int (undefined). It is refused.
TEST(FuzzRegressions, GridScanWithANaNAperture) {
  CRTreeOccupancyGridMap m(0.1);
  mrpt::obs::CObservation2DRangeScan scan;
  scan.aperture = kNaN;
  scan.resizeScan(3);
  for (std::size_t i = 0; i < 3; ++i) scan.setScanRange(i, 1.0f), scan.setScanRangeValidity(i, true);
  EXPECT_THROW(m.insertObservation(scan, mrpt::poses::CPose3D(0.3, 0.2, 0.0, 0, 0, 0)), std::invalid_argument);
  EXPECT_TRUE(m.isEmpty());
}

// rtog_fuzz_insert (long run of 2026-12-04, after 333,998 executions): scored by mean information
// on the 2D view, a scan is "inserted" by MRPT into a copy of the view, which MRPT does not grow
// for that insertion (it only counts information): end points beyond the view were read out of
// bounds (SEGV in COccupancyGridMap2D::internal_insertObservation, any build). The map's cells
// here lie 1 m above the second scan's, so the view is small, and the scan reaches past it.
TEST(FuzzRegressions, MeanInformationOfAScanReachingBeyondTheView) {
  CRTreeOccupancyGridMap::TInsertionOptions io;
  io.sensorModelPreset = "octomap";
  io.maxDistanceInsertion = 3.99f;
  CRTreeOccupancyGridMap m(0.05, io);
  m.likelihoodOptions.likelihoodMethod = CRTreeOccupancyGridMap::lmMeanInformation;
  ASSERT_TRUE(m.likelihoodOptions.scanLikelihoodOnGridView);
  const auto scanOf = [](std::vector<float> ranges, float aperture, float max_range, const mrpt::poses::CPose3D& sensor) {
    mrpt::obs::CObservation2DRangeScan s;
    s.aperture = aperture, s.maxRange = max_range, s.rightToLeft = true, s.sensorPose = sensor;
    s.resizeScan(ranges.size());
    for (std::size_t i = 0; i < ranges.size(); ++i) s.setScanRange(i, ranges[i]), s.setScanRangeValidity(i, true);
    return s;
  };
  const auto first = scanOf({4, 2.16f, 2.16f, 2.16f, 2.16f, 0.094f, 3.59f, 1.58f, 1.54f}, 6.26f, 0.505f,
                            mrpt::poses::CPose3D(-0.104, -0.104, 1.0, M_PI, 0, 0));
  const mrpt::poses::CPose3D at1(-2.75, 4.0, 1.0, M_PI, 0, 0);
  (void)m.insertObservation(first, at1);
  (void)m.computeObservationLikelihood(first, at1);
  const auto second = scanOf({4, 4, 4, 4, 4, 4, 4, 3.99f, 2.16f, 2.16f}, 5.64f, 3.64f,
                             mrpt::poses::CPose3D(0.398, 0.5, -1e9, 87.15 * M_PI / 180, 0, 0));
  const mrpt::poses::CPose3D at2(0.329, 0.329, 1.0, 143.29 * M_PI / 180, 0, 0);
  EXPECT_THROW(m.insertObservation(second, at2), std::out_of_range);  // the sensor 1e9 m down has no key
  (void)m.computeObservationLikelihood(second, at2);
  // The same scan from the map's own height, and from poses about it: every end point read is
  // inside the view.
  auto level = second;
  level.sensorPose = mrpt::poses::CPose3D(0.398, 0.5, 0.0, 87.15 * M_PI / 180, 0, 0);
  for (const double dx : {-3.0, 0.0, 3.0}) (void)m.computeObservationLikelihood(level, mrpt::poses::CPose3D(dx, 0.3, 1.0, 2.5, 0, 0));
  EXPECT_EQ(m.map().checkInvariants(), "");
}

// rtog_fuzz_insert (long run of 2026-12-04, after about 1,029,000 executions of its third run):
// scored by consensus on the 2D view, a scan with a NaN aperture has NaN beam angles, and MRPT
// read the grid cells of its NaN end points at an undefined index (SEGV in
// COccupancyGridMap2D::computeObservationLikelihood_Consensus, any build). A scan of one beam,
// which MRPT's sin/cos table refuses (assertion nRays >= 2), is scored the same way: by the
// native path, as with the view off.
TEST(FuzzRegressions, EndPointMethodsOnTheViewWithNaNBeamAngles) {
  CRTreeOccupancyGridMap m(0.5);
  mrpt::obs::CObservation2DRangeScan good;
  good.aperture = static_cast<float>(M_PI), good.maxRange = 8.0f;
  good.resizeScan(11);
  for (std::size_t i = 0; i < 11; ++i) good.setScanRange(i, 3.0f), good.setScanRangeValidity(i, true);
  ASSERT_TRUE(m.insertObservation(good, mrpt::poses::CPose3D(4, 4, 0, -0.28, 0, 0)));
  const auto before = m.map().statistics();
  const auto scanOf = [](float aperture, std::vector<float> ranges) {
    mrpt::obs::CObservation2DRangeScan s;
    s.aperture = aperture, s.maxRange = 8.0f;
    s.sensorPose = mrpt::poses::CPose3D(0.5, 0.5, 0.0, -1.32, 0, 0);
    s.resizeScan(ranges.size());
    for (std::size_t i = 0; i < ranges.size(); ++i) s.setScanRange(i, ranges[i]), s.setScanRangeValidity(i, true);
    return s;
  };
  const mrpt::poses::CPose3D at(4, 4, 0, -0.28, 0, 0);
  for (const auto& scan : {scanOf(kNaN, {1.22f, 0.156f, 4.0f}), scanOf(std::numeric_limits<float>::infinity(), {1.0f, 2.0f}),
                           scanOf(static_cast<float>(M_PI), {1.5f})}) {
    for (const auto method : {CRTreeOccupancyGridMap::lmConsensus, CRTreeOccupancyGridMap::lmMeanInformation,
                              CRTreeOccupancyGridMap::lmCellsDifference}) {
      m.likelihoodOptions.likelihoodMethod = method;
      m.likelihoodOptions.scanLikelihoodOnGridView = false;
      const double native = m.computeObservationLikelihood(scan, at);
      m.likelihoodOptions.scanLikelihoodOnGridView = true;
      const double on_view = m.computeObservationLikelihood(scan, at);
      EXPECT_TRUE(on_view == native || (std::isnan(on_view) && std::isnan(native))) << on_view << " vs " << native;
    }
  }
  EXPECT_EQ(m.map().statistics().cells, before.cells);
  EXPECT_EQ(m.map().checkInvariants(), "");
}
