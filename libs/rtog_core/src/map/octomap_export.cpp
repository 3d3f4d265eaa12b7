#include "rtog/core/octomap_export.hpp"

#include <array>
#include <limits>
#include <locale>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace rtog {
namespace {

// 2-bit child states of OctoMap's binary stream (bit 2i and 2i+1 of a node's byte pair).
constexpr unsigned kUnknown = 0;   // no child
constexpr unsigned kFree = 1;      // free leaf
constexpr unsigned kOccupied = 2;  // occupied leaf
constexpr unsigned kInner = 3;     // has children; its own byte pair follows later in the stream

struct Item {
  Box box;  // OctoMap keys (lattice key + 2^15), all in [0, 2^16)
  bool occupied;
};

class TreeWriter {
 public:
  explicit TreeWriter(std::vector<Item> items) : items_(std::move(items)) {}

  /// Encodes the whole tree into data(); the root is always an inner node.
  void run() {
    if (items_.empty()) return;
    std::vector<std::uint32_t> all(items_.size());
    for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
    stats_.nodes = 1;
    writeInner(Key{0, 0, 0}, kOctoMapDepth, all);
  }

  const std::string& data() const { return data_; }
  const OctoMapExportStats& stats() const { return stats_; }

 private:
  static Box cube(const Key& o, int level) {
    const std::int32_t s = std::int32_t{1} << level;
    return Box{o, Key{o.x + s - 1, o.y + s - 1, o.z + s - 1}};
  }

  /// State of the cube from the items that intersect it (leaves never overlap, so the cube
  /// is one class exactly when that class's intersections fill its volume).
  unsigned classify(const Box& c, const std::vector<std::uint32_t>& idx) const {
    if (idx.empty()) return kUnknown;
    std::int64_t occ = 0, fr = 0;
    for (std::uint32_t i : idx) {
      const std::int64_t v = items_[i].box.intersection(c).volume();
      (items_[i].occupied ? occ : fr) += v;
      if (occ > 0 && fr > 0) return kInner;
    }
    const std::int64_t vol = c.volume();
    if (occ == vol) return kOccupied;
    if (fr == vol) return kFree;
    return kInner;
  }

  /// Writes the byte pair of the inner node at `o` (cube of 2^level cells), then recurses into
  /// its inner children in child order, as OctoMap's reader expects.
  void writeInner(const Key& o, int level, const std::vector<std::uint32_t>& idx) {
    const std::int32_t h = std::int32_t{1} << (level - 1);
    std::array<std::vector<std::uint32_t>, 8> child;
    for (std::uint32_t i : idx) {
      const Box& b = items_[i].box;
      int lo[3], hi[3];  // which halves the item spans per axis
      for (int a = 0; a < 3; ++a) {
        lo[a] = b.min[a] >= o[a] + h ? 1 : 0;
        hi[a] = b.max[a] >= o[a] + h ? 1 : 0;
      }
      for (int z = lo[2]; z <= hi[2]; ++z)
        for (int y = lo[1]; y <= hi[1]; ++y)
          for (int x = lo[0]; x <= hi[0]; ++x) child[x | (y << 1) | (z << 2)].push_back(i);
    }
    std::array<Key, 8> origin;
    std::array<unsigned, 8> state;
    unsigned char bytes[2] = {0, 0};
    for (int c = 0; c < 8; ++c) {
      origin[c] = Key{o.x + ((c & 1) ? h : 0), o.y + ((c & 2) ? h : 0), o.z + ((c & 4) ? h : 0)};
      state[c] = classify(cube(origin[c], level - 1), child[c]);
      bytes[c / 4] = static_cast<unsigned char>(bytes[c / 4] | (state[c] << (2 * (c % 4))));
      if (state[c] != kUnknown) ++stats_.nodes;
      if (state[c] == kOccupied) ++stats_.occupied_leaves;
      if (state[c] == kFree) ++stats_.free_leaves;
      if (state[c] != kInner) std::vector<std::uint32_t>().swap(child[c]);
    }
    ++stats_.inner_nodes;
    data_.push_back(static_cast<char>(bytes[0]));
    data_.push_back(static_cast<char>(bytes[1]));
    for (int c = 0; c < 8; ++c) {
      if (state[c] != kInner) continue;
      writeInner(origin[c], level - 1, child[c]);
      std::vector<std::uint32_t>().swap(child[c]);
    }
  }

  std::vector<Item> items_;
  std::string data_;
  OctoMapExportStats stats_;
};

/// Shortest decimal that reads back as the same double.
std::string exactDecimal(double v) {
  for (int prec = 1; prec <= std::numeric_limits<double>::max_digits10; ++prec) {
    std::ostringstream os;
    os.imbue(std::locale::classic());
    os.precision(prec);
    os << v;
    std::istringstream is(os.str());
    is.imbue(std::locale::classic());
    double back = 0;
    if (is >> back && back == v) return os.str();
  }
  std::ostringstream os;
  os.imbue(std::locale::classic());
  os.precision(std::numeric_limits<double>::max_digits10);
  os << v;
  return os.str();
}

}  // namespace

OctoMapExportStats writeOctoMapBinary(const OccupancyMap& map, std::ostream& os) {
  std::vector<Item> items;
  items.reserve(map.leafCount());
  bool bad = false;
  Box first_bad;
  map.forEachLeaf([&](const Box& b, float v) {
    if (!inOctoMapKeyRange(b)) {
      if (!bad) first_bad = b;
      bad = true;
      return;
    }
    const Key off{kOctoMapKeyOffset, kOctoMapKeyOffset, kOctoMapKeyOffset};
    items.push_back(Item{Box{Key{b.min.x + off.x, b.min.y + off.y, b.min.z + off.z},
                             Key{b.max.x + off.x, b.max.y + off.y, b.max.z + off.z}},
                         map.logOddsModel().classify(v) == CellState::Occupied});
  });
  if (bad) {
    const double reach = kOctoMapKeyOffset * map.resolution();
    throw std::out_of_range("cells " + toString(first_bad) +
                            " lie outside OctoMap's key range (cell keys -32768..32767 per axis, about +-" +
                            exactDecimal(reach) + " m at " + exactDecimal(map.resolution()) + " m)");
  }

  TreeWriter w(std::move(items));
  w.run();
  const OctoMapExportStats& st = w.stats();
  if (st.nodes > std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("the OctoMap tree would have " + std::to_string(st.nodes) +
                            " nodes, more than its header can state");

  const std::string header = "# Octomap OcTree binary file\n# (written by rtog)\nid OcTree\nsize " +
                             std::to_string(st.nodes) + "\nres " + exactDecimal(map.resolution()) + "\ndata\n";
  os.write(header.data(), static_cast<std::streamsize>(header.size()));
  os.write(w.data().data(), static_cast<std::streamsize>(w.data().size()));
  if (!os) throw std::runtime_error("writing the OctoMap stream failed");
  return st;
}

}  // namespace rtog
