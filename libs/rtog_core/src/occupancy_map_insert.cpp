// Insertion: beams -> per-scan update batch -> one sweep over the touched bricks.
#include <algorithm>

#include "rtog/core/occupancy_map.hpp"
#include "rtog/core/ray_traversal.hpp"

namespace rtog {

InsertStats OccupancyMap::insertPointCloud(const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                                           std::size_t count, const InsertParams& ip, const std::uint8_t* is_hit) {
  InsertStats stats;
  UpdateBatch batch;
  computeUpdate(origin, points, count, ip, is_hit, batch, stats);
  batch.finalize();
  applyUpdate(batch, stats);
  return stats;
}

void OccupancyMap::computeUpdate(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                                 const InsertParams& ip, const std::uint8_t* is_hit, UpdateBatch& batch,
                                 InsertStats& stats) const {
  const Key origin_key = lattice_.key(origin);  // throws for a bad origin
  const Eigen::Vector3d origin_l = lattice_.toLattice(origin);
  const bool limited = ip.max_range > 0.0 && std::isfinite(ip.max_range);
  const bool trace = ip.model == SensorModel::BeamBased;
  for (std::size_t i = 0; i < count; ++i) {
    const Eigen::Vector3d p = points[i].cast<double>();
    if (!p.allFinite()) {
      ++stats.skipped_non_finite;
      continue;
    }
    const Eigen::Vector3d diff = p - origin;
    const double dist = diff.norm();
    if (!(dist > 0.0)) {
      ++stats.skipped_zero_length;
      continue;
    }
    bool hit = is_hit == nullptr || is_hit[i] != 0;
    Eigen::Vector3d end = p;
    if (limited && dist > ip.max_range) {
      end = origin + diff * (ip.max_range / dist);
      hit = false;
    }
    Key end_key;
    if (!lattice_.tryKey(end, end_key)) {
      ++stats.skipped_out_of_range;
      continue;
    }
    ++(hit ? stats.rays_hit : stats.rays_truncated);
    if (trace)
      traverseRay(origin_l, lattice_.toLattice(end), origin_key, end_key, [&](const Key& k) { batch.markFree(k); });
    if (hit) batch.markOccupied(end_key);
  }
}

void OccupancyMap::applyUpdate(const UpdateBatch& batch, InsertStats& stats) {
  stats.cells_occupied += batch.occupiedCount();
  stats.cells_free += batch.freeCount();
  for (const auto& upd : batch.bricks()) applyBrick(upd, stats);
}

namespace {

// Cuts `box` (brick-local, inclusive) around `cell` into at most six boxes that cover
// box minus cell: x-slabs first, then y-rows, then z-runs.
int cutAround(const std::uint8_t lo[3], const std::uint8_t hi[3], const Key& cell, std::uint8_t out_lo[6][3],
              std::uint8_t out_hi[6][3]) {
  int n = 0;
  std::uint8_t cur_lo[3] = {lo[0], lo[1], lo[2]}, cur_hi[3] = {hi[0], hi[1], hi[2]};
  for (int a = 0; a < 3; ++a) {
    const auto c = static_cast<std::uint8_t>(cell[a]);
    if (c > cur_lo[a]) {
      std::copy(cur_lo, cur_lo + 3, out_lo[n]);
      std::copy(cur_hi, cur_hi + 3, out_hi[n]);
      out_hi[n][a] = static_cast<std::uint8_t>(c - 1);
      ++n;
    }
    if (c < cur_hi[a]) {
      std::copy(cur_lo, cur_lo + 3, out_lo[n]);
      std::copy(cur_hi, cur_hi + 3, out_hi[n]);
      out_lo[n][a] = static_cast<std::uint8_t>(c + 1);
      ++n;
    }
    cur_lo[a] = cur_hi[a] = c;
  }
  return n;
}

inline int localIdx(int x, int y, int z) { return x | (y << kBrickBits) | (z << (2 * kBrickBits)); }

template <class Fn>
void forEachLocal(const std::uint8_t lo[3], const std::uint8_t hi[3], Fn&& fn) {
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int x = lo[0]; x <= hi[0]; ++x) fn(localIdx(x, y, z));
}

}  // namespace

void OccupancyMap::applyBrick(const UpdateBatch::BrickUpdates& upd, InsertStats& stats) {
  const std::uint32_t slot = brickSlot(upd.brick);
  Brick& br = bricks_[slot];
  std::vector<std::int32_t>& local = local_;
  for (std::size_t i = 0; i < br.leaves.size(); ++i)
    forEachLocal(br.leaves[i].lo, br.leaves[i].hi, [&](int idx) { local[idx] = static_cast<std::int32_t>(i); });

  const Key origin = brickOrigin(upd.brick);
  const bool merging = params_.merge != MergePolicy::Off;
  std::vector<std::uint32_t> candidates;
  for (int w = 0; w < kBrickWords; ++w) {
    std::uint64_t bits = upd.occupied[w] | upd.free[w];
    while (bits) {
      const int b = __builtin_ctzll(bits);
      bits &= bits - 1;
      const int idx = w * 64 + b;
      const float delta = (upd.occupied[w] >> b) & 1u ? model_.hitDelta() : model_.missDelta();
      const Key lk = localKey(idx);
      const std::int32_t li = local[idx];
      if (li < 0) {
        const float v = model_.first(delta);
        const Key k{origin.x + lk.x, origin.y + lk.y, origin.z + lk.z};
        const Handle h = tree_.insert(Box::cell(k), v);
        const auto x = static_cast<std::uint8_t>(lk.x), y = static_cast<std::uint8_t>(lk.y),
                   z = static_cast<std::uint8_t>(lk.z);
        br.leaves.push_back(BrickLeaf{{x, y, z}, {x, y, z}, h});
        local[idx] = static_cast<std::int32_t>(br.leaves.size() - 1);
        ++stats.leaves_created;
        if (merging && mergeable(v)) candidates.push_back(static_cast<std::uint32_t>(br.leaves.size() - 1));
        continue;
      }
      const BrickLeaf leaf = br.leaves[li];
      const float old = tree_.payload(leaf.handle);
      const float v = model_.update(old, delta);
      if (v == old) {
        ++stats.cells_unchanged;
        continue;
      }
      tree_.payload(leaf.handle) = v;
      if (merging && mergeable(v)) candidates.push_back(static_cast<std::uint32_t>(li));
      if (leaf.lo[0] == leaf.hi[0] && leaf.lo[1] == leaf.hi[1] && leaf.lo[2] == leaf.hi[2]) continue;

      // Disagreeing evidence inside a merged cuboid: the leaf shrinks to the updated cell
      // and the rest of its cells keep the old value in at most six new leaves.
      std::uint8_t plo[6][3], phi[6][3];
      const int pieces = cutAround(leaf.lo, leaf.hi, lk, plo, phi);
      BrickLeaf& shrunk = br.leaves[li];
      for (int a = 0; a < 3; ++a) shrunk.lo[a] = shrunk.hi[a] = static_cast<std::uint8_t>(lk[a]);
      tree_.updateBox(leaf.handle, globalBox(br, shrunk));
      for (int p = 0; p < pieces; ++p) {
        BrickLeaf piece{{plo[p][0], plo[p][1], plo[p][2]}, {phi[p][0], phi[p][1], phi[p][2]}, kNoHandle};
        piece.handle = tree_.insert(globalBox(br, piece), old);
        br.leaves.push_back(piece);
        const auto pi = static_cast<std::int32_t>(br.leaves.size() - 1);
        forEachLocal(piece.lo, piece.hi, [&](int i) { local[i] = pi; });
        candidates.push_back(static_cast<std::uint32_t>(pi));  // was merged, so mergeable
      }
      ++stats.leaves_split;
      stats.leaves_created += static_cast<std::size_t>(pieces);
    }
  }

  if (merging && !candidates.empty()) mergeInBrick(br, local, candidates, stats);

  // Drop the leaves merged away and leave the scratch map empty for the next brick.
  br.leaves.erase(std::remove_if(br.leaves.begin(), br.leaves.end(),
                                 [](const BrickLeaf& l) { return l.handle == kNoHandle; }),
                  br.leaves.end());
  std::fill(local.begin(), local.end(), -1);
}

void OccupancyMap::mergeInBrick(Brick& br, std::vector<std::int32_t>& local, std::vector<std::uint32_t>& candidates,
                                InsertStats& stats) {
  for (const std::uint32_t i : candidates) {
    for (bool merged = true; merged;) {
      merged = false;
      BrickLeaf& a = br.leaves[i];
      if (a.handle == kNoHandle) break;
      const float v = tree_.payload(a.handle);
      if (!mergeable(v)) break;
      for (int axis = 0; axis < 3 && !merged; ++axis) {
        const int b1 = (axis + 1) % 3, b2 = (axis + 2) % 3;
        for (int dir = 1; dir >= -1 && !merged; dir -= 2) {
          const int c = dir > 0 ? a.hi[axis] + 1 : a.lo[axis] - 1;
          if (c < 0 || c >= kBrickSize) continue;
          int n[3] = {a.lo[0], a.lo[1], a.lo[2]};
          n[axis] = c;
          const std::int32_t j = local[localIdx(n[0], n[1], n[2])];
          if (j < 0 || static_cast<std::uint32_t>(j) == i) continue;
          BrickLeaf& nb = br.leaves[j];
          // A face neighbour holding the cell next to a's corner starts right after a on
          // this axis (leaves are disjoint); it merges if its face matches exactly.
          if (nb.lo[b1] != a.lo[b1] || nb.hi[b1] != a.hi[b1] || nb.lo[b2] != a.lo[b2] || nb.hi[b2] != a.hi[b2])
            continue;
          if (tree_.payload(nb.handle) != v) continue;
          a.lo[axis] = std::min(a.lo[axis], nb.lo[axis]);
          a.hi[axis] = std::max(a.hi[axis], nb.hi[axis]);
          forEachLocal(nb.lo, nb.hi, [&](int idx) { local[idx] = static_cast<std::int32_t>(i); });
          tree_.remove(nb.handle);
          nb.handle = kNoHandle;
          tree_.updateBox(a.handle, globalBox(br, a));
          ++stats.leaves_merged;
          merged = true;
        }
      }
    }
  }
}

}  // namespace rtog
