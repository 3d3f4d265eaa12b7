#include "rtog/sim/sensors.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rtog::sim {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double deg2rad(double d) { return d * kPi / 180.0; }

// Fires one beam (unit direction in the map frame) and records it.
void fire(const World& w, const Eigen::Vector3d& o, const Eigen::Vector3d& dir, double max_range, RangeNoise& noise,
          Scan& s) {
  const auto hit = w.castRay(o, dir, max_range);
  const double truth = hit ? hit->t : std::numeric_limits<double>::infinity();
  double measured = max_range;
  bool returned = false;
  if (hit) {
    measured = std::max(1e-3, hit->t + noise.sample());
    returned = measured <= max_range;
    if (!returned) measured = max_range;
  }
  s.points.push_back((o + dir * measured).cast<float>());
  s.is_hit.push_back(returned ? 1 : 0);
  s.range.push_back(static_cast<float>(measured));
  s.true_range.push_back(static_cast<float>(truth));
}
}  // namespace

std::size_t Scan::hits() const {
  std::size_t n = 0;
  for (auto h : is_hit) n += h;
  return n;
}

void LidarParams::validate() const {
  if (rings < 1 || azimuth_steps < 1 || !(max_range > 0) || !(sigma >= 0) || !(elev_max_deg >= elev_min_deg) ||
      elev_min_deg < -90 || elev_max_deg > 90)
    throw std::invalid_argument("rtog::sim::LidarParams: invalid parameters");
}

int ScannerParams::beams() const { return static_cast<int>(std::lround(fov_deg / step_deg)) + 1; }

void ScannerParams::validate() const {
  if (!(fov_deg > 0 && fov_deg <= 360) || !(step_deg > 0) || !(max_range > 0) || !(sigma >= 0))
    throw std::invalid_argument("rtog::sim::ScannerParams: invalid parameters");
}

Lidar3D::Lidar3D(const LidarParams& p, std::uint32_t seed) : p_(p), noise_(p.sigma, seed) {
  p_.validate();
  dirs_.reserve(static_cast<std::size_t>(p_.rings) * p_.azimuth_steps);
  for (int r = 0; r < p_.rings; ++r) {
    const double e = p_.rings == 1 ? deg2rad(0.5 * (p_.elev_min_deg + p_.elev_max_deg))
                                   : deg2rad(p_.elev_min_deg + (p_.elev_max_deg - p_.elev_min_deg) * r / (p_.rings - 1));
    for (int a = 0; a < p_.azimuth_steps; ++a) {
      const double az = 2.0 * kPi * a / p_.azimuth_steps;
      dirs_.emplace_back(std::cos(e) * std::cos(az), std::cos(e) * std::sin(az), std::sin(e));
    }
  }
}

Scan Lidar3D::scan(const World& w, const Pose& pose) {
  Scan s;
  s.origin = pose.position + Eigen::Vector3d(0, 0, p_.height);
  const double c = std::cos(pose.yaw), sn = std::sin(pose.yaw);
  s.points.reserve(dirs_.size());
  for (const auto& d : dirs_) {
    const Eigen::Vector3d dm(c * d.x() - sn * d.y(), sn * d.x() + c * d.y(), d.z());
    fire(w, s.origin, dm, p_.max_range, noise_, s);
  }
  return s;
}

PlanarScanner::PlanarScanner(const ScannerParams& p, std::uint32_t seed) : p_(p), noise_(p.sigma, seed) {
  p_.validate();
}

double PlanarScanner::angle(int i) const { return deg2rad(-0.5 * p_.fov_deg + p_.step_deg * i); }

Scan PlanarScanner::scan(const World& w, const Pose& pose) {
  Scan s;
  s.origin = pose.position + Eigen::Vector3d(0, 0, p_.height);
  const int n = p_.beams();
  s.points.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double a = pose.yaw + angle(i);
    fire(w, s.origin, Eigen::Vector3d(std::cos(a), std::sin(a), 0.0), p_.max_range, noise_, s);
  }
  return s;
}

SimulatedLog simulate(const World& w, const LidarParams& lp, const ScannerParams& sp, std::uint32_t lidar_seed,
                      std::uint32_t scanner_seed, int stride) {
  if (stride < 1) throw std::invalid_argument("rtog::sim::simulate: stride must be >= 1");
  Lidar3D lidar(lp, lidar_seed);
  PlanarScanner scanner(sp, scanner_seed);
  SimulatedLog log;
  for (std::size_t i = 0; i < w.trajectory().size(); i += static_cast<std::size_t>(stride)) {
    const Pose& pose = w.trajectory()[i];
    log.poses.push_back(pose);
    log.lidar.push_back(lidar.scan(w, pose));
    log.planar.push_back(scanner.scan(w, pose));
  }
  return log;
}

Scan displaced(const Scan& s, const PoseError& e) {
  Scan out = s;
  const double c = std::cos(e.dyaw), sn = std::sin(e.dyaw);
  const Eigen::Vector3d shift(e.dx, e.dy, 0.0);
  for (auto& p : out.points) {
    const Eigen::Vector3d d = p.cast<double>() - s.origin;
    p = (s.origin + shift + Eigen::Vector3d(c * d.x() - sn * d.y(), sn * d.x() + c * d.y(), d.z())).cast<float>();
  }
  out.origin = s.origin + shift;
  return out;
}

std::vector<PoseError> samplePoseErrors(std::size_t n, double sigma_xy, double sigma_yaw, std::uint32_t seed,
                                        double correlation) {
  if (!(sigma_xy >= 0) || !(sigma_yaw >= 0) || !std::isfinite(sigma_xy) || !std::isfinite(sigma_yaw))
    throw std::invalid_argument("rtog::sim::samplePoseErrors: sigmas must be finite and >= 0");
  if (!(correlation >= 0 && correlation < 1))
    throw std::invalid_argument("rtog::sim::samplePoseErrors: the correlation must be in [0, 1)");
  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const double rho = correlation, fresh = std::sqrt(1.0 - rho * rho);
  std::vector<PoseError> out(n);
  for (std::size_t k = 0; k < n; ++k) {
    const PoseError prev = k == 0 ? PoseError{} : out[k - 1];
    const double a = k == 0 ? 1.0 : fresh, r = k == 0 ? 0.0 : rho;
    out[k].dx = r * prev.dx + a * sigma_xy * unit(rng);
    out[k].dy = r * prev.dy + a * sigma_xy * unit(rng);
    out[k].dyaw = r * prev.dyaw + a * sigma_yaw * unit(rng);
  }
  return out;
}

}  // namespace rtog::sim
