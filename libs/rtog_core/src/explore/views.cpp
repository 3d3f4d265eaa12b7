// Next-best views (rtog/core/explore.hpp): candidates on a ring about each large frontier region's
// centroid, facing it, kept where the robot may stand; each scored by its expected information
// gain, the best by gain given a risk-aware path (the planner's f(P)) and ranked by utility.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "explore/views.hpp"
#include "rtog/core/band.hpp"

namespace rtog {
namespace {

void validate(const ViewOptions& o) {
  const auto bad = [](const char* why) { throw std::invalid_argument(std::string("rtog::nextBestViews: ") + why); };
  if (!(std::isfinite(o.standoff) && o.standoff > 0.0)) bad("standoff must be positive and finite");
  if (o.candidates_per_region < 1 || o.candidates_per_region > 360) bad("candidates_per_region must lie in [1, 360]");
  if (!(std::isfinite(o.lambda) && o.lambda >= 0.0)) bad("lambda must be finite and non-negative");
  if (!std::isfinite(o.sensor_z)) bad("sensor_z must be finite");
  (void)o.sensor.rays();  // throws for a bad sensor
}

/// Whether the robot may stand at p: a known free cell (planar: a free column of the band) with no
/// occupied cell nearer than the plan's radius.
bool standable(const OccupancyMap& map, const Eigen::Vector3d& p, const ViewOptions& o) {
  Key k;
  if (!map.lattice().tryKey(p, k)) return false;
  if (o.frontiers.planar) {
    const Box region = bandRegion(map, Box{Key{k.x, k.y, 0}, Key{k.x, k.y, 0}}, o.frontiers.min_z, o.frontiers.max_z);
    if (region.isEmpty()) return false;
    bool known = false;
    float best = 0.0f;
    map.forEachLeafIn(region, [&](const Box&, float v) { best = known ? std::max(best, v) : v, known = true; });
    if (!known || best >= map.logOddsModel().occupiedThreshold()) return false;
  } else if (map.state(k) != CellState::Free) {
    return false;
  }
  return o.plan.radius <= 0.0 || !map.nearestOccupied(p, o.plan.radius).found;
}

Eigen::Isometry3d facing(const Eigen::Vector3d& p, double yaw, ViewSensor::Kind kind) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = p;
  Eigen::Matrix3d r = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  if (kind == ViewSensor::Kind::Depth) {
    // Optical frame (z forward, x right, y down) in the body frame (x forward, z up).
    Eigen::Matrix3d optical;
    optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;
    r = r * optical;
  }
  t.linear() = r;
  return t;
}

}  // namespace

std::vector<View> nextBestViews(const OccupancyMap& map, const Eigen::Vector3d& from, const ViewOptions& o) {
  validate(o);
  return nextBestViews(map, frontierRegions(map, o.frontiers), from, o);
}

std::vector<View> nextBestViews(const OccupancyMap& map, const std::vector<FrontierRegion>& regions,
                                const Eigen::Vector3d& from, const ViewOptions& o) {
  validate(o);
  const std::vector<Eigen::Vector3d> rays = o.sensor.rays();
  explore_detail::CellReader cells(map);
  std::vector<View> candidates;
  for (std::size_t r = 0; r < std::min(o.max_regions, regions.size()); ++r) {
    Eigen::Vector3d c = regions[r].centroid;
    if (o.frontiers.planar) c.z() = o.sensor_z;
    for (int i = 0; i < o.candidates_per_region; ++i) {
      const double a = 2.0 * M_PI * i / o.candidates_per_region;
      const Eigen::Vector3d p = c + o.standoff * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0);
      if (!standable(map, p, o)) continue;
      View v;
      v.pose = facing(p, a + M_PI, o.sensor.kind);
      v.region = r;
      v.gain = explore_detail::gainOf(cells, map, v.pose, rays, o.sensor.max_range);
      candidates.push_back(v);
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(), [](const View& a, const View& b) { return a.gain.bits > b.gain.bits; });
  if (candidates.size() > o.planned) candidates.resize(o.planned);
  for (View& v : candidates) {
    const Eigen::Vector3d to = v.pose.translation();
    try {
      if (o.frontiers.planar) {
        PlanOptions po = o.plan;
        po.min_z = o.frontiers.min_z, po.max_z = o.frontiers.max_z;
        const PlanResult p = planPath2D(map, from.head<2>(), to.head<2>(), po);
        v.reachable = p.found, v.path_cost = p.cost, v.path_length = p.length;
      } else {
        const PlanResult3D p = planPath3D(map, from, to, o.plan);
        v.reachable = p.found, v.path_cost = p.cost, v.path_length = p.length;
      }
    } catch (const std::invalid_argument&) {
      v.reachable = false;  // the start or the view is blocked for the planner
    }
    v.score = v.reachable ? v.gain.bits * std::exp(-o.lambda * v.path_cost) : 0.0;
  }
  std::stable_sort(candidates.begin(), candidates.end(), [](const View& a, const View& b) { return a.score > b.score; });
  return candidates;
}

}  // namespace rtog
