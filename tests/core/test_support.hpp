// Shared by the core tests: the bundled real data and a straightforward reference grid.
#pragma once

#include <gtest/gtest.h>

#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "rtog/core/occupancy_map.hpp"
#include "rtog/core/ray_traversal.hpp"
#include "rtog/image/tum_dataset.hpp"

namespace rtog::test {

inline std::vector<image::WorldScan> loadTumScans(int stride) {
  const image::DepthSequence seq = image::readTumSequence(RTOG_TEST_TUM_DIR);
  std::vector<image::WorldScan> scans;
  for (const auto& f : seq.frames) scans.push_back(image::loadDepthScan(f, seq.intrinsics, stride));
  return scans;
}

/// The map's semantics written the plain way: a hash map of cells, each scan's free and
/// occupied cell sets de-duplicated, occupied winning, then l += l_meas - l0, clamped.
class ReferenceGrid {
 public:
  explicit ReferenceGrid(const MapParams& p) : lattice_(p.resolution), model_(p.log_odds) {}

  void insert(const Eigen::Vector3d& origin, const std::vector<Eigen::Vector3f>& points, const InsertParams& ip) {
    std::unordered_set<Key, KeyHash> free, occupied;
    const Key ok = lattice_.key(origin);
    for (const Eigen::Vector3f& pf : points) {
      const Eigen::Vector3d p = pf.cast<double>();
      if (!p.allFinite() || (p - origin).norm() == 0.0) continue;
      Eigen::Vector3d end = p;
      bool hit = true;
      const double dist = (p - origin).norm();
      if (ip.max_range > 0 && dist > ip.max_range) {
        end = origin + (p - origin) * (ip.max_range / dist);
        hit = false;
      }
      Key ek;
      if (!lattice_.tryKey(end, ek)) continue;
      Eigen::Vector3d end_l = lattice_.toLattice(end);
      if (ip.discretize) {
        // Beams go to the centre of their end cell, and only the first beam to a cell counts.
        if (hit && occupied.count(ek)) continue;
        end_l = Eigen::Vector3d(ek.x + 0.5, ek.y + 0.5, ek.z + 0.5);
      }
      if (ip.model == SensorModel::BeamBased)
        traverseRay(lattice_.toLattice(origin), end_l, ok, ek, [&](const Key& k) { free.insert(k); });
      if (hit) occupied.insert(ek);
    }
    for (const Key& k : free)
      if (!occupied.count(k)) update(k, model_.missDelta());
    for (const Key& k : occupied) update(k, model_.hitDelta());
  }

  const std::unordered_map<Key, float, KeyHash>& cells() const { return cells_; }

 private:
  void update(const Key& k, float delta) {
    auto it = cells_.find(k);
    float v = (it == cells_.end() ? model_.prior() : it->second) + delta;
    v = std::min(std::max(v, model_.clampMin()), model_.clampMax());
    cells_[k] = v;
  }

  Lattice lattice_;
  LogOddsModel model_;
  std::unordered_map<Key, float, KeyHash> cells_;
};

/// Every cell of the map equals the reference: same set of known cells, same log-odds
/// bit for bit when `exact`, else the same occupied/free class.
inline void expectMatchesReference(const OccupancyMap& map, const ReferenceGrid& ref, bool exact) {
  std::int64_t cells = 0, mismatches = 0;
  map.forEachLeaf([&](const Box& b, float v) {
    forEachCell(b, [&](const Key& k) {
      ++cells;
      const auto it = ref.cells().find(k);
      if (it == ref.cells().end()) {
        ++mismatches;
        return;
      }
      const auto& m = map.logOddsModel();
      if (exact ? (it->second != v) : (m.classify(it->second) != m.classify(v))) ++mismatches;
    });
  });
  EXPECT_EQ(cells, static_cast<std::int64_t>(ref.cells().size())) << "known-cell count differs";
  EXPECT_EQ(mismatches, 0) << "cells differing from the reference";
}

}  // namespace rtog::test
