// rtog fuse: two maps into one by the independent opinion pool (OccupancyMap::fuse).
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <ostream>
#include <stdexcept>

#include <Eigen/Geometry>

#include "commands.hpp"
#include "rtog/app/output_files.hpp"
#include "rtog/mrpt/map_registration.h"

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
  // The translation is turned into whole cells: 1e20 m left the integer keys' range and made the
  // fusion loop for ever; 1e9 m is 1e13 cells at the finest resolution (1e-4 m), far inside it.
  for (int i = 0; i < 3; ++i)
    if (std::fabs(p[std::size_t(i)]) > 1e9) {
      char got[32];
      std::snprintf(got, sizeof(got), "%g", p[std::size_t(i)]);
      throw std::invalid_argument(std::string("fuse: --pose: x y z must lie within +-1e9 m, got ") + got);
    }
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
  InsertStats st;
  if (o.register_maps) {
    if (o.pose[2] != 0.0 || o.pose[4] != 0.0 || o.pose[5] != 0.0)
      throw std::invalid_argument("fuse: --register estimates x, y and yaw: a --pose guess must have z, pitch and roll 0");
    CRTreeOccupancyGridMap wa(a.resolution()), wb(b.resolution());
    wa.map() = std::move(a);
    wb.map() = b;
    TMapRegistrationOptions ro;
    ro.minZ = static_cast<float>(o.register_band[0]), ro.maxZ = static_cast<float>(o.register_band[1]);
    ro.guessX = o.pose[0], ro.guessY = o.pose[1], ro.guessYaw = o.pose[3] * M_PI / 180.0;
    const TMapRegistration r = registerMaps(wa, wb, ro);
    // A failed registration fuses nothing: a wrong pose or a meaningless covariance would blur
    // or misplace the second map without a sign in the output.
    if (!r.converged) throw std::runtime_error("fuse --register: " + o.map_b + " not registered: " + r.failure);
    const auto& m = r.pose.mean;
    out << "registered " << o.map_b << " at x " << m.x() << " m, y " << m.y() << " m, yaw " << m.yaw() * 180.0 / M_PI
        << " deg (sigma " << std::sqrt(r.pose.cov(0, 0)) << " m, " << std::sqrt(r.pose.cov(1, 1)) << " m, "
        << std::sqrt(r.pose.cov(3, 3)) * 180.0 / M_PI << " deg; " << r.goodness * 100.0 << " % of " << r.pointsB
        << " occupied cells matched, rms " << r.rmsResidual << " m)\n";
    wa.insertionOptions.threads = o.threads;
    st = fuseUncertain(wa, wb, r.pose);
    a = std::move(wa.map());
  } else {
    st = a.fuse(b, pose, o.threads);
  }
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
