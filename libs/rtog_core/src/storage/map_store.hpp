// What a map holds: its parameters, the lattice and log-odds model made from them, and the
// leaves with their index. Integration reads and writes it; queries read it.
#pragma once

#include "rtog/core/key.hpp"
#include "rtog/core/log_odds.hpp"
#include "rtog/core/params.hpp"
#include "storage/leaf_index.hpp"

namespace rtog {

struct MapStore {
  explicit MapStore(const MapParams& p)
      : params((p.validate(), p)), lattice(p.resolution), model(p.log_odds), index(p.rtree) {}

  /// True if leaves of value v may be merged into larger cuboids under the merge policy.
  bool mergeable(float v) const {
    switch (params.merge) {
      case MergePolicy::Off: return false;
      case MergePolicy::Clamped: return model.isClamped(v);
      default: return true;
    }
  }
  void clear() { index.clear(); }
  /// True if the map holds the cells of brick `b` (brick coordinates): every brick, unless the
  /// map is restricted to a region (OccupancyMap::setRegion).
  bool ownsBrick(const Key& b) const { return !restricted || region.contains(b); }
  std::string checkInvariants() const {
    return index.checkInvariants(model, [this](float v) { return mergeable(v); });
  }

  MapParams params;
  /// OccupancyMap::setRegion: the bricks (brick coordinates) whose cells the map holds.
  bool restricted = false;
  Box region = Box::empty();
  Lattice lattice;
  LogOddsModel model;
  LeafIndex index;
};

}  // namespace rtog
