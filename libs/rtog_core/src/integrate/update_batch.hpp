// The per-scan update set: which cells a scan saw free and which occupied, each at most
// once, occupied winning over free (as OctoMap's computeUpdate), grouped by brick.
#pragma once

#include <array>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <vector>

#include "kernels/lane_walk.hpp"
#include "rtog/core/key.hpp"
#include "rtog/core/ray_traversal.hpp"
#include "storage/brick.hpp"
#include "util/chunked_vector.hpp"
#include "util/flat_hash_map.hpp"

namespace rtog {

// Cache-line aligned: per-thread batches sit side by side and are written on every brick change.
class alignas(64) UpdateBatch {
 public:
  struct BrickUpdates {
    Key brick;                                        ///< brick coordinates (key >> kBrickBits)
    std::array<std::uint64_t, kBrickWords> occupied;  ///< bit per local cell index
    std::array<std::uint64_t, kBrickWords> free;
    bool any_occupied;  ///< some bit of `occupied` is set
  };

  /// A ray queued by queueRayFree().
  using QueuedRay = detail::QueuedRay;

  UpdateBatch() = default;
  // Scratch kept between scans: a copied map starts with an empty batch.
  UpdateBatch(const UpdateBatch&) {}
  UpdateBatch& operator=(const UpdateBatch& other) {
    if (this != &other) clear();
    return *this;
  }
  UpdateBatch(UpdateBatch&&) = default;
  UpdateBatch& operator=(UpdateBatch&&) = default;

  void clear();
  /// Marks the cells of traverseRay(from, to, from_key, to_key) free.
  void markRayFree(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key, const Key& to_key);
  /// markRayFree, perhaps later: where the CPU has a lane walk (detail::laneKernel()), a ray that
  /// leaves its z-layer and spans under kLaneReach cells waits in a queue, to be walked with
  /// others eight or sixteen at a time (finalize() walks what is left); others are walked at
  /// once. The marks are the same.
  /// Inline: called for every beam of a scan.
  void queueRayFree(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key, const Key& to_key) {
    // Long rays would need a window too large to sweep (LiDAR rays reach thousands of cells);
    // walked at once, they also find the bricks their end points were just marked in.
    const auto reach = [&](int a) { return std::abs(std::int64_t{to_key[a]} - from_key[a]); };
    if (lanes_ == detail::LaneKernel::None || from_key.z == to_key.z || reach(0) >= kLaneReach ||
        reach(1) >= kLaneReach || reach(2) >= kLaneReach / 2) {
      markRayFree(from, to, from_key, to_key);
      return;
    }
    // The whole queue at once: grown by doubling, it would be copied into fresh memory again
    // and again.
    if (queued_.capacity() < kQueuedRays) queued_.reserve(kQueuedRays);
    queued_.push_back(QueuedRay{from, to, from_key, to_key});
    if (queued_.size() == kQueuedRays) walkQueued();
  }
  static constexpr std::int32_t kLaneReach = 240;
  /// Walks the queued rays now, in lanes if `wide`, else one by one.
  void walkQueued(bool wide = true);
  /// The lane walk this batch uses from now on (tests and benchmarks compare them; the default
  /// is detail::laneKernel()); false, and no change, if this CPU cannot run it.
  bool useLaneKernel(detail::LaneKernel kernel);
  /// Returns false if the cell was already marked occupied in this batch.
  bool markOccupied(const Key& k) {
    const int i = localIndex(k);
    BrickUpdates& b = brickFor(k);
    std::uint64_t& w = b.occupied[static_cast<std::size_t>(i >> 6)];
    const std::uint64_t bit = std::uint64_t{1} << (i & 63);
    const bool fresh = (w & bit) == 0;
    w |= bit;
    b.any_occupied = true;
    return fresh;
  }

  /// Drops free marks of cells also marked occupied and orders bricks by the Morton code of
  /// their keys, so that applying the batch is deterministic and the bricks a first scan brings
  /// get their map slots in the order the upper tree is packed in. Ends marking; clear() starts
  /// a new batch.
  void finalize();
  /// The bricks marked so far (each kBrickWords * 16 bytes and more).
  std::size_t brickCount() const { return packed_keys_.size(); }

  /// The touched bricks in Morton order, after finalize().
  const std::vector<const BrickUpdates*>& bricks() const { return sorted_; }
  /// Their keys, in the same order.
  const std::vector<Key>& brickKeys() const { return sorted_keys_; }
  /// Their keys' Morton codes, ascending.
  const std::vector<std::uint64_t>& brickCodes() const { return sorted_codes_; }
  std::size_t memoryBytes() const {
    return bricks_.capacity() * sizeof(BrickUpdates) + index_.memoryBytes() +
           packed_keys_.capacity() * sizeof(std::uint64_t) +
           order_scratch_.capacity() * sizeof(std::pair<std::uint64_t, std::uint32_t>) +
           sorted_.capacity() * sizeof(void*) + sorted_keys_.capacity() * sizeof(Key) +
           sorted_codes_.capacity() * sizeof(std::uint64_t) + queued_.capacity() * sizeof(QueuedRay) +
           lane_rays_.capacity() * sizeof(std::uint32_t) + window_.capacity() * sizeof(std::uint64_t) +
           touched_.capacity() + (brick_slots_.capacity() + slotted_.capacity()) * sizeof(std::uint32_t);
  }

 private:
  BrickUpdates& brickFor(const Key& k) {
    const Key b = brickOf(k);
    if (cached_ == nullptr || b != cached_->brick) {
      // The hash outgrows the cache on a long-range scan.
      cached_ = &brickAt(recent_.get(packKey(b), [&] { return brickSlot(b); }));
    }
    return *cached_;
  }
  std::uint32_t brickSlot(const Key& b);
  static constexpr std::size_t kQueuedRays = 8192;
  /// Walks queued_[i] for each i of `lanes` into a dense window of bricks, then or-s the window
  /// into the batch. Keeps in `lanes` only the rays the window holds (near the first one's start
  /// if all would not fit); false if it walked none.
  bool walkInWindow(std::vector<std::uint32_t>& lanes);
  BrickUpdates& brickAt(std::uint32_t slot) { return bricks_[slot]; }
  // Bricks live in fixed chunks kept from batch to batch: no copying as a batch grows, stable
  // addresses, and a new scan does not fault its memory in again.
  detail::ChunkedVector<BrickUpdates, 256> bricks_;
  detail::FlatHashMap64 index_;
  BrickUpdates* cached_ = nullptr;
  detail::RecentLookups<9> recent_;  // packed brick key -> slot
  std::vector<const BrickUpdates*> sorted_;
  std::vector<Key> sorted_keys_;
  std::vector<std::uint64_t> sorted_codes_;
  std::vector<std::uint64_t> packed_keys_;  // of each brick slot; its size is the brick count
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order_scratch_;  // finalize(): Morton code, slot
  std::vector<QueuedRay> queued_;
  std::vector<std::uint32_t> lane_rays_;  // walkQueued(): the queued rays the window takes
  std::vector<std::uint32_t> wave_order_;  // walkInWindow(): lane_rays_ as the lanes take them
  std::vector<std::uint8_t> wave_shared_;  // walkInWindow(): per block of wave_order_, see orderForWaves
  std::vector<std::uint64_t> window_;     // walkInWindow(): 64 words a brick, zero between walks
  std::vector<std::uint8_t> touched_;     // walkInWindow(): a flag a run of kBrickWords window words
  static constexpr std::uint32_t kNoSlot = 0xffffffffu;
  std::vector<std::uint32_t> brick_slots_;  // walkInWindow(): a window brick's slot, or kNoSlot
  std::vector<std::uint32_t> slotted_;      // walkInWindow(): the window bricks given a slot
  detail::LaneKernel lanes_ = detail::laneKernel();  // asked once: queueRayFree() asks for every ray
};

}  // namespace rtog
