// The fusion integrator (fusion_integrator.hpp).
#include "integrate/fusion_integrator.hpp"

#include <algorithm>
#include <array>
#include <utility>

#include "integrate/fusion_resample.hpp"
#include "integrate/insert_scratch.hpp"
#include "rtog/core/mixture.hpp"
#include "parallel/parallel.hpp"
#include "storage/map_store.hpp"
#include "util/flat_hash_map.hpp"

namespace rtog {
namespace {

/// The cells of `box` of `src` moved by a whole-cell shift of an equal lattice: each to `emit`, with
/// no transform per cell; those beyond the keys are left out, the box counted once.
template <class Emit>
void shiftedCells(const std::array<std::int64_t, 3>& shift, const Box& box, InsertStats& stats, Emit&& emit) {
  bool beyond = false;
  for (std::int64_t z = box.min.z; z <= box.max.z; ++z)
    for (std::int64_t y = box.min.y; y <= box.max.y; ++y)
      for (std::int64_t x = box.min.x; x <= box.max.x; ++x) {
        const std::int64_t kx = x + shift[0], ky = y + shift[1], kz = z + shift[2];
        if (kx < kKeyMin || ky < kKeyMin || kz < kKeyMin || kx > kKeyMax || ky > kKeyMax || kz > kKeyMax) {
          beyond = true;
          continue;
        }
        emit(Key{static_cast<std::int32_t>(kx), static_cast<std::int32_t>(ky), static_cast<std::int32_t>(kz)});
      }
  if (beyond) ++stats.skipped_out_of_range;
}

/// `other`'s evidence (l - l0 per cell) placed by `pose` and resampled into `dst`, conserved: the
/// one rule of both fusions (fusion_resample.hpp). The leaves go in blocks of a fixed size, each
/// summed apart (by the threads, a wave at a time), the blocks' sums added in block order: the
/// same sums in the same order for any thread count.
ResampledEvidence resample(const OccupancyMap& other, const Lattice& dst, const Eigen::Isometry3d& pose, float l0,
                           int threads, InsertStats& stats) {
  constexpr std::size_t kBlock = kResampleBlock;
  std::vector<std::pair<Box, float>> leaves;
  other.forEachLeaf([&](const Box& box, float v) { leaves.emplace_back(box, v); });
  const Placement place(dst, other.lattice(), pose);
  const std::size_t blocks = (leaves.size() + kBlock - 1) / kBlock;
  const std::size_t wave = std::max<std::size_t>(1, std::min<std::size_t>(static_cast<std::size_t>(threads), blocks));
  std::vector<ResampledEvidence> part(wave);
  std::vector<std::size_t> skipped(wave);
  ResampledEvidence out;
  for (std::size_t first = 0; first < blocks; first += wave) {
    const std::size_t n = std::min(wave, blocks - first);
    const auto run = [&](std::size_t t) {
      part[t].clear();
      InsertStats st;
      const std::size_t end = std::min(leaves.size(), (first + t + 1) * kBlock);
      for (std::size_t i = (first + t) * kBlock; i < end; ++i) {
        const double d = static_cast<double>(leaves[i].second - l0);
        place.overlaps(leaves[i].first, st, [&](const Key& k, double volume) { part[t].add(k, d * volume); });
      }
      skipped[t] = st.skipped_out_of_range;
    };
    if (n == 1)
      run(0);
    else
      parallel::run(n, run);
    for (std::size_t t = 0; t < n; ++t) {
      for (std::size_t j = 0; j < part[t].keys().size(); ++j) out.add(part[t].keys()[j], part[t].sums()[j]);
      stats.skipped_out_of_range += skipped[t];
    }
  }
  return out;
}

/// The scratch's first graded scan, cleared: fusion's one update.
GradedScan& fusionScan(InsertScratch& scratch) {
  if (scratch.graded.empty()) scratch.graded.resize(1);
  scratch.graded[0].clear();
  return scratch.graded[0];
}

/// The finalized scan as fusion's update set.
UpdateSet fusionSet(GradedScan& graded, const InsertStats& stats, int threads) {
  graded.finalize();
  UpdateSet set = UpdateSet::nothing(UpdateSet::Kind::Graded, stats);
  set.graded.push_back(&graded);
  set.threads = threads;
  return set;
}

}  // namespace

UpdateSet FusionIntegrator::trace(const OccupancyMap& other, const Eigen::Isometry3d& pose, int threads) {
  const float l0 = other.logOddsModel().prior();
  const Lattice& lattice = ctx_.store.lattice;
  InsertStats stats;
  GradedScan& graded = fusionScan(ctx_.scratch);
  if (const auto shift = wholeCellShift(lattice, other.lattice(), pose)) {
    // Chunks of one log, maps of one frame: the leaves are disjoint and the shift one-to-one, so
    // each cell is reached once.
    other.forEachLeaf([&](const Box& box, float v) {
      shiftedCells(*shift, box, stats, [&](const Key& k) { graded.mark(k, v - l0); });
    });
  } else {
    const ResampledEvidence r = resample(other, lattice, pose, l0, threads, stats);
    for (std::size_t i = 0; i < r.keys().size(); ++i) graded.mark(r.keys()[i], static_cast<float>(r.sums()[i]));
  }
  return fusionSet(graded, stats, threads);
}

UpdateSet FusionIntegrator::trace(const OccupancyMap& other, const std::vector<OccupancyMap::WeightedPose>& poses,
                                  int threads) {
  if (poses.size() == 1) return trace(other, poses[0].pose, threads);
  // Per cell of this map: the mixture over the poses of the other map's P(occupied) there, a pose
  // that leaves the cell outside the other map's known cells adding the prior (it says nothing).
  const float l0 = other.logOddsModel().prior();
  const ProbabilityMixture mixture(l0);
  detail::FlatHashMap64 index;
  std::vector<Key> keys;
  std::vector<double> sum;  // of the poses' terms w (P_i - P0), in pose order
  InsertStats stats;
  for (const OccupancyMap::WeightedPose& w : poses) {
    // The other map under this pose, resampled as by the plain fusion: P_i = P(l0 + evidence).
    const ResampledEvidence r = resample(other, ctx_.store.lattice, w.pose, l0, threads, stats);
    for (std::size_t j = 0; j < r.keys().size(); ++j) {
      const auto i = static_cast<std::uint32_t>(keys.size());
      const std::uint32_t at = index.findOrInsert(packKey(r.keys()[j]), i);
      if (at == i) keys.push_back(r.keys()[j]), sum.push_back(0.0);
      sum[at] += mixture.term(w.weight, r.sums()[j]);
    }
  }
  GradedScan& graded = fusionScan(ctx_.scratch);
  for (std::size_t i = 0; i < keys.size(); ++i) graded.mark(keys[i], mixture.change(sum[i]));
  return fusionSet(graded, stats, threads);
}

}  // namespace rtog
