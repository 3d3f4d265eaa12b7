#include "storage/morton_order.hpp"

namespace rtog {

const std::array<std::uint16_t, kBrickCells>& mortonOrder() {
  static const std::array<std::uint16_t, kBrickCells> order = [] {
    std::array<std::uint16_t, kBrickCells> o{};
    for (int m = 0; m < kBrickCells; ++m) {
      int c[3] = {0, 0, 0};
      for (int bit = 0; bit < kBrickBits; ++bit)
        for (int a = 0; a < 3; ++a) c[a] |= ((m >> (3 * bit + a)) & 1) << bit;
      o[static_cast<std::size_t>(m)] = static_cast<std::uint16_t>(localIndex(c[0], c[1], c[2]));
    }
    return o;
  }();
  return order;
}

const std::array<std::uint16_t, kBrickCells>& mortonRank() {
  static const std::array<std::uint16_t, kBrickCells> rank = [] {
    std::array<std::uint16_t, kBrickCells> r{};
    const auto& order = mortonOrder();
    for (std::size_t m = 0; m < order.size(); ++m) r[order[m]] = static_cast<std::uint16_t>(m);
    return r;
  }();
  return rank;
}

}  // namespace rtog
