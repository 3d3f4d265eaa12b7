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
  std::string checkInvariants() const {
    return index.checkInvariants(model, [this](float v) { return mergeable(v); });
  }

  MapParams params;
  Lattice lattice;
  LogOddsModel model;
  LeafIndex index;
};

}  // namespace rtog
