// The cells of a map read brick by brick into dense tables, kept for the next reads: casting many
// rays through the same space (a view's, a set of candidate views') costs a query per brick, not an
// R-tree descent per cell.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <unordered_map>

#include "rtog/core/key.hpp"
#include "rtog/core/occupancy_map.hpp"

namespace rtog::explore_detail {

class CellReader {
 public:
  explicit CellReader(const OccupancyMap& map) : map_(map) {}
  /// The cell's log-odds, NaN if unknown.
  float at(const Key& k) {
    const Key b{k.x >> kBits, k.y >> kBits, k.z >> kBits};
    const std::uint64_t code = packKey(b);
    if (code != last_code_) {
      auto& slot = bricks_[code];
      if (!slot) {
        slot = std::make_unique<Table>();
        slot->fill(std::numeric_limits<float>::quiet_NaN());
        const Box box{Key{b.x * kSide, b.y * kSide, b.z * kSide},
                      Key{b.x * kSide + kSide - 1, b.y * kSide + kSide - 1, b.z * kSide + kSide - 1}};
        map_.forEachLeafIn(box, [&](const Box& leaf, float v) {
          forEachCell(leaf.intersection(box), [&](const Key& c) { (*slot)[index(c)] = v; });
        });
      }
      last_ = slot.get(), last_code_ = code;
    }
    return (*last_)[index(k)];
  }

 private:
  static constexpr int kBits = 4, kSide = 1 << kBits;
  using Table = std::array<float, kSide * kSide * kSide>;
  static std::size_t index(const Key& k) {
    constexpr int m = kSide - 1;
    return static_cast<std::size_t>((k.x & m) | ((k.y & m) << kBits) | ((k.z & m) << (2 * kBits)));
  }
  const OccupancyMap& map_;
  std::unordered_map<std::uint64_t, std::unique_ptr<Table>> bricks_;
  const Table* last_ = nullptr;
  std::uint64_t last_code_ = ~std::uint64_t{0};
};

}  // namespace rtog::explore_detail
