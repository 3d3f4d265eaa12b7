// `rtog build --tiles`: a map split by space (doc/scale-out.md). Every rank reads the whole log;
// a cheap first pass measures the work and the memory per brick column; the tiles are slabs of
// about equal shares of both; each rank builds its tiles (maps restricted to them, fed every
// scan: exactly the single build's cells there) and writes them; rank 0 writes the index last,
// only if every rank succeeded.
#include <sys/resource.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iomanip>
#include <map>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include "build_log.hpp"
#include "ranks.hpp"
#include "rtog/mrpt/error_line.h"
#include "rtog/mrpt/tiled_map.h"

namespace rtog::cli {
namespace {

/// What each brick column across x and y holds, from a sample of the log: every 8th beam of
/// about 1,000 scans spread over the log, sampled every half brick from its origin to its end.
/// `work` counts the samples (the cells the beams step); `bricks` the distinct bricks they meet
/// (the map's memory: its leaves cover what sensors saw, however often it was crossed; a set of
/// finer blocks would cost the pass more memory than some maps). Only the shares count, not the
/// totals.
struct ColumnLoad {
  std::unordered_map<std::int32_t, double> work, bricks;

  /// Per column, its share of the work plus its share of the bricks: slabs of equal weight
  /// balance both, within what a cut between whole columns allows.
  std::vector<std::pair<std::int32_t, double>> weights() const {
    double w = 0.0, b = 0.0;
    for (const auto& [c, v] : work) w += v;
    for (const auto& [c, v] : bricks) b += v;
    std::map<std::int32_t, double> sum;
    for (const auto& [c, v] : work) sum[c] += w > 0.0 ? v / w : 0.0;
    for (const auto& [c, v] : bricks) sum[c] += b > 0.0 ? v / b : 0.0;
    return {sum.begin(), sum.end()};
  }
};

void firstPass(const BuildOptions& o, const BuildLog& log, const CRTreeOccupancyGridMap& map, ColumnLoad& x,
               ColumnLoad& y) {
  const double cell = map.resolution(), step = double((1 << kBrickBits) / 2) * cell;
  const double max_range = map.insertionOptions.maxDistanceInsertion;
  const std::size_t every = std::max<std::size_t>(1, logSize(log) / 1000);
  std::unordered_set<std::uint64_t> seen;  // packKey of the bricks met
  forEachBeams(o, log, map, every, [&](const Eigen::Vector3d& origin, const std::vector<Eigen::Vector3f>& pts) {
    for (std::size_t i = 0; i < pts.size(); i += 8) {
      Eigen::Vector3d d = pts[i].cast<double>() - origin;
      double len = d.norm();
      if (!std::isfinite(len) || len <= 0.0) continue;
      if (max_range > 0.0) len = std::min(len, double(max_range));
      d /= d.norm();
      Key last{kKeyMax, kKeyMax, kKeyMax};  // no brick: brick coordinates are far smaller
      for (double t = 0.0; t <= len; t += step) {
        const Eigen::Array3d c = ((origin + t * d) / cell).array().floor();
        // A cell beyond the key range is one the map skips (and the cast's range ends there).
        if (!(c.abs().maxCoeff() <= double(kKeyMax))) continue;
        const Key b{static_cast<std::int32_t>(c.x()) >> kBrickBits, static_cast<std::int32_t>(c.y()) >> kBrickBits,
                    static_cast<std::int32_t>(c.z()) >> kBrickBits};
        x.work[b.x] += 1.0;
        y.work[b.y] += 1.0;
        if (b == last) continue;
        last = b;
        if (seen.insert(packKey(b)).second) x.bricks[b.x] += 1.0, y.bricks[b.y] += 1.0;
      }
    }
  });
}

double peakRssMb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}

void makeDirectory(const std::string& dir) {
  if (::mkdir(dir.c_str(), 0777) != 0 && errno != EEXIST)
    throw std::runtime_error("cannot make the tiles' directory '" + dir + "': " + std::strerror(errno));
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw std::runtime_error("'" + dir + "' is not a directory (--tiles writes a directory of tiles)");
}

/// This rank's tiles: read the log, measure the work, cut the slabs, build and write the tiles
/// i = rank, rank + size, ...; one report line a tile.
std::string buildOwnTiles(const BuildOptions& o, const Ranks& ranks, int n,
                          std::chrono::steady_clock::time_point t0, std::ostream& say) {
  std::ostringstream mine;
  const BuildLog log = readBuildLog(o, say);
  const auto probe = makeBuildMap(o);
  ColumnLoad x, y;
  firstPass(o, log, *probe, x, y);
  const std::vector<Box> slabs = balancedSlabs(x.weights(), y.weights(), n);
  const double first_pass = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  say << "tiles: " << slabs.size() << " slabs of about equal work and memory (first pass " << std::fixed << std::setprecision(3)
      << first_pass << " s), " << ranks.size() << " rank" << (ranks.size() == 1 ? "" : "s") << "\n";
  say.unsetf(std::ios::floatfield);
  for (std::size_t i = std::size_t(ranks.rank()); i < slabs.size(); i += std::size_t(ranks.size())) {
    auto map = makeBuildMap(o);
    map->map().setRegion(slabs[i]);
    const FeedFigures f = feedMap(o, log, *map, nullptr);
    map->map().flush();
    char name[32];
    std::snprintf(name, sizeof name, "tile_%04zu.rtog", i);
    const TileInfo t = writeTile(map->map(), o.out_path, name);
    const Box& r = t.region;
    mine << "tile " << t.file << " " << r.min.x << " " << r.min.y << " " << r.min.z << " " << r.max.x << " " << r.max.y
         << " " << r.max.z << " " << t.leaves << " " << t.cells << " " << f.seconds << " " << f.points << "\n";
  }
  return mine.str();
}

constexpr int kAutoTilesPerRank = 4;

}  // namespace

int buildTiles(const BuildOptions& o, std::ostream& out) {
  if (o.out_path.empty()) throw std::invalid_argument("--tiles needs --out DIR (the directory of the tiles)");
  Ranks ranks;
  // A rank builds its tiles one after another: its memory is its largest tile's, and a smaller
  // tile's layers stay in the processor's caches (doc/scale-out.md), for one more reading of the
  // log a tile.
  int n = kAutoTilesPerRank * ranks.size();
  if (o.tiles != "auto") {
    std::size_t used = 0;
    try {
      n = std::stoi(o.tiles, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != o.tiles.size() || n < 1 || n > 4096)
      throw std::invalid_argument("--tiles: expected a count in [1, 4096] or 'auto', got '" + o.tiles + "'");
  }
  std::ostringstream quiet;
  std::ostream& say = ranks.rank() == 0 ? out : quiet;
  // A failure anywhere is every rank's: each tries its part, then all learn whether all succeeded.
  std::string error;
  std::ostringstream mine;  // this rank's tiles: "tile FILE region leaves cells seconds beams"
  const auto t0 = std::chrono::steady_clock::now();
  try {
    if (ranks.rank() == 0) {
      makeDirectory(o.out_path);
      std::remove((o.out_path + "/" + TiledMapIndex::kFile).c_str());  // the old map is gone until the new one is whole
    }
  } catch (const std::exception& e) {
    error = "rank 0: " + errorLine(e);
  }
  // Every rank reaches this, whatever rank 0 met: after it the directory exists, or no rank builds.
  const bool directory_ok = ranks.all(error.empty());
  if (directory_ok) {
    try {
      mine << buildOwnTiles(o, ranks, n, t0, say);
    } catch (const std::exception& e) {
      error = "rank " + std::to_string(ranks.rank()) + ": " + errorLine(e);
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  mine << "rank " << ranks.rank() << " " << seconds << " " << peakRssMb() << "\n";
  const bool ok = ranks.all(error.empty());
  const std::vector<std::string> reports = ranks.gather(error.empty() ? mine.str() : "error " + error + "\n");
  if (ranks.rank() != 0) return ok ? 0 : 1;
  if (!ok) {
    for (const std::string& r : reports)
      if (r.rfind("error ", 0) == 0) out << "rtog: error: " << r.substr(6);
    out << "no tile index written: '" << o.out_path << "' is not a map\n";
    return 1;
  }
  TiledMapIndex idx;
  idx.resolution = makeBuildMap(o)->resolution();
  std::size_t leaves = 0;
  std::int64_t cells = 0;
  for (const std::string& r : reports) {
    std::istringstream in(r);
    std::string word;
    while (in >> word) {
      if (word == "tile") {
        TileInfo t;
        double s = 0;
        std::size_t beams = 0;
        in >> t.file >> t.region.min.x >> t.region.min.y >> t.region.min.z >> t.region.max.x >> t.region.max.y >>
            t.region.max.z >> t.leaves >> t.cells >> s >> beams;
        out << "  " << t.file << ": " << t.leaves << " leaves, " << t.cells << " cells, inserted in " << s << " s\n";
        leaves += t.leaves, cells += t.cells;
        idx.tiles.push_back(t);
      } else if (word == "rank") {
        int rank = 0;
        double s = 0, rss = 0;
        in >> rank >> s >> rss;
        out << "  rank " << rank << ": " << s << " s, peak RSS " << rss << " MB\n";
      }
    }
  }
  idx.write(o.out_path);
  out << "tiled map: " << idx.tiles.size() << " tiles, " << leaves << " leaves, " << cells << " cells\n";
  out << "saved             " << o.out_path << " (" << TiledMapIndex::kFile << " and its tiles)\n";
  return 0;
}

}  // namespace rtog::cli
