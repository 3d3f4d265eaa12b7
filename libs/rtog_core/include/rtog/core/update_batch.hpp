// The per-scan update set: which cells a scan saw free and which occupied, each at most
// once, occupied winning over free (as OctoMap's computeUpdate), grouped by brick.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "rtog/core/detail/flat_hash_map.hpp"
#include "rtog/core/key.hpp"
#include "rtog/core/ray_traversal.hpp"

namespace rtog {

/// Bricks are aligned cubes of kBrickSize^3 cells. They group updates and bound leaf
/// cuboids so that one scan's changes stay local.
constexpr int kBrickBits = 4;
constexpr int kBrickSize = 1 << kBrickBits;
constexpr int kBrickCells = kBrickSize * kBrickSize * kBrickSize;
constexpr int kBrickWords = kBrickCells / 64;
/// A brick's z-layer: kBrickSize^2 cells, local indices z * kLayerCells + (0 .. kLayerCells).
constexpr int kLayerCells = kBrickSize * kBrickSize;
constexpr int kLayerWords = kLayerCells / 64;

inline Key brickOf(const Key& k) {
  // Arithmetic shift: floor division for negative keys too.
  return Key{k.x >> kBrickBits, k.y >> kBrickBits, k.z >> kBrickBits};
}
inline Key brickOrigin(const Key& brick) {
  return Key{brick.x * kBrickSize, brick.y * kBrickSize, brick.z * kBrickSize};
}
inline int localIndex(const Key& k) {
  constexpr int m = kBrickSize - 1;
  return (k.x & m) | ((k.y & m) << kBrickBits) | ((k.z & m) << (2 * kBrickBits));
}
inline Key localKey(int index) {
  constexpr int m = kBrickSize - 1;
  return Key{index & m, (index >> kBrickBits) & m, (index >> (2 * kBrickBits)) & m};
}

inline std::size_t popcount64(std::uint64_t w) {
  // SWAR count: the baseline x86-64 target has no POPCNT instruction.
  w = w - ((w >> 1) & 0x5555555555555555ull);
  w = (w & 0x3333333333333333ull) + ((w >> 2) & 0x3333333333333333ull);
  w = (w + (w >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return static_cast<std::size_t>((w * 0x0101010101010101ull) >> 56);
}

inline std::size_t maskPopcount(const std::array<std::uint64_t, kBrickWords>& words) {
  std::size_t n = 0;
  for (const std::uint64_t w : words) n += popcount64(w);
  return n;
}

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
  struct QueuedRay {
    Eigen::Vector3d from, to;
    Key from_key, to_key;
  };

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
  /// markRayFree, perhaps later: where the CPU has AVX2, a ray that leaves its z-layer and spans
  /// under kLaneReach cells waits in a queue, to be walked with others eight at a time
  /// (finalize() walks what is left); others are walked at once. The marks are the same.
  void queueRayFree(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key, const Key& to_key);
  static constexpr std::int32_t kLaneReach = 240;
  /// Walks the queued rays now, with AVX2 if `wide` and the CPU has it, else one by one.
  void walkQueued(bool wide = true);
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

  /// The touched bricks in Morton order, after finalize().
  const std::vector<const BrickUpdates*>& bricks() const { return sorted_; }
  /// Their keys, in the same order.
  const std::vector<Key>& brickKeys() const { return sorted_keys_; }
  /// Their keys' Morton codes, ascending.
  const std::vector<std::uint64_t>& brickCodes() const { return sorted_codes_; }
  std::size_t memoryBytes() const {
    return chunks_.size() * sizeof(Chunk) + chunks_.capacity() * sizeof(void*) + index_.memoryBytes() +
           packed_keys_.capacity() * sizeof(std::uint64_t) +
           order_scratch_.capacity() * sizeof(std::pair<std::uint64_t, std::uint32_t>) +
           sorted_.capacity() * sizeof(void*) + sorted_keys_.capacity() * sizeof(Key) +
           sorted_codes_.capacity() * sizeof(std::uint64_t) + queued_.capacity() * sizeof(QueuedRay) +
           lane_rays_.capacity() * sizeof(std::uint32_t) + window_.capacity() * sizeof(std::uint64_t) +
           touched_.capacity();
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
  BrickUpdates& brickAt(std::uint32_t slot) { return (*chunks_[slot / kChunkBricks])[slot % kChunkBricks]; }
  // Bricks live in fixed chunks kept from batch to batch: no copying as a batch grows, stable
  // addresses, and a new scan does not fault its memory in again.
  static constexpr std::size_t kChunkBricks = 256;
  using Chunk = std::array<BrickUpdates, kChunkBricks>;
  std::vector<std::unique_ptr<Chunk>> chunks_;
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
  std::vector<std::uint64_t> window_;     // walkInWindow(): 64 words a brick, zero between walks
  std::vector<std::uint8_t> touched_;     // walkInWindow(): a flag a brick of the window
};

/// A beam of a planar scan in the exact form a PlanarBatch walks.
struct PlanarBeam {
  PlanarSegment seg;
  Key end;
  bool traced = false;          ///< false for a beam skipped as bad input
  bool hit = false;
  std::int64_t skip_runs = 0;  ///< leading runs other beams of the scan are known to mark
};

/// For the beams of one scan from one origin (one start cell and one rounded start point), in
/// the order of a scanner's sweep: sets each beam's skip_runs so that marking every beam
/// without its skipped runs marks the same cells as the full walks.
/// Beams closer in angle than a cell's width near the origin cross the same cells there, so
/// beam i (i = odd * 2^k) leaves out the cells within the radius where, between beams i - 2^k
/// and i + 2^k, no cell fits that neither crosses; those two have larger k, so by induction
/// the cells they leave out are marked by others. Beams out of sweep order are walked whole.
void fanSkipRuns(PlanarBeam* beams, std::size_t count);

/// The update set of a planar scan, whose cells all lie in one z-layer: the layer masks of the
/// bricks under the scan's bounding box in a dense grid, found by arithmetic instead of a hash.
class PlanarBatch {
 public:
  struct Tile {
    std::array<std::uint64_t, kLayerWords> occupied, free;  ///< bit (y % 16) * 16 + x % 16
  };
  /// Free marks of walks that step more along y, transposed: bit (x % 16) * 16 + y % 16, so that
  /// a run in a column is one mask in one word, as a run in a row is in a Tile.
  struct ColumnTile {
    std::array<std::uint64_t, kLayerWords> free;
  };
  /// Bricks a batch over cells [lo, hi] (x and y) would hold.
  static std::size_t tilesFor(const Key& lo, const Key& hi) {
    return static_cast<std::size_t>((hi.x >> kBrickBits) - (lo.x >> kBrickBits) + 1) *
           static_cast<std::size_t>((hi.y >> kBrickBits) - (lo.y >> kBrickBits) + 1);
  }
  /// Starts an empty batch over cells [lo, hi]; z is not looked at.
  void reset(const Key& lo, const Key& hi);
  bool markOccupied(const Key& k) {
    const int i = bitOf(k.x, k.y);
    std::uint64_t& w = tileOf(k.x, k.y).occupied[static_cast<std::size_t>(i >> 6)];
    const std::uint64_t bit = std::uint64_t{1} << (i & 63);
    const bool fresh = (w & bit) == 0;
    w |= bit;
    return fresh;
  }
  void markRayFree(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key, const Key& to_key) {
    markRayFree(planarSegment(from, to, from_key, to_key), from_key, 0);
  }
  /// Marks the walk of `seg` from cell `from_key`, leaving out its first `skip_runs` runs (rows
  /// if it steps more along x, else columns; never the last).
  void markRayFree(const PlanarSegment& seg, const Key& from_key, std::int64_t skip_runs);
  /// Folds the column marks into tiles(); call after the last markRayFree.
  void finalize();

  int brickX0() const { return bx0_; }
  int brickY0() const { return by0_; }
  int width() const { return width_; }  ///< bricks along x
  const std::vector<Tile>& tiles() const { return tiles_; }

 private:
  static int bitOf(int x, int y) { return (x & (kBrickSize - 1)) | ((y & (kBrickSize - 1)) << kBrickBits); }
  std::size_t tileIndex(int x, int y) const {
    return static_cast<std::size_t>(((y >> kBrickBits) - by0_) * width_ + ((x >> kBrickBits) - bx0_));
  }
  Tile& tileOf(int x, int y) { return tiles_[tileIndex(x, y)]; }
  int bx0_ = 0, by0_ = 0, width_ = 0;
  std::vector<Tile> tiles_;
  std::vector<ColumnTile> columns_;  // indexed as tiles_
};

}  // namespace rtog
