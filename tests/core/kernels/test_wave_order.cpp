// orderForWaves: the order the lanes take queued rays in. A permutation of the rays; a block of
// rays about as long as their neighbours keeps its order (neighbouring pixels stay side by side
// for the AVX-512 lanes' shared cells); a block whose lengths alternate, as a LiDAR's rings do,
// is put in order of length, so that a wave's lanes end together.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <numeric>
#include <vector>

#include "kernels/lane_walk.hpp"

using namespace rtog;
using detail::QueuedRay;

namespace {

QueuedRay rayOfLength(int n) {
  QueuedRay q;
  q.from = Eigen::Vector3d(0.5, 0.5, 0.5);
  q.to = Eigen::Vector3d(n / 2 + 0.5, 0.5, n - n / 2 + 0.5);
  q.from_key = Key{0, 0, 0};
  q.to_key = Key{n / 2, 0, n - n / 2};
  return q;
}

int lengthOf(const QueuedRay& q) { return std::abs(q.to_key.x) + std::abs(q.to_key.z); }

}  // namespace

TEST(WaveOrder, SimilarLengthsKeepTheirOrder) {
  std::vector<QueuedRay> queued;
  for (int i = 0; i < 1000; ++i) queued.push_back(rayOfLength(40 + (i / 7) % 3));  // a depth image's row
  std::vector<std::uint32_t> rays(queued.size()), order;
  std::iota(rays.begin(), rays.end(), 0u);
  std::vector<std::uint8_t> shared;
  detail::orderForWaves(queued, rays, order, shared);
  EXPECT_EQ(order, rays);
  EXPECT_EQ(shared, std::vector<std::uint8_t>(4, 1));
}

TEST(WaveOrder, AlternatingLengthsAreSortedBlockByBlock) {
  std::vector<QueuedRay> queued;
  const int rings[4] = {12, 180, 35, 90};
  for (int i = 0; i < 1000; ++i) queued.push_back(rayOfLength(rings[i % 4] + (i % 3)));
  std::vector<std::uint32_t> rays(queued.size()), order;
  std::iota(rays.begin(), rays.end(), 0u);
  std::vector<std::uint8_t> shared;
  detail::orderForWaves(queued, rays, order, shared);
  EXPECT_EQ(shared, std::vector<std::uint8_t>(4, 0));
  ASSERT_EQ(order.size(), rays.size());
  std::vector<std::uint32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(sorted, rays);  // a permutation
  // Within each block of 256 the lengths do not decrease (by halves: lengths 2k and 2k + 1 tie).
  for (std::size_t i = 1; i < order.size(); ++i) {
    if (i % 256 != 0) {
      EXPECT_LE(lengthOf(queued[order[i - 1]]) / 2, lengthOf(queued[order[i]]) / 2) << i;
    }
  }
  // A wave of 16 then waits little for its longest ray.
  std::size_t useful = 0, walked = 0;
  for (std::size_t w = 0; w < order.size(); w += 16) {
    int most = 0;
    for (std::size_t j = w; j < std::min(order.size(), w + 16); ++j) {
      useful += lengthOf(queued[order[j]]);
      most = std::max(most, lengthOf(queued[order[j]]));
    }
    walked += 16 * static_cast<std::size_t>(most);
  }
  EXPECT_LT(walked, useful * 110 / 100);
}
