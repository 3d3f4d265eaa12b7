// Simulated range sensors against a World: a multi-ring 3D LiDAR and a planar 2D scanner,
// both with Gaussian range noise from their own seeded std::mt19937.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "rtog/sim/world.hpp"

namespace rtog::sim {

/// One simulated sweep, in the map frame.
struct Scan {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< sensor position
  std::vector<Eigen::Vector3f> points;  ///< end points; a no-return beam ends at max_range
  std::vector<std::uint8_t> is_hit;     ///< 1: a return; 0: no return within max_range
  std::vector<float> range;             ///< measured range (max_range for a no-return) [m]
  std::vector<float> true_range;        ///< exact distance to the first surface (inf: none)
  std::size_t hits() const;
};

struct LidarParams {
  int rings = 16;                 ///< vertical channels, evenly spread over [elev_min, elev_max]
  double elev_min_deg = -15.0, elev_max_deg = 15.0;
  int azimuth_steps = 1024;       ///< beams per ring over 360 degrees
  double max_range = 10.0;        ///< [m]
  double sigma = 0.02;            ///< range noise standard deviation [m]; 0: exact
  double height = 1.2;            ///< sensor height above the pose [m]
  void validate() const;
};

struct ScannerParams {
  double fov_deg = 270.0;         ///< field of view, centred on the heading
  double step_deg = 0.5;          ///< angular step
  double max_range = 10.0;        ///< [m]
  double sigma = 0.02;            ///< range noise standard deviation [m]; 0: exact
  double height = 0.3;            ///< scan plane height above the pose [m]
  int beams() const;              ///< fov / step + 1
  void validate() const;
};

/// A measured range from an exact one: noise, then no-return if beyond max_range.
class RangeNoise {
 public:
  RangeNoise(double sigma, std::uint32_t seed) : sigma_(sigma), rng_(seed), normal_(0.0, sigma > 0 ? sigma : 1.0) {}
  double sample() { return sigma_ > 0 ? normal_(rng_) : 0.0; }

 private:
  double sigma_;
  std::mt19937 rng_;
  std::normal_distribution<double> normal_;
};

class Lidar3D {
 public:
  explicit Lidar3D(const LidarParams& p, std::uint32_t seed = 0x11DA2u);
  const LidarParams& params() const { return p_; }
  /// Beam directions in the sensor frame (unit vectors), ring-major.
  const std::vector<Eigen::Vector3d>& directions() const { return dirs_; }
  Scan scan(const World& w, const Pose& pose);

 private:
  LidarParams p_;
  std::vector<Eigen::Vector3d> dirs_;
  RangeNoise noise_;
};

class PlanarScanner {
 public:
  explicit PlanarScanner(const ScannerParams& p, std::uint32_t seed = 0x2D5CAu);
  const ScannerParams& params() const { return p_; }
  /// Beam i points at heading + angle(i); angle(0) = -fov/2 (right), counter-clockwise.
  double angle(int i) const;
  Scan scan(const World& w, const Pose& pose);

 private:
  ScannerParams p_;
  RangeNoise noise_;
};

/// An error of a planar pose: the robot believes it stands at (x + dx, y + dy) heading yaw + dyaw.
struct PoseError {
  double dx = 0.0, dy = 0.0, dyaw = 0.0;
};

/// The scan as a robot that is wrong about its pose by `e` places it in the map: every point
/// rotated by dyaw about the vertical through the sensor (which stands above the pose), then
/// points and origin shifted by (dx, dy). Flags and ranges are unchanged.
Scan displaced(const Scan& s, const PoseError& e);

/// `n` pose errors along a trajectory, each component a stationary Gauss-Markov sequence:
/// e_0 ~ N(0, sigma^2), e_{k+1} = rho e_k + sqrt(1 - rho^2) sigma n_k, so every error has
/// dx, dy ~ N(0, sigma_xy^2), dyaw ~ N(0, sigma_yaw^2) [rad] and consecutive errors correlate by
/// `correlation` = rho in [0, 1) (0: independent; near 1: the slowly drifting error of dead
/// reckoning or of a SLAM map). From their own std::mt19937 (deterministic for a seed). Throws
/// std::invalid_argument for a negative or non-finite sigma or rho outside [0, 1).
std::vector<PoseError> samplePoseErrors(std::size_t n, double sigma_xy, double sigma_yaw, std::uint32_t seed,
                                        double correlation = 0.0);

/// All scans of both sensors along the world's trajectory.
struct SimulatedLog {
  std::vector<Scan> lidar;
  std::vector<Scan> planar;
  std::vector<Pose> poses;
};
/// Simulates every `stride`-th pose of the trajectory. Deterministic for given seeds.
SimulatedLog simulate(const World& w, const LidarParams& lp, const ScannerParams& sp, std::uint32_t lidar_seed,
                      std::uint32_t scanner_seed, int stride = 1);

}  // namespace rtog::sim
