// The update batch's queued free walks (eight rays at a time in AVX2 lanes or sixteen in AVX-512
// ones, through a dense window of cells, where the CPU has them) mark exactly what its ray-by-ray
// walk marks: every lane kernel this CPU runs is tested, not only the one it would choose.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <vector>

#include "integrate/update_batch.hpp"

using namespace rtog;

namespace {

Key floorKey(const Eigen::Vector3d& p) {
  return Key{static_cast<std::int32_t>(std::floor(p.x())), static_cast<std::int32_t>(std::floor(p.y())),
             static_cast<std::int32_t>(std::floor(p.z()))};
}

// A finalized batch's free marks: brick key -> the brick's free words.
std::map<Key, std::array<std::uint64_t, kBrickWords>> freeMarks(UpdateBatch& batch) {
  batch.finalize();
  std::map<Key, std::array<std::uint64_t, kBrickWords>> marks;
  for (const UpdateBatch::BrickUpdates* b : batch.bricks()) marks[b->brick] = b->free;
  return marks;
}

// The lane kernels this CPU runs (the one insertion uses first), each named once per process.
std::vector<detail::LaneKernel> kernelsHere() {
  static const char* names[] = {"none: every ray walked alone", "AVX2", "AVX-512"};
  std::vector<detail::LaneKernel> kernels{detail::laneKernel()};
  for (const auto k : {detail::LaneKernel::Avx2, detail::LaneKernel::Avx512})
    if (k != kernels.front() && detail::laneKernelRuns(k)) kernels.push_back(k);
  static bool said = false;
  for (std::size_t i = 0; i < kernels.size() && !said; ++i)
    std::printf("[ lanes    ] %s%s\n", names[static_cast<int>(kernels[i])], i == 0 ? " (this CPU's choice)" : "");
  said = true;
  return kernels;
}

}  // namespace

// Queued rays (walked eight at a time in AVX2 lanes through a dense window, where the CPU has
// AVX2) mark exactly what markRayFree marks ray by ray: segments from a shared start and from
// scattered ones (some too far apart for one window), from cell corners (every crossing a tie),
// exact diagonals, axis-parallel and planar ones, zero-length ones, negative keys, long ones.
TEST(RayTraversal, QueuedRaysMarkWhatEachWalkMarks) {
  std::mt19937 rng(33);
  std::uniform_real_distribution<double> c(-1.0, 1.0), len(0.0, 90.0);
  std::uniform_int_distribution<int> ci(-60, 60), kind(0, 7);
  const auto kernels = kernelsHere();
  for (int round = 0; round < 16; ++round) {
    std::vector<UpdateBatch> queued(kernels.size());
    for (std::size_t k = 0; k < kernels.size(); ++k) ASSERT_TRUE(queued[k].useLaneKernel(kernels[k]));
    UpdateBatch wide_off, one_by_one;
    const Eigen::Vector3d shared(c(rng) * 30.0, c(rng) * 30.0, c(rng) * 10.0);
    const int rays = round == 0 ? 20000 : 3000;  // round 0 fills the queue more than twice
    for (int i = 0; i < rays; ++i) {
      // Starts: one shared; scattered near each other; scattered too far apart for one window.
      const double spread = round % 4 == 3 ? 4000.0 : 60.0;
      Eigen::Vector3d a = round % 4 >= 2 ? Eigen::Vector3d(c(rng), c(rng), c(rng) / 3.0) * spread : shared;
      Eigen::Vector3d b = a + Eigen::Vector3d(c(rng), c(rng), 0.4 * c(rng)).normalized() * len(rng);
      switch (kind(rng)) {
        case 1:  // cell corners
          a = Eigen::Vector3d(ci(rng), ci(rng), ci(rng) / 3), b = Eigen::Vector3d(ci(rng), ci(rng), ci(rng) / 3);
          break;
        case 2: {  // exact diagonal in x, y and z
          const double s = 40.0 * c(rng);
          b = a + Eigen::Vector3d(s, i % 2 ? s : -s, s);
          break;
        }
        case 3:  // axis-parallel in one axis
          b[i % 3] = a[i % 3];
          break;
        case 4:  // planar: walked in the exact integer form, never in lanes
          b.z() = a.z();
          break;
        case 5:  // long: walked at once, not queued
          b = a + (b - a) * 40.0;
          break;
        case 6:  // zero length
          b = a;
          break;
        default: break;
      }
      const Key ka = floorKey(a), kb = floorKey(b);
      for (UpdateBatch& q : queued) q.queueRayFree(a, b, ka, kb);
      wide_off.queueRayFree(a, b, ka, kb);
      if (i % 997 == 0) wide_off.walkQueued(/*wide=*/false);
      one_by_one.markRayFree(a, b, ka, kb);
    }
    wide_off.walkQueued(false);
    const auto want = freeMarks(one_by_one);
    ASSERT_GT(want.size(), 10u);
    for (std::size_t k = 0; k < kernels.size(); ++k)
      ASSERT_TRUE(freeMarks(queued[k]) == want) << "round " << round << ", kernel " << static_cast<int>(kernels[k]);
    ASSERT_TRUE(freeMarks(wide_off) == want) << "round " << round;
  }
}

// The lane window is stored cell-linear, x fastest, and swept back into bricks 16 cells of a row
// at a time: a window one, two or four bricks wide in x puts four, two or one rows in a word,
// and one brick deep in y or z makes the other strides small. Rays confined so, starting at
// cell corners too, mark what markRayFree marks.
TEST(RayTraversal, QueuedRaysInNarrowWindowsMarkWhatEachWalkMarks) {
  std::mt19937 rng(35);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto kernels = kernelsHere();
  int windows = 0;
  for (int narrow_axis = 0; narrow_axis < 3; ++narrow_axis)
    for (int bricks : {1, 2, 4}) {
      std::vector<UpdateBatch> queued(kernels.size());
      for (std::size_t k = 0; k < kernels.size(); ++k) ASSERT_TRUE(queued[k].useLaneKernel(kernels[k]));
      UpdateBatch one_by_one;
      const double width = 16.0 * bricks;
      for (int i = 0; i < 2000; ++i) {
        Eigen::Vector3d a, b;
        for (int axis = 0; axis < 3; ++axis) {
          const double span = axis == narrow_axis ? width : 100.0;
          // Brick -3 .. in the narrow axis (negative keys), about the origin in the others.
          const double base = axis == narrow_axis ? -48.0 : -50.0;
          a[axis] = base + u(rng) * span;
          b[axis] = base + u(rng) * span;
          if (i % 5 == 0) a[axis] = std::floor(a[axis]), b[axis] = std::floor(b[axis]);  // corners: ties
        }
        if (i % 7 == 0) b[narrow_axis] = a[narrow_axis];  // flat in the narrow axis
        const Key ka = floorKey(a), kb = floorKey(b);
        for (UpdateBatch& q : queued) q.queueRayFree(a, b, ka, kb);
        one_by_one.markRayFree(a, b, ka, kb);
      }
      const auto want = freeMarks(one_by_one);
      ASSERT_GT(want.size(), 10u);
      for (std::size_t k = 0; k < kernels.size(); ++k)
        ASSERT_TRUE(freeMarks(queued[k]) == want)
            << "narrow axis " << narrow_axis << ", " << bricks << " bricks, kernel " << static_cast<int>(kernels[k]);
      ++windows;
    }
  EXPECT_EQ(windows, 9);
}
