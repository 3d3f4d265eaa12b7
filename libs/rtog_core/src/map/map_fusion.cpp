// Fusion of another map into this one by the independent opinion pool (the estimator seed,
// section 3): P = P1 P2 / (P1 P2 + (1 - P1)(1 - P2)) with the prior P0 counted once, which in
// log-odds is l = l1 + l2 - l0, clamped. The other map's evidence enters as one update whose
// change in a cell is l2 - l0 of the other map's cell there, through the graded path that
// range-noise scans take: each cell once, brick by brick, the map independent of the threads.
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "integrate/batch_apply.hpp"
#include "integrate/graded_scan.hpp"
#include "map/map_engine.hpp"
#include "rtog/core/occupancy_map.hpp"

namespace rtog {

namespace {

void checkRigid(const Eigen::Isometry3d& pose) {
  const Eigen::Matrix3d r = pose.linear();
  const bool finite = pose.matrix().allFinite();
  if (!finite || !(r.transpose() * r).isIdentity(1e-9) || !(r.determinant() > 0.0))
    throw std::invalid_argument(
        "rtog::OccupancyMap::fuse: the pose must be rigid (finite, a rotation and a translation)");
}

/// The cells of `dst` whose centres, taken back by `inv` into the other map, fall in `box` of
/// `src`: each gets `delta`. Identity or a shift by whole cells of equal lattices maps centres to
/// centres, so each cell of the box lands on exactly one cell.
void markBox(const Lattice& dst, const Lattice& src, const Eigen::Isometry3d& pose, const Eigen::Isometry3d& inv,
             const Box& box, float delta, GradedScan& out, InsertStats& stats) {
  const Eigen::Vector3d lo = src.boxMin(box), hi = src.boxMax(box);
  Eigen::Vector3d a = Eigen::Vector3d::Constant(HUGE_VAL), b = Eigen::Vector3d::Constant(-HUGE_VAL);
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z());
    const Eigen::Vector3d p = dst.toLattice(pose * corner);
    a = a.cwiseMin(p), b = b.cwiseMax(p);
  }
  // Cells whose centre lies within [a, b]: from ceil(a - 0.5) to floor(b - 0.5), within the keys.
  constexpr double kMin = kKeyMin, kMax = kKeyMax;
  std::int64_t from[3], to[3];
  bool beyond = false;  // the part beyond the keys is left out, the cuboid counted once
  for (int i = 0; i < 3; ++i) {
    const double f = std::ceil(a[i] - 0.5), t = std::floor(b[i] - 0.5);
    beyond = beyond || f < kMin || t > kMax;
    from[i] = static_cast<std::int64_t>(std::max(f, kMin));
    to[i] = static_cast<std::int64_t>(std::min(t, kMax));
  }
  if (beyond) ++stats.skipped_out_of_range;
  for (std::int64_t z = from[2]; z <= to[2]; ++z)
    for (std::int64_t y = from[1]; y <= to[1]; ++y)
      for (std::int64_t x = from[0]; x <= to[0]; ++x) {
        const Key k{static_cast<std::int32_t>(x), static_cast<std::int32_t>(y), static_cast<std::int32_t>(z)};
        Key back;
        if (src.tryKey(inv * dst.cellCenter(k), back) && box.contains(back)) out.mark(k, delta);
      }
}

}  // namespace

InsertStats OccupancyMap::fuse(const OccupancyMap& other, const Eigen::Isometry3d& pose, int threads) {
  if (&other == this)
    throw std::invalid_argument("rtog::OccupancyMap::fuse: a map fused with itself would count its evidence twice");
  checkRigid(pose);
  if (threads < 1) throw std::invalid_argument("rtog::OccupancyMap::fuse: threads must be at least 1");
  other.engine_->ensureCovered();
  MapEngine& e = *engine_;
  e.ensureCovered();
  const float l0 = other.logOddsModel().prior();
  const Eigen::Isometry3d inv = pose.inverse();
  InsertStats stats;
  GradedScan graded;
  other.forEachLeaf([&](const Box& box, float v) {
    markBox(e.store.lattice, other.lattice(), pose, inv, box, v - l0, graded, stats);
  });
  graded.finalize();
  std::vector<ApplyContext> contexts;
  applyGraded(e.store, {&graded}, stats, threads, contexts);
  return stats;
}

}  // namespace rtog
