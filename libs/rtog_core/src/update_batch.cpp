#include "rtog/core/update_batch.hpp"

#include <algorithm>
#include <bitset>
#include <numeric>

namespace rtog {

void UpdateBatch::clear() {
  bricks_.clear();
  index_.clear();
  sorted_.clear();
  cached_ = nullptr;
}

std::uint32_t UpdateBatch::brickSlot(const Key& b) {
  const auto next = static_cast<std::uint32_t>(bricks_.size());
  const std::uint32_t slot = index_.findOrInsert(packKey(b), next);
  if (slot == next) {
    cached_ = nullptr;  // the vector may move
    bricks_.emplace_back();
    bricks_.back().brick = b;
    bricks_.back().occupied.fill(0);
    bricks_.back().free.fill(0);
  }
  return slot;
}

void UpdateBatch::merge(const UpdateBatch& other) {
  for (const BrickUpdates& o : other.bricks_) {
    BrickUpdates& b = bricks_[brickSlot(o.brick)];
    for (std::size_t w = 0; w < kBrickWords; ++w) {
      b.occupied[w] |= o.occupied[w];
      b.free[w] |= o.free[w];
    }
  }
  cached_ = nullptr;
}

void UpdateBatch::finalize() {
  sorted_.clear();
  for (auto& b : bricks_) {
    for (std::size_t w = 0; w < kBrickWords; ++w) b.free[w] &= ~b.occupied[w];
    sorted_.push_back(&b);
  }
  std::sort(sorted_.begin(), sorted_.end(), [](const BrickUpdates* a, const BrickUpdates* b) { return a->brick < b->brick; });
}

static std::size_t popcount(const std::array<std::uint64_t, kBrickWords>& words) {
  std::size_t n = 0;
  for (std::uint64_t w : words) n += std::bitset<64>(w).count();
  return n;
}

std::size_t UpdateBatch::occupiedCount() const {
  std::size_t n = 0;
  for (const auto& b : bricks_) n += popcount(b.occupied);
  return n;
}

std::size_t UpdateBatch::freeCount() const {
  std::size_t n = 0;
  for (const auto& b : bricks_) n += popcount(b.free);
  return n;
}

}  // namespace rtog
