#include "rtog/core/update_batch.hpp"

#include <algorithm>
#include <numeric>

namespace rtog {

void UpdateBatch::clear() {
  count_ = 0;
  occupied_count_ = free_count_ = 0;
  index_.clear();
  sorted_.clear();
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

void UpdateBatch::merge(const UpdateBatch& other) {
  for (std::size_t i = 0; i < other.count_; ++i) {
    const BrickUpdates& o = (*other.chunks_[i / kChunkBricks])[i % kChunkBricks];
    BrickUpdates& b = brickAt(brickSlot(o.brick));
    for (std::size_t w = 0; w < kBrickWords; ++w) {
      b.occupied[w] |= o.occupied[w];
      b.free[w] |= o.free[w];
    }
  }
  cached_ = nullptr;
}

namespace {

std::size_t popcount(const std::array<std::uint64_t, kBrickWords>& words) {
  // SWAR count: the baseline x86-64 target has no POPCNT instruction.
  std::size_t n = 0;
  for (std::uint64_t w : words) {
    w = w - ((w >> 1) & 0x5555555555555555ull);
    w = (w & 0x3333333333333333ull) + ((w >> 2) & 0x3333333333333333ull);
    w = (w + (w >> 4)) & 0x0f0f0f0f0f0f0f0full;
    n += static_cast<std::size_t>((w * 0x0101010101010101ull) >> 56);
  }
  return n;
}

}  // namespace

void UpdateBatch::finalize() {
  sorted_.clear();
  occupied_count_ = free_count_ = 0;
  forEachBrick([&](BrickUpdates& b) {
    for (std::size_t w = 0; w < kBrickWords; ++w) b.free[w] &= ~b.occupied[w];
    occupied_count_ += popcount(b.occupied);
    free_count_ += popcount(b.free);
    sorted_.push_back(&b);
  });
  std::sort(sorted_.begin(), sorted_.end(), [](const BrickUpdates* a, const BrickUpdates* b) { return a->brick < b->brick; });
}

}  // namespace rtog
