#include "commands.hpp"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <ostream>

#include "rtog/image/tum_dataset.hpp"

namespace rtog::cli {

OccupancyMap loadMap(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open map file '" + path + "'");
  try {
    return OccupancyMap::read(in);
  } catch (const std::exception& e) {
    throw std::runtime_error("'" + path + "': " + e.what());
  }
}

void saveMap(const OccupancyMap& map, const std::string& path) {
  const std::string tmp = path + ".partial";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write '" + tmp + "'");
    map.write(out);
    out.close();
    if (!out) {
      std::remove(tmp.c_str());
      throw std::runtime_error("writing '" + tmp + "' failed");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error("cannot rename '" + tmp + "' to '" + path + "'");
  }
}

void printStatistics(const OccupancyMap& map, std::ostream& out) {
  const MapStatistics s = map.statistics();
  const double res = map.resolution();
  out << "resolution        " << res << " m\n"
      << "merge policy      " << toString(map.params().merge) << "\n"
      << "leaves (cuboids)  " << s.leaves << "  (occupied " << s.occupied_leaves << ", free " << s.free_leaves
      << ")\n"
      << "cells covered     " << s.cells << "  (occupied " << s.occupied_cells << ", free " << s.free_cells << ")\n"
      << "cells per leaf    " << std::fixed << std::setprecision(2) << (s.leaves ? double(s.cells) / s.leaves : 0.0)
      << "\n"
      << "R-tree            height " << s.tree_height << ", " << s.tree_nodes << " nodes, " << s.bricks
      << " bricks\n"
      << "memory            " << std::setprecision(2) << s.memory_bytes / 1048576.0 << " MiB\n";
  if (!s.bounds.isEmpty()) {
    const auto lo = map.lattice().boxMin(s.bounds), hi = map.lattice().boxMax(s.bounds);
    out << std::setprecision(2) << "bounds            [" << lo.x() << ", " << lo.y() << ", " << lo.z() << "] .. ["
        << hi.x() << ", " << hi.y() << ", " << hi.z() << "] m\n";
  }
  out.unsetf(std::ios::floatfield);
}

int buildFromTum(const BuildTumOptions& opts, std::ostream& out) {
  const image::DepthSequence seq = image::readTumSequence(opts.tum_dir);
  OccupancyMap map(opts.map);
  InsertStats total;
  double seconds = 0.0;
  std::size_t points = 0;
  for (std::size_t i = 0; i < seq.frames.size(); ++i) {
    const image::WorldScan scan = image::loadDepthScan(seq.frames[i], seq.intrinsics, opts.stride);
    const auto t0 = std::chrono::steady_clock::now();
    total += map.insertPointCloud(scan.origin, scan.points, opts.insert);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    points += scan.points.size();
    out << "frame " << (i + 1) << "/" << seq.frames.size() << ": " << scan.points.size() << " points, "
        << map.leafCount() << " leaves\n";
  }
  out << "inserted " << points << " points from " << seq.frames.size() << " frames in " << std::fixed
      << std::setprecision(3) << seconds << " s (" << std::setprecision(2) << points / seconds / 1e6
      << " M points/s), sensor model " << toString(opts.insert.model) << "\n";
  out.unsetf(std::ios::floatfield);
  out << "skipped: " << total.skipped_non_finite << " non-finite, " << total.skipped_zero_length << " zero-length, "
      << total.skipped_out_of_range << " out of range; " << total.leaves_merged << " merges, "
      << total.leaves_split << " splits\n";
  printStatistics(map, out);
  if (!opts.out_path.empty()) {
    saveMap(map, opts.out_path);
    out << "saved             " << opts.out_path << "\n";
  }
  return 0;
}

int info(const std::string& map_path, bool json, std::ostream& out) {
  const OccupancyMap map = loadMap(map_path);
  if (!json) {
    printStatistics(map, out);
    return 0;
  }
  const MapStatistics s = map.statistics();
  out << "{\"resolution\": " << map.resolution() << ", \"merge\": \"" << toString(map.params().merge)
      << "\", \"leaves\": " << s.leaves << ", \"occupied_leaves\": " << s.occupied_leaves
      << ", \"free_leaves\": " << s.free_leaves << ", \"cells\": " << s.cells
      << ", \"occupied_cells\": " << s.occupied_cells << ", \"free_cells\": " << s.free_cells
      << ", \"memory_bytes\": " << s.memory_bytes << "}\n";
  return 0;
}

}  // namespace rtog::cli
