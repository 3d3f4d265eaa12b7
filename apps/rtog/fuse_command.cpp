// rtog fuse: two maps into one by the independent opinion pool (OccupancyMap::fuse).
#include <sys/stat.h>

#include <cmath>
#include <ostream>
#include <stdexcept>

#include <Eigen/Geometry>

#include "commands.hpp"
#include "rtog/app/output_files.hpp"

namespace rtog::cli {

namespace {

/// Same device and inode: one file under two names (a link, ./a and a). Pipes are never the same.
bool sameFile(const std::string& a, const std::string& b) {
  struct stat sa {}, sb {};
  return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && S_ISREG(sa.st_mode) && sa.st_dev == sb.st_dev &&
         sa.st_ino == sb.st_ino;
}

}  // namespace

Eigen::Isometry3d poseFromXyzYpr(const std::array<double, 6>& p) {
  for (double v : p)
    if (!std::isfinite(v)) throw std::invalid_argument("fuse: --pose needs six finite numbers: x y z [m] yaw pitch roll [deg]");
  constexpr double kDeg = M_PI / 180.0;
  // MRPT's CPose3D convention: R = Rz(yaw) Ry(pitch) Rx(roll).
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translate(Eigen::Vector3d(p[0], p[1], p[2]));
  t.rotate(Eigen::AngleAxisd(p[3] * kDeg, Eigen::Vector3d::UnitZ()) *
           Eigen::AngleAxisd(p[4] * kDeg, Eigen::Vector3d::UnitY()) *
           Eigen::AngleAxisd(p[5] * kDeg, Eigen::Vector3d::UnitX()));
  return t;
}

std::pair<std::size_t, std::size_t> parseScanRange(const std::string& text) {
  const auto bad = [&] {
    return std::invalid_argument("--scans '" + text + "': need A:B with whole numbers A < B (either may be left out)");
  };
  const std::size_t colon = text.find(':');
  if (colon == std::string::npos || text.find(':', colon + 1) != std::string::npos) throw bad();
  const auto number = [&](const std::string& t, std::size_t fallback) {
    if (t.empty()) return fallback;
    if (t.find_first_not_of("0123456789") != std::string::npos || t.size() > 18) throw bad();
    return static_cast<std::size_t>(std::stoull(t));
  };
  const std::size_t a = number(text.substr(0, colon), 0), b = number(text.substr(colon + 1), static_cast<std::size_t>(-1));
  if (!(a < b)) throw bad();
  return {a, b};
}

int fuse(const FuseOptions& o, std::ostream& out) {
  if (o.out_path.empty()) throw std::invalid_argument("fuse: --out FILE is required (where the fused map goes)");
  if (sameFile(o.map_a, o.map_b))
    throw std::invalid_argument("fuse: '" + o.map_a + "' and '" + o.map_b +
                                "' are the same file: fused with itself, its evidence would count twice");
  const Eigen::Isometry3d pose = poseFromXyzYpr(o.pose);
  // The output checked (never an input) and opened before the maps are read.
  app::OutputSet files({{"map", o.map_a}, {"map", o.map_b}});
  std::ostream& dst = files.add("--out", o.out_path);
  OccupancyMap a = loadMap(o.map_a);
  const OccupancyMap b = loadMap(o.map_b);
  const std::int64_t cells_a = a.cellCount(), cells_b = b.cellCount();
  const InsertStats st = a.fuse(b, pose, o.threads);
  a.write(dst);
  files.commit();
  out << "fused " << o.map_b << " (" << cells_b << " cells) into " << o.map_a << " (" << cells_a << " cells): "
      << a.cellCount() << " cells, " << a.leafCount() << " leaves (resolution " << a.resolution() << " m)\n";
  if (st.skipped_out_of_range > 0)
    out << "left out: " << st.skipped_out_of_range << " cuboids of the second map reach beyond the key range\n";
  out << "wrote " << o.out_path << "\n";
  return 0;
}

}  // namespace rtog::cli
