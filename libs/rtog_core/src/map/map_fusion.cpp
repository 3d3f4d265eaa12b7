// Fusion of another map into this one by the independent opinion pool (the estimator seed,
// section 3): P = P1 P2 / (P1 P2 + (1 - P1)(1 - P2)) with the prior P0 counted once, which in
// log-odds is l = l1 + l2 - l0, clamped. The other map's evidence enters as one update whose
// change in a cell is l2 - l0 of the other map's cell there, through the graded path that
// range-noise scans take: each cell once, brick by brick, the map independent of the threads.
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "integrate/fusion_integrator.hpp"
#include "map/map_engine.hpp"
#include "rtog/core/occupancy_map.hpp"

namespace rtog {

namespace {

void checkRigid(const Eigen::Isometry3d& pose) {
  const Eigen::Matrix3d r = pose.linear();
  const bool finite = pose.matrix().allFinite();
  if (!finite || !(r.transpose() * r).isIdentity(1e-9) || !(r.determinant() > 0.0))
    throw std::invalid_argument(
        "rtog::OccupancyMap::fuse: the pose must be rigid (finite, a rotation and a translation)");
}

}  // namespace

InsertStats OccupancyMap::fuse(const OccupancyMap& other, const Eigen::Isometry3d& pose, int threads) {
  if (&other == this)
    throw std::invalid_argument("rtog::OccupancyMap::fuse: a map fused with itself would count its evidence twice");
  checkRigid(pose);
  if (threads < 1) throw std::invalid_argument("rtog::OccupancyMap::fuse: threads must be at least 1");
  return engine_->integrate([&](const IntegrationContext& c) { return FusionIntegrator(c).trace(other, pose, threads); });
}

InsertStats OccupancyMap::fuse(const OccupancyMap& other, const std::vector<WeightedPose>& poses, int threads) {
  if (&other == this)
    throw std::invalid_argument("rtog::OccupancyMap::fuse: a map fused with itself would count its evidence twice");
  if (threads < 1) throw std::invalid_argument("rtog::OccupancyMap::fuse: threads must be at least 1");
  double total = 0.0;
  for (const WeightedPose& w : poses) {
    checkRigid(w.pose);
    if (!(std::isfinite(w.weight) && w.weight > 0.0))
      throw std::invalid_argument("rtog::OccupancyMap::fuse: each pose's weight must be finite and positive");
    total += w.weight;
  }
  if (poses.empty() || !(std::fabs(total - 1.0) < 1e-9))
    throw std::invalid_argument("rtog::OccupancyMap::fuse: the poses' weights must sum to 1");
  return engine_->integrate([&](const IntegrationContext& c) { return FusionIntegrator(c).trace(other, poses, threads); });
}

}  // namespace rtog
