// The memory a 2D view takes beyond its own cells. A map whose few cells lie far apart has a
// dense view over their bounding box (the view is a COccupancyGridMap2D, one byte a cell); what
// it must not do is hold a second, wider array over all of it (rtog_fuzz_insert found a view
// asking for four bytes a cell at once, and the likelihood field keeping eight).
//
// This binary counts every operator new of the process (MRPT's libraries' too: ELF interposition),
// so it holds these cases only.
#include <gtest/gtest.h>

#include <malloc.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <vector>

#include <Eigen/Core>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace {
std::atomic<std::size_t> g_now{0}, g_peak{0};

void* counted(std::size_t n) {
  void* p = std::malloc(n ? n : 1);
  if (!p) throw std::bad_alloc();
  const std::size_t now = g_now += malloc_usable_size(p);
  std::size_t peak = g_peak.load();
  while (now > peak && !g_peak.compare_exchange_weak(peak, now)) {
  }
  return p;
}
void uncounted(void* p) {
  if (!p) return;
  g_now -= malloc_usable_size(p);
  std::free(p);
}

/// The most bytes held at once while `f` runs, beyond those held when it started.
template <class F>
std::size_t peakGrowth(F&& f) {
  const std::size_t start = g_now.load();
  g_peak = start;
  f();
  return g_peak.load() - start;
}

constexpr std::size_t kMiB = std::size_t{1} << 20;

/// Two short walls 200 m apart in x and y at 5 cm: a view of 4,000 x 4,000 cells (16 MB).
void twoFarWalls(rtog::OccupancyMap& m) {
  std::vector<Eigen::Vector3f> a, b;
  for (int i = 0; i < 10; ++i) {
    // Cell centres, so that rounding does not move a point into the next cell.
    a.emplace_back(1.025f, 0.025f + 0.05f * static_cast<float>(i), 0.025f);
    b.emplace_back(201.025f, 200.025f + 0.05f * static_cast<float>(i), 0.025f);
  }
  m.insertPointCloud(Eigen::Vector3d(0, 0, 0), a);
  m.insertPointCloud(Eigen::Vector3d(200, 200, 0), b);
}
}  // namespace

void* operator new(std::size_t n) { return counted(n); }
void* operator new[](std::size_t n) { return counted(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return counted(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void operator delete(void* p) noexcept { uncounted(p); }
void operator delete[](void* p) noexcept { uncounted(p); }
void operator delete(void* p, std::size_t) noexcept { uncounted(p); }
void operator delete[](void* p, std::size_t) noexcept { uncounted(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { uncounted(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { uncounted(p); }

// The view's cells and a bounded tile of band maxima; before: a float per cell besides (64 MB).
TEST(ViewMemory, AWideViewOfASparseMapTakesItsCellsAndLittleMore) {
  rtog::CRTreeOccupancyGridMap m(0.05);
  twoFarWalls(m.map());
  m.notifyMapChanged();
  std::size_t cells = 0;
  const std::size_t grown = peakGrowth([&] {
    const auto view = m.gridView();
    cells = std::size_t{view->getSizeX()} * view->getSizeY();
    // Both walls are drawn, as the stock grid would hold them.
    EXPECT_LT(view->getPos(1.025f, 0.225f), 0.5f);
    EXPECT_LT(view->getPos(201.025f, 200.225f), 0.5f);
    EXPECT_EQ(view->getPos(100.0f, 100.0f), 0.5f);
  });
  ASSERT_GE(cells, std::size_t{15'000'000});
  EXPECT_LT(grown, cells + 8 * kMiB) << cells << " cells";
}

// The likelihood field keeps its terms where scans reach; before: a double per view cell (128 MB).
TEST(ViewMemory, TheLikelihoodFieldKeepsTermsOnlyWhereScansReach) {
  rtog::CRTreeOccupancyGridMap m(0.05);
  twoFarWalls(m.map());
  m.notifyMapChanged();
  m.likelihoodOptions.likelihoodMethod = rtog::CRTreeOccupancyGridMap::lmLikelihoodField_Thrun;
  mrpt::obs::CObservation2DRangeScan scan;
  scan.aperture = static_cast<float>(M_PI);
  scan.maxRange = 8.0f;
  scan.resizeScan(181);
  for (std::size_t i = 0; i < 181; ++i) scan.setScanRange(i, 1.0f), scan.setScanRangeValidity(i, true);
  (void)m.gridView();  // built before the measurement: only the field is measured
  double first = 0;
  const std::size_t grown = peakGrowth([&] { first = m.computeObservationLikelihood(scan, mrpt::poses::CPose3D()); });
  EXPECT_LT(grown, 8 * kMiB);
  // The kept terms give the same value again.
  EXPECT_EQ(m.computeObservationLikelihood(scan, mrpt::poses::CPose3D()), first);
}

// The grid of the backed 2D map is refreshed from the band a tile at a time too.
TEST(ViewMemory, TheBackedGridRefreshesWithoutASecondArray) {
  rtog::CRTreeBackedGridMap2D g(0.05);
  twoFarWalls(g.rtreeMap().map());
  g.rtreeMap().notifyMapChanged();
  std::size_t cells = 0;
  const std::size_t grown = peakGrowth([&] {
    g.refreshGrid();
    cells = std::size_t{g.getSizeX()} * g.getSizeY();
  });
  ASSERT_GE(cells, std::size_t{15'000'000});
  EXPECT_LT(g.getPos(1.025f, 0.225f), 0.5f);
  EXPECT_LT(g.getPos(201.025f, 200.225f), 0.5f);
  EXPECT_LT(grown, cells + 8 * kMiB) << cells << " cells";
}
