// The closed exploration loop (rtog/sim/exploration.hpp).
#include "rtog/sim/exploration.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <stdexcept>
#include <unordered_set>

namespace rtog::sim {
namespace {

constexpr double kNearby = 0.5;  // [m]

/// The cells of the scan height's layer reachable from the start through cells no box occupies
/// (4-connected, within the world's bounds).
std::vector<Key> reachableFree(const World& w, const Lattice& lat, const Eigen::Vector3d& start) {
  const Key s = lat.key(start);
  const Key lo = lat.key(w.boundsMin()), hi = lat.key(w.boundsMax());
  std::unordered_set<Key, KeyHash> seen{s};
  std::deque<Key> todo{s};
  std::vector<Key> out;
  while (!todo.empty()) {
    const Key k = todo.front();
    todo.pop_front();
    out.push_back(k);
    for (const auto& [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
      const Key n{k.x + dx, k.y + dy, k.z};
      if (n.x < lo.x || n.x > hi.x || n.y < lo.y || n.y > hi.y || seen.count(n) || w.cellOccupied(lat, n)) continue;
      seen.insert(n);
      todo.push_back(n);
    }
  }
  return out;
}

double coverage(const OccupancyMap& map, const std::vector<Key>& free) {
  std::size_t known = 0;
  for (const Key& k : free) known += map.logOdds(k).has_value();
  return free.empty() ? 0.0 : double(known) / double(free.size());
}

}  // namespace

std::vector<ExplorationStep> explore(const World& world, ExploreStrategy strategy, const ExplorationParams& p) {
  if (world.trajectory().empty()) throw std::invalid_argument("rtog::sim::explore: the world has no start pose");
  if (!(p.scan_every > 0.0)) throw std::invalid_argument("rtog::sim::explore: scan_every must be positive");
  MapParams mp;
  mp.resolution = p.resolution;
  OccupancyMap map(mp);
  PlanarScanner scanner(p.scanner, p.seed);
  InsertParams ip;
  ip.max_range = p.scanner.max_range;
  ip.threads = 1;
  const double height = world.floorZ() + p.scanner.height;
  ViewOptions vo = p.views;
  vo.frontiers.planar = true;
  vo.frontiers.min_z = vo.frontiers.max_z = height;
  vo.sensor_z = height;
  vo.sensor.kind = ViewSensor::Kind::Laser2D;
  vo.sensor.max_range = p.scanner.max_range;
  vo.sensor.aperture = p.scanner.fov_deg * M_PI / 180.0;
  vo.sensor.beams = std::max(2, p.scanner.beams() / 4);  // scoring needs fewer rays than scanning
  PlanOptions po = vo.plan;
  po.min_z = po.max_z = height;

  Pose pose = world.trajectory().front();
  const std::vector<Key> free = reachableFree(world, map.lattice(), pose.position + Eigen::Vector3d(0, 0, p.scanner.height));
  std::vector<ExplorationStep> steps;
  ExplorationStep st;
  // The robot knows its body's cells are free (as a costmap clears the footprint): a noisy return
  // in them would leave it standing in a cell its planner takes for an obstacle.
  const double body = std::max(vo.plan.radius, p.resolution);
  const auto scanAt = [&](const Pose& at) {
    const Scan s = scanner.scan(world, at);
    map.insertPointCloud(s.origin, s.points.data(), s.points.size(), ip, s.is_hit.data());
    std::vector<Box> cells;
    const Lattice& lat = map.lattice();
    const Key c = lat.key(s.origin);
    const auto r = static_cast<std::int32_t>(std::ceil(body / p.resolution));
    for (std::int32_t y = c.y - r; y <= c.y + r; ++y)
      for (std::int32_t x = c.x - r; x <= c.x + r; ++x) {
        const Eigen::Vector2d centre((x + 0.5) * p.resolution, (y + 0.5) * p.resolution);
        if ((centre - s.origin.head<2>()).norm() <= body) cells.push_back(Box::cell(Key{x, y, c.z}));
      }
    const std::vector<float> free(cells.size(), map.logOddsModel().clampMin());
    map.assignCells(cells.data(), free.data(), cells.size());
    ++st.scans;
  };
  scanAt(pose);
  st.coverage = coverage(map, free);
  steps.push_back(st);
  for (int step = 1; step <= p.max_steps && st.coverage < p.stop_coverage; ++step) {
    const Eigen::Vector3d here(pose.position.x(), pose.position.y(), height);
    // A robot that finds itself within its radius of an obstacle (seen only now) plans this step
    // without the radius, to get away.
    const std::vector<FrontierRegion> regions = frontierRegions(map, vo.frontiers);
    std::vector<View> views = nextBestViews(map, regions, here, vo);
    PlanOptions step_plan = po;
    if (std::none_of(views.begin(), views.end(), [](const View& v) { return v.reachable; })) {
      ViewOptions loose = vo;
      loose.plan.radius = step_plan.radius = 0.0;
      views = nextBestViews(map, regions, here, loose);
    }
    const View* pick = nullptr;
    for (const View& v : views) {
      // A view where the robot stands adds nothing its last scan did not.
      if (!v.reachable || !(v.gain.bits > 0.0) || v.path_length < kNearby) continue;
      if (!pick || (strategy == ExploreStrategy::InformationGain ? v.score > pick->score : v.path_cost < pick->path_cost))
        pick = &v;
    }
    if (!pick) break;
    const Eigen::Vector3d to = pick->pose.translation();
    const PlanResult path = planPath2D(map, here.head<2>(), to.head<2>(), step_plan);
    if (!path.found || path.path.size() < 2) break;
    // Drive the path, scanning every scan_every metres and at its end facing the view's way; stop
    // before a cell the world occupies (the map may not know it yet).
    double since = 0.0;
    for (std::size_t i = 1; i < path.path.size(); ++i) {
      const Eigen::Vector2d a = path.path[i - 1], b = path.path[i];
      Key next;
      if (!map.lattice().tryKey(Eigen::Vector3d(b.x(), b.y(), height), next) || world.cellOccupied(map.lattice(), next)) break;
      const double d = (b - a).norm();
      st.path_length += d, since += d;
      pose.position = Eigen::Vector3d(b.x(), b.y(), world.floorZ());
      pose.yaw = std::atan2(b.y() - a.y(), b.x() - a.x());
      if (since >= p.scan_every) scanAt(pose), since = 0.0;
    }
    const Eigen::Vector3d fwd = pick->pose.linear().col(0);
    pose.yaw = std::atan2(fwd.y(), fwd.x());
    scanAt(pose);
    st.step = step;
    st.coverage = coverage(map, free);
    steps.push_back(st);
  }
  return steps;
}

double lengthToCoverage(const std::vector<ExplorationStep>& steps, double c) {
  for (std::size_t i = 0; i < steps.size(); ++i) {
    if (steps[i].coverage < c) continue;
    if (i == 0) return steps[0].path_length;
    const ExplorationStep &a = steps[i - 1], &b = steps[i];
    const double t = (c - a.coverage) / (b.coverage - a.coverage);
    return a.path_length + t * (b.path_length - a.path_length);
  }
  return -1.0;
}

}  // namespace rtog::sim
