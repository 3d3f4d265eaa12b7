#include "integrate/graded_scan.hpp"

#include <algorithm>
#include <cmath>

#include "integrate/beams.hpp"
#include "rtog/core/ray_traversal.hpp"
#include "storage/brick.hpp"

namespace rtog {
namespace {

// Where the line origin + t * dir (lattice units, |dir| = 1) is inside cell k: [t_in, t_out].
void cellInterval(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, const Key& k, double& t_in,
                  double& t_out) {
  t_in = 0.0;
  t_out = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (dir[a] == 0.0) continue;
    const double t1 = (double(k[a]) - origin[a]) / dir[a], t2 = (double(k[a]) + 1.0 - origin[a]) / dir[a];
    t_in = std::max(t_in, std::min(t1, t2));
    t_out = std::min(t_out, std::max(t1, t2));
  }
  t_out = std::max(t_out, t_in);  // a cell the walk only grazes (rounding): a point
}

}  // namespace

void GradedScan::clear() {
  index_.clear();
  keys_.clear();
  deltas_.clear();
  bricks_.clear();
  first_.clear();
  cells_.clear();
}

std::size_t GradedScan::memoryBytes() const {
  return index_.memoryBytes() + keys_.capacity() * sizeof(Key) + deltas_.capacity() * sizeof(float) +
         order_.capacity() * sizeof(order_[0]) + bricks_.capacity() * sizeof(Key) +
         first_.capacity() * sizeof(std::uint32_t) + cells_.capacity() * sizeof(GradedCell);
}

void GradedScan::finalize() {
  order_.clear();
  order_.reserve(keys_.size());
  for (std::uint32_t i = 0; i < keys_.size(); ++i)
    order_.emplace_back(mortonCode(brickOf(keys_[i])), static_cast<std::uint64_t>(localIndex(keys_[i])) << 32 | i);
  std::sort(order_.begin(), order_.end());
  bricks_.clear();
  first_.clear();
  cells_.clear();
  cells_.reserve(order_.size());
  for (std::size_t j = 0; j < order_.size(); ++j) {
    const auto pos = static_cast<std::uint32_t>(order_[j].second);
    const Key& k = keys_[pos];
    if (j == 0 || order_[j].first != order_[j - 1].first) {
      bricks_.push_back(brickOf(k));
      first_.push_back(static_cast<std::uint32_t>(cells_.size()));
    }
    cells_.push_back(GradedCell{static_cast<std::uint16_t>(localIndex(k)), deltas_[pos]});
  }
  first_.push_back(static_cast<std::uint32_t>(cells_.size()));
}

void GradedScan::traceRangeNoise(const Lattice& lattice, const LogOddsModel& model, const Eigen::Vector3d& origin,
                                 const Eigen::Vector3f* points, std::size_t count, const InsertParams& ip,
                                 const std::uint8_t* is_hit, InsertStats& stats) {
  const Key origin_key = lattice.key(origin);  // throws for a bad origin
  const Eigen::Vector3d origin_l = lattice.toLattice(origin);
  const BeamRules rules(lattice, ip);
  const RangeNoiseRule noise(model, ip);
  const double res = lattice.resolution();
  Eigen::Vector3d end;
  Key end_key;
  for (std::size_t i = 0; i < count; ++i) {
    const BeamEnd kind = rules.classify(origin, points[i].cast<double>(), is_hit == nullptr || is_hit[i] != 0, end, end_key);
    if (!BeamRules::count(kind, stats)) continue;
    const Eigen::Vector3d end_l = rules.walkEnd(end, end_key);
    const auto freeUpToEnd = [&](const Key& k) { mark(k, model.missDelta()); };
    const double r = (end - origin).norm();
    const double sigma = noise.sigma(r);
    if (kind != BeamEnd::Hit || sigma == 0.0) {  // the beam model's marks (its sigma -> 0 limit)
      if (kind == BeamEnd::Hit) mark(end_key, model.hitDelta());
      traverseRay(origin_l, end_l, origin_key, end_key, freeUpToEnd);
      continue;
    }
    // The walk goes on to the far edge of the band, unless that has no key or is too long.
    const Eigen::Vector3d dir = (end - origin) / r;
    const Eigen::Vector3d far = origin + dir * (r + noise.reach(sigma));
    Key far_key;
    Eigen::Vector3d far_l = end_l;
    if (lattice.tryKey(far, far_key) &&
        (ip.max_ray_cells == 0 || (far - origin).norm() <= double(ip.max_ray_cells) * res)) {
      far_l = lattice.toLattice(far);
    } else {
      far_key = end_key;
    }
    if (far_key == end_key) far_l = end_l;  // the beam model's walk, exactly
    const Eigen::Vector3d dir_l = (far_l - origin_l).normalized();
    // Cells before the end cell end before the reading, the end cell holds it, later cells
    // start after it, whatever the rounding of their intervals.
    bool past_end = false;
    const auto visit = [&](const Key& k) {
      double t_in, t_out;
      cellInterval(origin_l, dir_l, k, t_in, t_out);
      t_in *= res;
      t_out *= res;
      if (k == end_key) {
        past_end = true;
        t_in = std::min(t_in, r);
        t_out = std::max(t_out, r);
      } else if (!past_end) {
        t_out = std::min(t_out, r);
        t_in = std::min(t_in, t_out);
      } else {
        t_in = std::max(t_in, r);
        t_out = std::max(t_out, t_in);
      }
      float delta;
      if (noise.cellDelta(t_in, t_out, r, sigma, delta)) mark(k, delta);
    };
    traverseRay(origin_l, far_l, origin_key, far_key, visit);
    visit(far_key);
    // A walk that stepped around the end cell (rounding on a cell corner) still marks it.
    if (!past_end) visit(end_key);
  }
}

}  // namespace rtog
