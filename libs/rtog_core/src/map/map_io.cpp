// Binary serialization of the map: header, parameters, leaves, checksum (doc/format.md).
#include <algorithm>
#include <cstring>
#include <type_traits>
#include <istream>
#include <ostream>

#include "integrate/cell_assignment.hpp"
#include "map/map_engine.hpp"
#include "rtog/core/occupancy_map.hpp"

namespace rtog {
namespace {

constexpr char kMagic[8] = {'R', 'T', 'O', 'G', 'M', 'A', 'P', '\0'};
constexpr std::uint32_t kFormatVersion = 1;

// FNV-1a over everything written after the magic, so a flipped bit anywhere is caught.
class Fnv1a {
 public:
  void add(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h_ = (h_ ^ p[i]) * 0x100000001b3ull;
  }
  std::uint64_t value() const { return h_; }

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ull;
};

class Writer {
 public:
  explicit Writer(std::ostream& os) : os_(os) {}
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    os_.write(reinterpret_cast<const char*>(&v), sizeof(T));
    sum_.add(&v, sizeof(T));
  }
  std::uint64_t checksum() const { return sum_.value(); }

 private:
  std::ostream& os_;
  Fnv1a sum_;
};

class Reader {
 public:
  explicit Reader(std::istream& is) : is_(is) {}
  template <class T>
  T get(const char* what) {
    T v;
    if (!is_.read(reinterpret_cast<char*>(&v), sizeof(T)))
      throw std::runtime_error(std::string("rtog map: truncated stream while reading ") + what);
    sum_.add(&v, sizeof(T));
    return v;
  }
  std::uint64_t checksum() const { return sum_.value(); }

 private:
  std::istream& is_;
  Fnv1a sum_;
};

/// Bytes from the read position to the end, or -1 if the stream cannot tell (a pipe).
std::int64_t bytesLeft(std::istream& is) {
  const std::istream::pos_type here = is.tellg();
  if (here == std::istream::pos_type(-1)) return -1;
  is.seekg(0, std::ios::end);
  const std::istream::pos_type end = is.tellg();
  is.seekg(here);
  if (end == std::istream::pos_type(-1) || !is) {
    is.clear();
    is.seekg(here);
    return -1;
  }
  return static_cast<std::int64_t>(end - here);
}

}  // namespace

void OccupancyMap::write(std::ostream& os) const {
  engine_->ensureCovered();
  const MapStore& store = engine_->store;
  const MapParams& params = store.params;
  os.write(kMagic, sizeof(kMagic));
  Writer w(os);
  w.put(kFormatVersion);
  const LogOddsParams& lp = params.log_odds;
  for (double d : {params.resolution, lp.prob_hit, lp.prob_miss, lp.clamp_min, lp.clamp_max, lp.occupied_threshold,
                   lp.prior})
    w.put(d);
  w.put(static_cast<std::uint8_t>(params.merge));
  w.put(params.rtree.max_entries);
  w.put(params.rtree.min_entries);
  w.put(static_cast<std::uint64_t>(store.index.leafCount()));
  // Bricks in key order so equal maps give equal files.
  std::vector<const Brick*> order;
  order.reserve(store.index.brickCount());
  store.index.forEachBrick([&](const Brick& b) { order.push_back(&b); });
  std::sort(order.begin(), order.end(), [](const Brick* a, const Brick* b) { return a->brick < b->brick; });
  for (const Brick* b : order) {
    std::vector<LeafEntry> leaves = b->leaves;
    std::sort(leaves.begin(), leaves.end(), [](const LeafEntry& x, const LeafEntry& y) {
      return std::memcmp(x.lo, y.lo, 3) < 0 || (std::memcmp(x.lo, y.lo, 3) == 0 && std::memcmp(x.hi, y.hi, 3) < 0);
    });
    const Key o = brickOrigin(b->brick);
    for (const LeafEntry& l : leaves) {
      const Box gb = l.global(o);
      for (int a = 0; a < 3; ++a) w.put(gb.min[a]);
      for (int a = 0; a < 3; ++a) w.put(gb.max[a]);
      w.put(l.value);
    }
  }
  const std::uint64_t sum = w.checksum();
  os.write(reinterpret_cast<const char*>(&sum), sizeof(sum));
  if (!os) throw std::runtime_error("rtog map: write failed");
}

OccupancyMap OccupancyMap::read(std::istream& is) {
  char magic[sizeof(kMagic)];
  if (!is.read(magic, sizeof(magic)) || std::memcmp(magic, kMagic, sizeof(kMagic)) != 0)
    throw std::runtime_error("rtog map: not an rtog map (bad magic)");
  Reader r(is);
  const auto version = r.get<std::uint32_t>("version");
  if (version != kFormatVersion)
    throw std::runtime_error("rtog map: unsupported format version " + std::to_string(version));
  MapParams p;
  p.resolution = r.get<double>("resolution");
  LogOddsParams& lp = p.log_odds;
  for (double* d : {&lp.prob_hit, &lp.prob_miss, &lp.clamp_min, &lp.clamp_max, &lp.occupied_threshold, &lp.prior})
    *d = r.get<double>("log-odds parameters");
  const auto merge = r.get<std::uint8_t>("merge policy");
  if (merge > static_cast<std::uint8_t>(MergePolicy::Equal)) throw std::runtime_error("rtog map: bad merge policy");
  p.merge = static_cast<MergePolicy>(merge);
  p.rtree.max_entries = r.get<std::uint32_t>("R-tree parameters");
  p.rtree.min_entries = r.get<std::uint32_t>("R-tree parameters");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("rtog map: bad parameters: ") + e.what());
  }
  const auto count = r.get<std::uint64_t>("leaf count");
  if (count > (std::uint64_t{1} << 36)) throw std::runtime_error("rtog map: implausible leaf count");
  // Leaves are stored as they are read, so memory follows the bytes present whatever the count
  // says; a stream that knows its size (a file, a block in memory; not a pipe) refuses a count
  // it cannot hold before reading any.
  constexpr std::uint64_t kLeafBytes = 6 * sizeof(std::int32_t) + sizeof(float);
  if (const std::int64_t left = bytesLeft(is); left >= 0 && count > std::uint64_t(left) / kLeafBytes)
    throw std::runtime_error("rtog map: the leaf count " + std::to_string(count) + " needs " +
                             std::to_string(count * kLeafBytes + 8) + " more bytes, the stream holds " +
                             std::to_string(left) + " (truncated or corrupt)");

  OccupancyMap map(p);
  // The leaves go in as pieces of a cell assignment into a map without leaves: they become its
  // leaves as they are, checked disjoint, with one bulk load of the upper tree.
  try {
    map.engine_->integrate([&](const IntegrationContext& c) {
      std::vector<AssignedPiece>& pieces = c.scratch.assigned;
      pieces.clear();
      if (bytesLeft(is) >= 0) pieces.reserve(static_cast<std::size_t>(count));  // the count was checked
      for (std::uint64_t i = 0; i < count; ++i) {
        Box b;
        for (int a = 0; a < 3; ++a) b.min[a] = r.get<std::int32_t>("leaf");
        for (int a = 0; a < 3; ++a) b.max[a] = r.get<std::int32_t>("leaf");
        const auto v = r.get<float>("leaf");
        if (!keyInRange(b.min) || !keyInRange(b.max) || b.isEmpty() || brickOf(b.min) != brickOf(b.max))
          throw std::runtime_error("rtog map: malformed leaf box " + toString(b));
        if (!(v >= c.store.model.clampMin() && v <= c.store.model.clampMax()))
          throw std::runtime_error("rtog map: leaf value outside the clamping bounds");
        if (b.volume() > 1 && !c.store.mergeable(v))
          throw std::runtime_error("rtog map: merged leaf " + toString(b) + " with a value its merge policy keeps apart");
        const Key o = brickOrigin(brickOf(b.min));
        AssignedPiece piece{brickOf(b.min), LeafEntry{}};
        for (int a = 0; a < 3; ++a) {
          piece.leaf.lo[a] = static_cast<std::uint8_t>(b.min[a] - o[a]);
          piece.leaf.hi[a] = static_cast<std::uint8_t>(b.max[a] - o[a]);
        }
        piece.leaf.value = v;
        pieces.push_back(piece);
      }
      std::uint64_t stored_sum;
      const std::uint64_t sum = r.checksum();
      if (!is.read(reinterpret_cast<char*>(&stored_sum), sizeof(stored_sum)))
        throw std::runtime_error("rtog map: truncated stream while reading checksum");
      if (stored_sum != sum) throw std::runtime_error("rtog map: checksum mismatch (corrupt file)");
      return CellAssignment(c).tracePieces();
    });
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("rtog map: ") + e.what());
  }
  return map;
}

}  // namespace rtog
