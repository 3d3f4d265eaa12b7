#include "rtog/mrpt/tiled_map.h"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "rtog/mrpt/map_file.h"

namespace rtog {
namespace {

std::string joined(const std::string& dir, const std::string& name) { return dir + "/" + name; }

[[noreturn]] void bad(const std::string& path, int line, const std::string& why) {
  throw std::runtime_error("tile index '" + path + "', line " + std::to_string(line) + ": " + why);
}

/// Tiles of one map: the same log-odds rule and merging (the resolution is the index's).
bool sameRule(const MapParams& a, const MapParams& b) {
  const LogOddsParams &x = a.log_odds, &y = b.log_odds;
  return x.prob_hit == y.prob_hit && x.prob_miss == y.prob_miss && x.clamp_min == y.clamp_min &&
         x.clamp_max == y.clamp_max && x.occupied_threshold == y.occupied_threshold && x.prior == y.prior &&
         a.merge == b.merge;
}

}  // namespace

TiledMapIndex TiledMapIndex::read(const std::string& dir) {
  const std::string path = joined(dir, kFile);
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open tile index '" + path + "' (not a tiled map, or a build that failed)");
  TiledMapIndex idx;
  std::string line, word;
  int lineno = 0;
  if (!std::getline(in, line) || line != "rtog-tiles 1") bad(path, 1, "expected 'rtog-tiles 1'");
  ++lineno;
  while (std::getline(in, line)) {
    ++lineno;
    std::istringstream ls(line);
    if (!(ls >> word)) continue;
    if (word == "resolution") {
      if (!(ls >> idx.resolution) || !(idx.resolution > 0.0) || !std::isfinite(idx.resolution))
        bad(path, lineno, "bad resolution");
    } else if (word == "tile") {
      TileInfo t;
      Key& a = t.region.min;
      Key& b = t.region.max;
      if (!(ls >> t.file >> a.x >> a.y >> a.z >> b.x >> b.y >> b.z >> t.leaves >> t.cells) || t.region.isEmpty() ||
          t.file.find('/') != std::string::npos)
        bad(path, lineno, "expected 'tile FILE x0 y0 z0 x1 y1 z1 LEAVES CELLS'");
      idx.tiles.push_back(t);
    } else {
      bad(path, lineno, "unknown entry '" + word + "'");
    }
  }
  if (!(idx.resolution > 0.0)) bad(path, lineno, "no resolution");
  for (std::size_t i = 0; i < idx.tiles.size(); ++i)
    for (std::size_t j = i + 1; j < idx.tiles.size(); ++j)
      if (idx.tiles[i].region.intersects(idx.tiles[j].region))
        bad(path, lineno, "tiles '" + idx.tiles[i].file + "' and '" + idx.tiles[j].file + "' overlap");
  return idx;
}

void TiledMapIndex::write(const std::string& dir) const {
  const std::string path = joined(dir, kFile), tmp = path + ".part";
  {
    std::ofstream out(tmp);
    out << "rtog-tiles 1\nresolution " << std::setprecision(17) << resolution << "\n";
    for (const TileInfo& t : tiles)
      out << "tile " << t.file << " " << t.region.min.x << " " << t.region.min.y << " " << t.region.min.z << " "
          << t.region.max.x << " " << t.region.max.y << " " << t.region.max.z << " " << t.leaves << " " << t.cells << "\n";
    if (!out.flush()) throw std::runtime_error("cannot write tile index '" + tmp + "'");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) throw std::runtime_error("cannot write tile index '" + path + "'");
}

bool isTiledMap(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode) && ::stat(joined(path, TiledMapIndex::kFile).c_str(), &st) == 0;
}

TileInfo writeTile(const OccupancyMap& tile, const std::string& dir, const std::string& name) {
  const std::string path = joined(dir, name);
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write tile '" + path + "'");
  tile.write(out);
  if (!out.flush()) throw std::runtime_error("cannot write tile '" + path + "'");
  return TileInfo{name, tile.region(), tile.leafCount(), tile.cellCount()};
}

OccupancyMap loadTiles(const std::string& dir, const Box& region) {
  const TiledMapIndex idx = TiledMapIndex::read(dir);
  std::vector<Box> boxes;
  std::vector<float> values;
  std::optional<MapParams> params;
  for (const TileInfo& t : idx.tiles) {
    if (!region.isEmpty() && !region.intersects(t.region)) continue;
    const std::string path = joined(dir, t.file);
    const OccupancyMap tile = std::move(loadMapFile(path)->map());
    const MapParams& p = tile.params();
    if (p.resolution != idx.resolution) throw std::runtime_error("tile '" + path + "': its resolution is not the index's");
    if (params && !sameRule(p, *params))
      throw std::runtime_error("tile '" + path + "': its rule is not the other tiles'");
    if (!params) params = p;
    tile.forEachLeaf([&](const Box& b, float v) {
      if (!t.region.contains(b)) throw std::runtime_error("tile '" + path + "': a leaf lies outside its region");
      boxes.push_back(b);
      values.push_back(v);
    });
  }
  if (!params) {
    MapParams p;
    p.resolution = idx.resolution;
    params = p;
  }
  OccupancyMap map(*params);
  if (!boxes.empty()) map.assignCells(boxes.data(), values.data(), boxes.size());
  return map;
}

std::shared_ptr<CRTreeOccupancyGridMap> loadTiledMap(const std::string& dir, const Eigen::Vector3d& lo,
                                                     const Eigen::Vector3d& hi) {
  const TiledMapIndex idx = TiledMapIndex::read(dir);
  const Lattice lattice(idx.resolution);
  Key a, b;
  if (!lattice.tryKey(lo, a) || !lattice.tryKey(hi, b) || a.x > b.x || a.y > b.y || a.z > b.z)
    throw std::invalid_argument("loadTiledMap: the box must be finite, within the key range, its low corner below its high one");
  return wrapCoreMap(loadTiles(dir, Box{a, b}));
}

std::vector<Box> balancedSlabs(const std::vector<std::pair<std::int32_t, double>>& work_x,
                               const std::vector<std::pair<std::int32_t, double>>& work_y, int n) {
  if (n < 1) throw std::invalid_argument("balancedSlabs: n must be >= 1");
  const auto extent = [](const std::vector<std::pair<std::int32_t, double>>& w) {
    if (w.empty()) return std::int64_t{0};
    const auto [lo, hi] = std::minmax_element(w.begin(), w.end());
    return std::int64_t{hi->first} - lo->first;
  };
  const int axis = extent(work_y) > extent(work_x) ? 1 : 0;
  std::map<std::int32_t, double> per;  // brick column -> work, in order
  for (const auto& [c, w] : axis == 0 ? work_x : work_y) per[c] += w;
  double total = 0.0;
  for (const auto& [c, w] : per) total += w;
  std::vector<std::int32_t> cuts;  // first brick of each slab after the first
  double acc = 0.0;
  for (auto it = per.begin(); it != per.end() && int(cuts.size()) + 1 < n; ++it) {
    acc += it->second;
    const auto next = std::next(it);
    if (next != per.end() && acc >= total * double(cuts.size() + 1) / n) cuts.push_back(next->first);
  }
  std::vector<Box> slabs;
  std::int32_t from = kKeyMin;
  const auto slab = [&](std::int32_t lo, std::int32_t hi) {
    Box b{Key{kKeyMin, kKeyMin, kKeyMin}, Key{kKeyMax, kKeyMax, kKeyMax}};
    b.min[axis] = lo, b.max[axis] = hi;
    slabs.push_back(b);
  };
  for (std::int32_t c : cuts) slab(from, c * (1 << kBrickBits) - 1), from = c * (1 << kBrickBits);
  slab(from, kKeyMax);
  return slabs;
}

}  // namespace rtog
