// Binary serialization of the map: header, parameters, leaves, checksum (doc/format.md).
#include <algorithm>
#include <array>
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
// Version 2 stores leaves brick by brick in brick-local bytes (10 bytes a leaf, 28 in version 1,
// which is still read).
constexpr std::uint32_t kFormatVersion = 2;

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

// Bytes gathered in a block and handed to the stream a block at a time: a map is millions of
// four-byte fields, and a stream call each costs more than the field.
class Writer {
 public:
  explicit Writer(std::ostream& os) : os_(os) {}
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T> && sizeof(T) <= 64);
    if (used_ + sizeof(T) > sizeof(buf_)) flush();
    std::memcpy(buf_ + used_, &v, sizeof(T));
    sum_.add(&v, sizeof(T));
    used_ += sizeof(T);
  }
  std::uint64_t checksum() const { return sum_.value(); }
  /// Hands the gathered bytes to the stream (which may throw: a stream with exceptions on).
  void flush() {
    const std::size_t n = used_;
    used_ = 0;
    if (n > 0) os_.write(buf_, static_cast<std::streamsize>(n));
  }

 private:
  std::ostream& os_;
  Fnv1a sum_;
  char buf_[1 << 16];
  std::size_t used_ = 0;
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

// The header (magic, version, seven doubles, merge policy, two R-tree parameters, leaf count);
// a brick's key and leaf count; a leaf (local corners, log-odds); the checksum.
constexpr std::uint64_t kHeaderBytes = sizeof(kMagic) + 4 + 7 * 8 + 1 + 2 * 4 + 8;
constexpr std::uint64_t kBrickBytes = 3 * 4 + 4;
constexpr std::uint64_t kLeafBytes = 6 + 4;
constexpr std::uint64_t kLeafBytesV1 = 6 * 4 + 4;

namespace {

/// Calls fn(brick key, its leaves) for every brick holding leaves, in key order, with the leaves
/// the covered map would hold: a brick's own, or for a brick with a cached layer those cover()
/// would make, read from the cache (a save of a map being built neither rebuilds its tree nor
/// clones shared bricks). The caller holds MapEngine::lockReadableCache().
template <class Fn>
void forEachCoveredBrick(const MapEngine& engine, Fn&& fn) {
  const LeafIndex& index = engine.store.index;
  std::vector<std::pair<Key, std::uint32_t>> order;
  order.reserve(index.brickCount());
  for (std::uint32_t slot = 0; slot < index.brickCount(); ++slot) order.emplace_back(index.brick(slot).brick, slot);
  std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<LeafEntry> covered;
  const bool any_cached = !engine.planar.empty();
  for (const auto& [key, slot] : order) {
    const bool cached = any_cached && engine.planar.coveredLeaves(engine.store, slot, covered);
    const std::vector<LeafEntry>& leaves = cached ? covered : index.brick(slot).leaves;
    if (!leaves.empty()) fn(key, leaves);
  }
}

}  // namespace

std::uint64_t OccupancyMap::writtenSize() const {
  const auto lock = engine_->lockReadableCache();
  std::uint64_t bytes = kHeaderBytes + 8;
  forEachCoveredBrick(*engine_, [&](const Key&, const std::vector<LeafEntry>& leaves) {
    bytes += kBrickBytes + kLeafBytes * leaves.size();
  });
  return bytes;
}

void OccupancyMap::write(std::ostream& os) const {
  const auto lock = engine_->lockReadableCache();
  const MapStore& store = engine_->store;
  const MapParams& params = store.params;
  std::uint64_t count = 0;
  forEachCoveredBrick(*engine_, [&](const Key&, const std::vector<LeafEntry>& leaves) { count += leaves.size(); });
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
  w.put(count);
  // Bricks in key order, a brick's leaves by their (lo, hi) bytes, so equal maps give equal files.
  const auto boxKey = [](const LeafEntry& l) {
    std::uint64_t k = 0;
    for (int a = 0; a < 3; ++a) k = k << 8 | l.lo[a];
    for (int a = 0; a < 3; ++a) k = k << 8 | l.hi[a];
    return k;
  };
  std::vector<std::pair<std::uint64_t, const LeafEntry*>> sorted;
  forEachCoveredBrick(*engine_, [&](const Key& brick, const std::vector<LeafEntry>& leaves) {
    sorted.clear();
    for (const LeafEntry& l : leaves) sorted.emplace_back(boxKey(l), &l);
    std::sort(sorted.begin(), sorted.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    for (int a = 0; a < 3; ++a) w.put(brick[a]);
    w.put(static_cast<std::uint32_t>(sorted.size()));
    for (const auto& kl : sorted) {
      std::uint8_t box[6];
      std::memcpy(box, kl.second->lo, 3);
      std::memcpy(box + 3, kl.second->hi, 3);
      w.put(box);
      w.put(kl.second->value);
    }
  });
  const std::uint64_t sum = w.checksum();
  w.flush();
  os.write(reinterpret_cast<const char*>(&sum), sizeof(sum));
  if (!os) throw std::runtime_error("rtog map: write failed");
}

OccupancyMap OccupancyMap::read(std::istream& is) {
  char magic[sizeof(kMagic)];
  if (!is.read(magic, sizeof(magic)) || std::memcmp(magic, kMagic, sizeof(kMagic)) != 0)
    throw std::runtime_error("rtog map: not an rtog map (bad magic)");
  Reader r(is);
  const auto version = r.get<std::uint32_t>("version");
  if (version != 1 && version != kFormatVersion)
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
  const std::uint64_t leaf_bytes = version == 1 ? kLeafBytesV1 : kLeafBytes;
  if (const std::int64_t left = bytesLeft(is); left >= 0 && count > std::uint64_t(left) / leaf_bytes)
    throw std::runtime_error("rtog map: the leaf count " + std::to_string(count) + " needs " +
                             std::to_string(count * leaf_bytes + 8) + " more bytes, the stream holds " +
                             std::to_string(left) + " (truncated or corrupt)");
  // Version 2: the leaves a brick at a time, each brick's key and count first.
  Key brick;
  std::uint32_t in_brick = 0;
  const auto nextLeaf = [&]() {
    Box b;
    if (version == 1) {
      for (int a = 0; a < 3; ++a) b.min[a] = r.get<std::int32_t>("leaf");
      for (int a = 0; a < 3; ++a) b.max[a] = r.get<std::int32_t>("leaf");
      return b;
    }
    while (in_brick == 0) {
      for (int a = 0; a < 3; ++a) brick[a] = r.get<std::int32_t>("brick");
      in_brick = r.get<std::uint32_t>("brick");
      const auto inRange = [](std::int32_t c) {
        return c >= (kKeyMin >> kBrickBits) && c <= (kKeyMax >> kBrickBits);  // before c * kBrickSize
      };
      if (!inRange(brick.x) || !inRange(brick.y) || !inRange(brick.z) || in_brick > std::uint32_t{kBrickCells})
        throw std::runtime_error("rtog map: malformed brick " + toString(Box::cell(brick)) + " of " +
                                 std::to_string(in_brick) + " leaves");
    }
    --in_brick;
    const auto box = r.get<std::array<std::uint8_t, 6>>("leaf");
    const Key o = brickOrigin(brick);
    for (int a = 0; a < 3; ++a) {
      b.min[a] = o[a] + box[static_cast<std::size_t>(a)];
      b.max[a] = o[a] + box[static_cast<std::size_t>(a + 3)];
    }
    return b;
  };

  OccupancyMap map(p);
  // The leaves go in as pieces of a cell assignment into a map without leaves: they become its
  // leaves as they are, checked disjoint, with one bulk load of the upper tree.
  try {
    map.engine_->integrate([&](const IntegrationContext& c) {
      std::vector<AssignedPiece>& pieces = c.scratch.assigned;
      pieces.clear();
      if (bytesLeft(is) >= 0) pieces.reserve(static_cast<std::size_t>(count));  // the count was checked
      for (std::uint64_t i = 0; i < count; ++i) {
        const Box b = nextLeaf();
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
      if (in_brick != 0) throw std::runtime_error("rtog map: a brick holds more leaves than the map's count");
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
