#include "rtog/core/update_batch.hpp"

#include <algorithm>
#include <numeric>

namespace rtog {

void UpdateBatch::clear() {
  count_ = 0;
  index_.clear();
  sorted_.clear();
  sorted_keys_.clear();
  cached_ = nullptr;
}

std::uint32_t UpdateBatch::brickSlot(const Key& b) {
  const auto next = static_cast<std::uint32_t>(count_);
  const std::uint32_t slot = index_.findOrInsert(packKey(b), next);
  if (slot == next) {
    if (count_ == chunks_.size() * kChunkBricks) chunks_.push_back(std::make_unique<Chunk>());
    ++count_;
    BrickUpdates& u = brickAt(slot);
    u.brick = b;
    u.occupied.fill(0);
    u.free.fill(0);
  }
  return slot;
}

void UpdateBatch::markRayFree(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key,
                              const Key& to_key) {
  // Tracks the cell's brick and bit incrementally: a carry out of the brick's local range is
  // the only time the brick is looked up again.
  struct BrickCursor {
    UpdateBatch& batch;
    Key cell;
    int local[3];
    std::uint64_t* words;
    void visit() {
      const int i = local[0] | (local[1] << kBrickBits) | (local[2] << (2 * kBrickBits));
      words[i >> 6] |= std::uint64_t{1} << (i & 63);
    }
    void move(int axis, int s) {
      cell[axis] += s;
      local[axis] += s;
      if (local[axis] & ~(kBrickSize - 1)) {
        local[axis] &= kBrickSize - 1;
        words = batch.brickFor(cell).free.data();
      }
    }
  };
  constexpr int m = kBrickSize - 1;
  BrickCursor cursor{*this, from_key, {from_key.x & m, from_key.y & m, from_key.z & m}, brickFor(from_key).free.data()};
  walkRay(from, to, from_key, to_key, cursor);
}

void UpdateBatch::finalize() {
  sorted_.clear();
  forEachBrick([&](BrickUpdates& b) {
    for (std::size_t w = 0; w < kBrickWords; ++w) b.free[w] &= ~b.occupied[w];
    sorted_.push_back(&b);
  });
  std::sort(sorted_.begin(), sorted_.end(), [](const BrickUpdates* a, const BrickUpdates* b) { return a->brick < b->brick; });
  sorted_keys_.clear();
  for (const BrickUpdates* b : sorted_) sorted_keys_.push_back(b->brick);
}

void PlanarBatch::reset(const Key& lo, const Key& hi) {
  bx0_ = lo.x >> kBrickBits;
  by0_ = lo.y >> kBrickBits;
  width_ = (hi.x >> kBrickBits) - bx0_ + 1;
  tiles_.assign(tilesFor(lo, hi), Tile{});
}

void PlanarBatch::markRayFree(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key,
                              const Key& to_key) {
  // As UpdateBatch's cursor: only a carry out of the brick moves to another tile.
  struct TileCursor {
    PlanarBatch& batch;
    Key cell;
    int local[3];
    std::uint64_t* words;
    void visit() {
      const int i = local[0] | (local[1] << kBrickBits);
      words[i >> 6] |= std::uint64_t{1} << (i & 63);
    }
    void move(int axis, int s) {
      cell[axis] += s;
      local[axis] += s;  // the walk of a planar beam never steps z
      if (local[axis] & ~(kBrickSize - 1)) {
        local[axis] &= kBrickSize - 1;
        words = batch.tileOf(cell.x, cell.y).free.data();
      }
    }
  };
  constexpr int m = kBrickSize - 1;
  TileCursor cursor{*this, from_key, {from_key.x & m, from_key.y & m, 0}, tileOf(from_key.x, from_key.y).free.data()};
  walkRay(from, to, from_key, to_key, cursor);
}

}  // namespace rtog
