#include "integrate/update_batch.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <type_traits>
#include <numeric>


namespace rtog {

void UpdateBatch::clear() {
  bricks_.clear();  // keeps the chunks
  packed_keys_.clear();
  index_.clear();
  sorted_.clear();
  sorted_keys_.clear();
  sorted_codes_.clear();
  cached_ = nullptr;
  recent_.clear();
  queued_.clear();
}

std::uint32_t UpdateBatch::brickSlot(const Key& b) {
  const auto next = static_cast<std::uint32_t>(packed_keys_.size());
  const std::uint64_t packed = packKey(b);
  const std::uint32_t slot = index_.findOrInsert(packed, next);
  if (slot == next) {
    packed_keys_.push_back(packed);
    BrickUpdates& u = bricks_.emplaceBack();  // value-initialized: masks empty, any_occupied false
    u.brick = b;
  }
  return slot;
}

void UpdateBatch::markRayFree(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key,
                              const Key& to_key) {
  // Tracks the cell's brick and bit incrementally: a carry out of the brick's local range is
  // the only time the brick is looked up again. The walk does not move past its last visit, so
  // no brick enters the batch without a mark.
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
  if (from_key == to_key) return;
  constexpr int m = kBrickSize - 1;
  BrickCursor cursor{*this, from_key, {from_key.x & m, from_key.y & m, from_key.z & m}, brickFor(from_key).free.data()};
  walkRay(from, to, from_key, to_key, cursor);
}

bool UpdateBatch::useLaneKernel(detail::LaneKernel kernel) {
  if (!detail::laneKernelRuns(kernel)) return false;
  walkQueued();  // what the old kernel queued
  lanes_ = kernel;
  return true;
}

void UpdateBatch::walkQueued(bool wide) {
  if (queued_.empty()) return;
  // queueRayFree queues only what lanes can walk (a lane kernel, rays leaving their z-layer).
  lane_rays_.clear();
  if (wide)
    for (std::uint32_t i = 0; i < queued_.size(); ++i) lane_rays_.push_back(i);
  const bool windowed = wide && walkInWindow(lane_rays_);
  std::size_t next_lane = 0;
  for (std::uint32_t i = 0; i < queued_.size(); ++i) {
    if (windowed && next_lane < lane_rays_.size() && lane_rays_[next_lane] == i) {
      ++next_lane;
      continue;
    }
    const QueuedRay& q = queued_[i];
    markRayFree(q.from, q.to, q.from_key, q.to_key);
  }
  queued_.clear();
}

bool UpdateBatch::walkInWindow(std::vector<std::uint32_t>& lanes) {
  // At most 2^14 bricks (8 MiB).
  constexpr int kMaxBits = 14;
  const auto bitsFor = [](std::int64_t extent) {
    int b = 0;
    while ((std::int64_t{1} << b) < extent) ++b;
    return b;
  };
  const auto boundsOf = [&](Key& lo, Key& hi) {
    lo = hi = brickOf(queued_[lanes.front()].from_key);
    for (const std::uint32_t i : lanes)
      for (const Key& k : {queued_[i].from_key, queued_[i].to_key}) {
        const Key b = brickOf(k);
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], b[a]), hi[a] = std::max(hi[a], b[a]);
      }
  };
  Key lo, hi;
  boundsOf(lo, hi);
  detail::LaneWindow w{lo, {0, 0, 0}};
  const auto fit = [&] {
    int total = 0;
    for (int a = 0; a < 3; ++a) total += w.bits[a] = bitsFor(std::int64_t{hi[a]} - lo[a] + 1);
    return total <= kMaxBits;
  };
  if (!fit()) {
    // Rays from scattered starts (queued rays are short): keep those within 32 x 32 x 16 bricks
    // around where the first one starts, if that is most of them.
    const std::size_t all = lanes.size();
    const Key c = brickOf(queued_[lanes.front()].from_key);
    const Key box_lo{c.x - 16, c.y - 16, c.z - 8}, box_hi{c.x + 15, c.y + 15, c.z + 7};
    const auto inside = [&](const Key& k) {
      const Key b = brickOf(k);
      for (int a = 0; a < 3; ++a)
        if (b[a] < box_lo[a] || b[a] > box_hi[a]) return false;
      return true;
    };
    const auto outside = [&](std::uint32_t i) { return !inside(queued_[i].from_key) || !inside(queued_[i].to_key); };
    lanes.erase(std::remove_if(lanes.begin(), lanes.end(), outside), lanes.end());
    if (lanes.size() * 2 < all) return false;
    boundsOf(lo, hi);
    w.origin = lo;
    if (!fit()) return false;
  }
  // One scratch brick in front of the window for lanes without a ray; all zero between walks,
  // as are the touched flags.
  const std::size_t words = (w.bricks() + 1) * kBrickWords;
  if (window_.size() < words) window_.resize(words, 0);
  if (touched_.size() < w.bricks() + 1) touched_.resize(w.bricks() + 1, 0);
  std::uint64_t* window = window_.data() + kBrickWords;
  std::uint8_t* touched = touched_.data() + 1;
  detail::orderForWaves(queued_, lanes, wave_order_, wave_shared_);
  detail::walkLanes(lanes_, queued_, wave_order_, wave_shared_, w, window, touched);
  std::fill_n(window_.data(), kBrickWords, 0);
  touched[-1] = 0;
  // Into the bricks: a window word is 64 cells of an x-row, four bricks' 16-cell rows; each
  // brick met is looked up once per window (brick_slots_, by its index in the window).
  if (brick_slots_.size() < w.bricks()) brick_slots_.resize(w.bricks(), kNoSlot);
  const int sx = w.shift(1), sy = w.shift(2);
  const std::int64_t mx = (std::int64_t{1} << sx) - 1, my = (std::int64_t{1} << (sy - sx)) - 1;
  constexpr std::int64_t kRow = kBrickSize, kRowMask = (std::uint64_t{1} << kRow) - 1;
  for (std::size_t run = 0; run < w.bricks(); ++run) {
    if (touched[run] == 0) continue;
    touched[run] = 0;
    for (std::size_t i = 0; i < kBrickWords; ++i) {
      std::uint64_t& word = window[run * kBrickWords + i];
      if (word == 0) continue;
      const std::int64_t first = static_cast<std::int64_t>(run * kBrickWords + i) * 64;
      for (std::int64_t c = 0; c < 64; c += kRow) {
        const std::uint64_t row = (word >> c) & kRowMask;
        if (row == 0) continue;
        const std::int64_t cell = first + c, x = cell & mx, y = (cell >> sx) & my, z = cell >> sy;
        const std::size_t b = static_cast<std::size_t>((x >> kBrickBits) | ((y >> kBrickBits) << w.bits[0]) |
                                                       ((z >> kBrickBits) << (w.bits[0] + w.bits[1])));
        if (brick_slots_[b] == kNoSlot) {
          const Key brick{w.origin.x + static_cast<std::int32_t>(x >> kBrickBits),
                          w.origin.y + static_cast<std::int32_t>(y >> kBrickBits),
                          w.origin.z + static_cast<std::int32_t>(z >> kBrickBits)};
          brick_slots_[b] = brickSlot(brick);
          slotted_.push_back(static_cast<std::uint32_t>(b));
        }
        const int local = localIndex(0, static_cast<int>(y & (kBrickSize - 1)), static_cast<int>(z & (kBrickSize - 1)));
        brickAt(brick_slots_[b]).free[static_cast<std::size_t>(local >> 6)] |= row << (local & 63);
      }
      word = 0;
    }
  }
  for (const std::uint32_t b : slotted_) brick_slots_[b] = kNoSlot;
  slotted_.clear();
  return true;
}

void UpdateBatch::finalize() {
  walkQueued();
  // Sorted as (code, slot) pairs, the codes computed from the packed keys kept beside the bricks:
  // reading the bricks (1 KiB apart) missed the cache on most of a comparison sort's comparisons.
  std::vector<std::pair<std::uint64_t, std::uint32_t>>& order = order_scratch_;
  order.clear();
  for (std::uint32_t slot = 0; slot < packed_keys_.size(); ++slot)
    order.emplace_back(mortonCode(unpackKey(packed_keys_[slot])), slot);
  std::sort(order.begin(), order.end());
  sorted_.clear();
  sorted_keys_.clear();
  sorted_codes_.clear();
  for (const auto& [code, slot] : order) {
    BrickUpdates& b = brickAt(slot);
    if (b.any_occupied)
      for (std::size_t w = 0; w < kBrickWords; ++w) b.free[w] &= ~b.occupied[w];
    sorted_.push_back(&b);
    sorted_keys_.push_back(unpackKey(packed_keys_[slot]));
    sorted_codes_.push_back(code);
  }
}

}  // namespace rtog
