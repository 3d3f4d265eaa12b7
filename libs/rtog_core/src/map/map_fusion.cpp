// Fusion of another map into this one by the independent opinion pool (the estimator seed,
// section 3): P = P1 P2 / (P1 P2 + (1 - P1)(1 - P2)) with the prior P0 counted once, which in
// log-odds is l = l1 + l2 - l0, clamped. The other map's evidence enters as one update whose
// change in a cell is l2 - l0 of the other map's cell there, through the graded path that
// range-noise scans take: each cell once, brick by brick, the map independent of the threads.
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "integrate/batch_apply.hpp"
#include "integrate/graded_scan.hpp"
#include "map/map_engine.hpp"
#include "util/flat_hash_map.hpp"
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

/// The shift in cells that `pose` is, if the lattices are equal, the pose has no rotation and its
/// translation is a whole number of cells (exactly); none otherwise.
std::optional<std::array<std::int64_t, 3>> wholeCellShift(const Lattice& dst, const Lattice& src, const Eigen::Isometry3d& pose) {
  if (dst.resolution() != src.resolution() || !pose.linear().isIdentity(0.0)) return std::nullopt;
  std::array<std::int64_t, 3> shift{};
  for (int a = 0; a < 3; ++a) {
    const double c = pose.translation()[a] / dst.resolution();
    if (!(std::fabs(c) < 1e9) || c != std::round(c) || std::round(c) * dst.resolution() != pose.translation()[a])
      return std::nullopt;
    shift[std::size_t(a)] = static_cast<std::int64_t>(std::round(c));
  }
  return shift;
}

/// The cells of `dst` whose centres, taken back by `inv` into the other map, fall in `box` of
/// `src`: each given to `emit`. Identity or a shift by whole cells of equal lattices maps centres
/// to centres, so each cell of the box lands on exactly one cell.
template <class Emit>
void forEachCellOfBox(const Lattice& dst, const Lattice& src, const Eigen::Isometry3d& pose,
                      const Eigen::Isometry3d& inv, const Box& box, InsertStats& stats, Emit&& emit) {
  // Equal lattices and a shift by whole cells (the identity included: chunks of one log, maps of
  // one frame): each cell of the box is the cell moved by the shift, with no transform per cell.
  if (const auto shift = wholeCellShift(dst, src, pose)) {
    bool beyond = false;
    for (std::int64_t z = box.min.z; z <= box.max.z; ++z)
      for (std::int64_t y = box.min.y; y <= box.max.y; ++y)
        for (std::int64_t x = box.min.x; x <= box.max.x; ++x) {
          const std::int64_t kx = x + (*shift)[0], ky = y + (*shift)[1], kz = z + (*shift)[2];
          if (kx < kKeyMin || ky < kKeyMin || kz < kKeyMin || kx > kKeyMax || ky > kKeyMax || kz > kKeyMax) {
            beyond = true;
            continue;
          }
          emit(Key{static_cast<std::int32_t>(kx), static_cast<std::int32_t>(ky), static_cast<std::int32_t>(kz)});
        }
    if (beyond) ++stats.skipped_out_of_range;
    return;
  }
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
        if (src.tryKey(inv * dst.cellCenter(k), back) && box.contains(back)) emit(k);
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
  // The other map's leaves are disjoint: moved by a whole-cell shift, no cell is reached twice.
  const bool distinct = wholeCellShift(e.store.lattice, other.lattice(), pose).has_value();
  if (distinct) {
    std::size_t cells = 0;
    other.forEachLeaf([&](const Box& box, float) { cells += static_cast<std::size_t>(box.volume()); });
    graded.reserve(cells);
  }
  other.forEachLeaf([&](const Box& box, float v) {
    forEachCellOfBox(e.store.lattice, other.lattice(), pose, inv, box, stats, [&](const Key& k) {
      if (distinct)
        graded.markDistinct(k, v - l0);
      else
        graded.mark(k, v - l0);
    });
  });
  graded.finalize();
  std::vector<ApplyContext> contexts;
  applyGraded(e.store, {&graded}, stats, threads, contexts);
  return stats;
}

InsertStats OccupancyMap::fuse(const OccupancyMap& other, const std::vector<WeightedPose>& poses, int threads) {
  if (&other == this)
    throw std::invalid_argument("rtog::OccupancyMap::fuse: a map fused with itself would count its evidence twice");
  if (threads < 1) throw std::invalid_argument("rtog::OccupancyMap::fuse: threads must be at least 1");
  double total = 0.0;
  for (const WeightedPose& w : poses) {
    checkRigid(w.pose);
    if (!(std::isfinite(w.weight) && w.weight > 0.0))
      throw std::invalid_argument("rtog::OccupancyMap::fuse: each pose's weight must be finite and positive");
    total += w.weight;
  }
  if (poses.empty() || !(std::fabs(total - 1.0) < 1e-9))
    throw std::invalid_argument("rtog::OccupancyMap::fuse: the poses' weights must sum to 1");
  if (poses.size() == 1) return fuse(other, poses[0].pose, threads);
  other.engine_->ensureCovered();
  MapEngine& e = *engine_;
  e.ensureCovered();
  // Per cell of this map: the mixture over the poses of the other map's P(occupied) there, a pose
  // that leaves the cell outside the other map's known cells adding the prior (it says nothing).
  const float l0 = other.logOddsModel().prior();
  const double p0 = probability(l0);
  detail::FlatHashMap64 index;
  std::vector<Key> keys;
  std::vector<double> mass, weight;  // sum of w P over the poses that know the cell, and of w
  InsertStats stats;
  for (const WeightedPose& w : poses) {
    const Eigen::Isometry3d inv = w.pose.inverse();
    other.forEachLeaf([&](const Box& box, float v) {
      const double p = probability(v);
      forEachCellOfBox(e.store.lattice, other.lattice(), w.pose, inv, box, stats, [&](const Key& k) {
        const auto i = static_cast<std::uint32_t>(keys.size());
        const std::uint32_t at = index.findOrInsert(packKey(k), i);
        if (at == i) keys.push_back(k), mass.push_back(0.0), weight.push_back(0.0);
        mass[at] += w.weight * p;
        weight[at] += w.weight;
      });
    });
  }
  GradedScan graded;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const double p = std::min(std::max(mass[i] + (1.0 - weight[i]) * p0, 1e-12), 1.0 - 1e-12);
    graded.mark(keys[i], static_cast<float>(logit(p)) - l0);
  }
  graded.finalize();
  std::vector<ApplyContext> contexts;
  applyGraded(e.store, {&graded}, stats, threads, contexts);
  return stats;
}

}  // namespace rtog
