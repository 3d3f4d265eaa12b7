// Graded scans of one z-layer (2D scans with range noise or pose blur) into the planar cache: the
// same union and the same update as the graded applier's (per cell the largest change, the miss
// masks or-ed), on the cached layer's values in place, covered with leaves when the map is next read.
#include <algorithm>
#include <utility>

#include "integrate/planar/planar_cache.hpp"
#include "kernels/layer_update.hpp"

namespace rtog {

bool gradedLayer(const std::vector<const GradedScan*>& scans, std::int32_t& z) {
  bool any = false;
  for (const GradedScan* s : scans) {
    for (std::size_t b = 0; b < s->brickCount(); ++b) {
      // The layer of the brick's first cell, then every cell in it.
      int local_z = -1;
      const GradedCell* cells = s->cells(b);
      for (std::size_t c = 0; c < s->cellCount(b); ++c) {
        const int cz = cells[c].local >> (2 * kBrickBits);
        if (local_z < 0) local_z = cz;
        if (cz != local_z) return false;
      }
      if (const BrickMask* miss = s->missMask(b)) {
        for (std::size_t w = 0; w < miss->size(); ++w) {
          if ((*miss)[w] == 0) continue;
          const int wz = static_cast<int>(w) / kLayerWords;  // a word holds cells of one layer
          if (local_z < 0) local_z = wz;
          if (wz != local_z) return false;
        }
      }
      if (local_z < 0) continue;
      const std::int32_t layer = s->brick(b).z * kBrickSize + local_z;
      if (any && layer != z) return false;
      z = layer, any = true;
    }
  }
  return any;
}

void PlanarCache::applyGradedLayer(MapStore& store, const std::vector<const GradedScan*>& scans, std::int32_t z,
                              InsertStats& stats) {
  const LogOddsModel& model = store.model;
  // The scans' bricks grouped, in Morton order (each scan's are ascending).
  std::vector<std::pair<std::uint64_t, std::pair<std::uint32_t, std::uint32_t>>> parts;
  for (std::uint32_t s = 0; s < scans.size(); ++s)
    for (std::uint32_t b = 0; b < scans[s]->brickCount(); ++b) parts.push_back({scans[s]->brickCode(b), {s, b}});
  std::stable_sort(parts.begin(), parts.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  // Each brick's cells of only the miss change go through the plain scans' layer kernel; the
  // graded ones (a band's few) one by one.
  const detail::UpdateLayerFn update_layer = detail::bestLayerUpdate();
  const float deltas[4] = {model.hitDelta(), model.missDelta(), model.clampMin(), model.clampMax()};
  constexpr LayerMask kNoCells{};
  detail::LayerCounts counts;
  std::array<float, kLayerCells> delta;
  const int first_word = (z & (kBrickSize - 1)) * kLayerWords;
  for (std::size_t p = 0; p < parts.size();) {
    const GradedScan& s0 = *scans[parts[p].second.first];
    const Key brick = s0.brick(parts[p].second.second);
    const std::uint64_t code = parts[p].first;
    if (!store.ownsBrick(brick)) {  // outside the map's region: passed over
      while (p < parts.size() && parts[p].first == code) ++p;
      continue;
    }
    LayerMask miss{}, graded{};
    for (; p < parts.size() && parts[p].first == code; ++p) {
      const GradedScan& s = *scans[parts[p].second.first];
      const std::uint32_t b = parts[p].second.second;
      if (const BrickMask* m = s.missMask(b))
        for (int w = 0; w < kLayerWords; ++w) miss[static_cast<std::size_t>(w)] |= (*m)[static_cast<std::size_t>(first_word + w)];
      const GradedCell* cells = s.cells(b);
      for (std::size_t c = 0; c < s.cellCount(b); ++c) {
        const int i = cells[c].local & (kLayerCells - 1);
        std::uint64_t& word = graded[static_cast<std::size_t>(i >> 6)];
        const std::uint64_t bit = std::uint64_t{1} << (i & 63);
        float& d = delta[static_cast<std::size_t>(i)];
        d = (word & bit) ? std::max(d, cells[c].delta) : cells[c].delta;
        word |= bit;
      }
    }
    PlanarLayer& layer = layerAt(store, brick, z);
    float* value = values(layer);
    LayerMask miss_only;
    for (std::size_t w = 0; w < miss.size(); ++w) miss_only[w] = miss[w] & ~graded[w];
    // Unknown cells hold the prior, so a first update is an update like any other.
    update_layer(value, layer.known.data(), kNoCells.data(), miss_only.data(), deltas, counts);
    for (std::size_t w = 0; w < graded.size(); ++w)
      for (std::uint64_t bits = graded[w]; bits; bits &= bits - 1) {
        const std::size_t i = w * 64 + static_cast<std::size_t>(__builtin_ctzll(bits));
        const std::uint64_t bit = std::uint64_t{1} << (i & 63);
        const float d = (miss[w] & bit) ? std::max(delta[i], model.missDelta()) : delta[i];
        (d > 0.0f ? stats.cells_occupied : stats.cells_free) += 1;
        const float v = model.update(value[i], d);
        if ((layer.known[w] & bit) && v == value[i]) ++stats.cells_unchanged;
        value[i] = v;
        layer.known[w] |= bit;
      }
  }
  stats.cells_unchanged += counts.unchanged;
  stats.cells_free += counts.free;
  stats.cells_occupied += counts.occupied;
}

}  // namespace rtog
