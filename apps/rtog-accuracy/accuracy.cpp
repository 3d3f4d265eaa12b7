#include "accuracy.hpp"

#include <chrono>
#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/COccupancyGridMap3D.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/version.h>
#include <octomap/octomap.h>

#include "rtog/core/occupancy_map.hpp"

#ifndef RTOG_OCTOMAP_VERSION
#define RTOG_OCTOMAP_VERSION "unknown"
#endif

namespace rtog::accuracy {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

constexpr double kPi = 3.14159265358979323846;

/// What one map says about every cell of the region: P(occupied) and its class.
struct MapView {
  std::string name;
  double insert_seconds = 0;
  std::vector<float> p;                 // P(occupied); only meaningful when state != Unknown
  std::vector<sim::Predicted> state;
  std::size_t outside = 0;              // known cells outside the region
  explicit MapView(std::string n, std::size_t cells)
      : name(std::move(n)), p(cells, 0.5f), state(cells, sim::Predicted::Unknown) {}
};

// ---- rtog ------------------------------------------------------------------------------

/// rtog with the beam model ("rtog"), or with the range-noise model at the sensor's own sigma
/// ("rtog_range_noise", doc/range-noise.md) if sigma > 0.
MapView buildRtog(const std::vector<sim::Scan>& scans, double res, double max_range, const sim::TruthGrid& region,
                  double sigma = 0.0) {
  MapParams mp;
  mp.resolution = res;
  OccupancyMap map(mp);
  InsertParams ip;
  ip.model = sigma > 0.0 ? SensorModel::RangeNoise : SensorModel::BeamBased;
  ip.range_noise_std = sigma;
  ip.max_range = max_range;
  const auto t0 = Clock::now();
  for (const auto& s : scans) map.insertPointCloud(s.origin, s.points.data(), s.points.size(), ip, s.is_hit.data());
  MapView v(sigma > 0.0 ? "rtog_range_noise" : "rtog", region.size());
  v.insert_seconds = secondsSince(t0);
  const Box& R = region.region();
  const LogOddsModel& model = map.logOddsModel();
  map.forEachLeaf([&](const Box& b, float value) {
    const Box c = b.intersection(R);
    v.outside += static_cast<std::size_t>(b.volume() - (c.isEmpty() ? 0 : c.volume()));
    if (c.isEmpty()) return;
    const float prob = static_cast<float>(probability(value));
    const sim::Predicted st =
        model.classify(value) == CellState::Occupied ? sim::Predicted::Occupied : sim::Predicted::Free;
    forEachCell(c, [&](const Key& k) {
      const std::size_t i = region.index(k);
      v.p[i] = prob;
      v.state[i] = st;
    });
  });
  return v;
}

// ---- OctoMap ----------------------------------------------------------------------------

MapView buildOctomap(const std::vector<sim::Scan>& scans, double res, double max_range, const sim::TruthGrid& region) {
  octomap::OcTree tree(res);  // OctoMap's defaults: hit 0.7, miss 0.4, clamp 0.1192/0.971
  const auto t0 = Clock::now();
  for (const auto& s : scans) {
    octomap::Pointcloud pc;
    pc.reserve(s.points.size());
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      Eigen::Vector3f p = s.points[i];
      if (!s.is_hit[i]) {  // no return: place it beyond max_range so OctoMap only clears up to it
        const Eigen::Vector3f o = s.origin.cast<float>();
        p = o + (p - o).normalized() * static_cast<float>(max_range + 1.0);
      }
      pc.push_back(p.x(), p.y(), p.z());
    }
    tree.insertPointCloud(pc, octomap::point3d(static_cast<float>(s.origin.x()), static_cast<float>(s.origin.y()),
                                               static_cast<float>(s.origin.z())),
                          max_range);
  }
  MapView v("octomap", region.size());
  v.insert_seconds = secondsSince(t0);
  const Box& R = region.region();
  const int depth = static_cast<int>(tree.getTreeDepth());
  const std::int32_t off = std::int32_t{1} << (depth - 1);  // OctoMap key of cell 0 (32768)
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const octomap::OcTreeKey k0 = it.getIndexKey();
    const std::int32_t n = 1 << (depth - static_cast<int>(it.getDepth()));
    const Key lo{static_cast<std::int32_t>(k0[0]) - off, static_cast<std::int32_t>(k0[1]) - off,
                 static_cast<std::int32_t>(k0[2]) - off};
    const Box b{lo, Key{lo.x + n - 1, lo.y + n - 1, lo.z + n - 1}};
    const Box c = b.intersection(R);
    v.outside += static_cast<std::size_t>(b.volume() - (c.isEmpty() ? 0 : c.volume()));
    if (c.isEmpty()) continue;
    const float prob = static_cast<float>(it->getOccupancy());
    const sim::Predicted st = tree.isNodeOccupied(*it) ? sim::Predicted::Occupied : sim::Predicted::Free;
    forEachCell(c, [&](const Key& k) {
      const std::size_t i = region.index(k);
      v.p[i] = prob;
      v.state[i] = st;
    });
  }
  return v;
}

// ---- MRPT --------------------------------------------------------------------------------

// Same sensor model as the others, as far as MRPT's options go: P(occ | hit) = 0.7 and
// P(free | miss) = 0.6. (MRPT's 3D grid triples the occupied log-odds increment internally.)
constexpr float kMrptOcc = 0.7f, kMrptFree = 0.6f;

void readMrpt(MapView& v, const sim::TruthGrid& region, double res, const std::function<float(double, double, double)>& freeness) {
  for (std::size_t i = 0; i < region.size(); ++i) {
    const Key k = region.key(i);
    const float f = freeness((k.x + 0.5) * res, (k.y + 0.5) * res, (k.z + 0.5) * res);
    if (f == 0.5f) continue;  // log-odds 0: never observed (or observed to exactly the prior)
    v.p[i] = 1.0f - f;
    v.state[i] = f < 0.5f ? sim::Predicted::Occupied : sim::Predicted::Free;
  }
}

MapView buildMrpt3D(const std::vector<sim::Scan>& scans, double res, double max_range, const sim::TruthGrid& region) {
  const Box& R = region.region();
  mrpt::maps::COccupancyGridMap3D grid(mrpt::math::TPoint3D(R.min.x * res, R.min.y * res, R.min.z * res),
                                       mrpt::math::TPoint3D((R.max.x + 1) * res, (R.max.y + 1) * res, (R.max.z + 1) * res),
                                       static_cast<float>(res));
  grid.insertionOptions.maxOccupancyUpdateCertainty = kMrptOcc;
  grid.insertionOptions.maxFreenessUpdateCertainty = kMrptFree;
  grid.insertionOptions.maxDistanceInsertion = static_cast<float>(max_range + 1.0);
  grid.insertionOptions.decimation = 1;
  const auto t0 = Clock::now();
  for (const auto& s : scans) {
    mrpt::maps::CSimplePointsMap pts;
    pts.reserve(s.points.size());
    const mrpt::math::TPoint3D o(s.origin.x(), s.origin.y(), s.origin.z());
    for (std::size_t i = 0; i < s.points.size(); ++i)
      if (s.is_hit[i]) pts.insertPointFast(s.points[i].x(), s.points[i].y(), s.points[i].z());
    grid.insertPointCloud(o, pts);
    for (std::size_t i = 0; i < s.points.size(); ++i)
      if (!s.is_hit[i])
        grid.insertRay(o, mrpt::math::TPoint3D(s.points[i].x(), s.points[i].y(), s.points[i].z()), false);
  }
  MapView v("mrpt_grid3d", region.size());
  v.insert_seconds = secondsSince(t0);
  readMrpt(v, region, res, [&](double x, double y, double z) {
    return grid.getFreenessByPos(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  });
  return v;
}

MapView buildMrpt2D(const std::vector<sim::Scan>& scans, const std::vector<sim::Pose>& poses,
                    const sim::ScannerParams& sp, double res, const sim::TruthGrid& region) {
  const Box& R = region.region();
  mrpt::maps::COccupancyGridMap2D grid(static_cast<float>(R.min.x * res), static_cast<float>((R.max.x + 1) * res),
                                       static_cast<float>(R.min.y * res), static_cast<float>((R.max.y + 1) * res),
                                       static_cast<float>(res));
  grid.insertionOptions.maxOccupancyUpdateCertainty = kMrptOcc;
  grid.insertionOptions.maxFreenessUpdateCertainty = kMrptFree;
  grid.insertionOptions.maxFreenessInvalidRanges = kMrptFree;
  grid.insertionOptions.maxDistanceInsertion = static_cast<float>(sp.max_range + 1.0);
  grid.insertionOptions.considerInvalidRangesAsFreeSpace = true;
  grid.insertionOptions.wideningBeamsWithDistance = false;
  const int n = sp.beams();
  const auto t0 = Clock::now();
  for (std::size_t s = 0; s < scans.size(); ++s) {
    mrpt::obs::CObservation2DRangeScan obs;
    obs.aperture = static_cast<float>(sp.fov_deg * kPi / 180.0);
    obs.rightToLeft = true;
    obs.maxRange = static_cast<float>(sp.max_range);
    obs.sensorPose = mrpt::poses::CPose3D(0, 0, sp.height, 0, 0, 0);
    obs.resizeScan(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      obs.setScanRange(static_cast<std::size_t>(i), scans[s].range[static_cast<std::size_t>(i)]);
      obs.setScanRangeValidity(static_cast<std::size_t>(i), scans[s].is_hit[static_cast<std::size_t>(i)] != 0);
    }
    const sim::Pose& p = poses[s];
    grid.insertObservation(obs, mrpt::poses::CPose3D(p.position.x(), p.position.y(), p.position.z(), p.yaw, 0, 0));
  }
  MapView v("mrpt_grid2d", region.size());
  v.insert_seconds = secondsSince(t0);
  readMrpt(v, region, res, [&](double x, double y, double) {
    return grid.getPos(static_cast<float>(x), static_cast<float>(y));
  });
  return v;
}

// ---- scoring -----------------------------------------------------------------------------

// The evaluation region is every cell that at least one of the first `region_maps` maps (rtog's
// beam model, OctoMap, MRPT's grid) observed. The maps after them (other sensor models) are scored
// on the same cells, so that adding one does not move the others' figures.
void score(const std::string& scenario_name, const std::vector<MapView>& maps, std::size_t region_maps,
           const sim::TruthGrid& truth, Scenario& sc, std::vector<MapResult>& out) {
  std::vector<std::uint8_t> eval(truth.size(), 0);
  for (std::size_t k = 0; k < region_maps && k < maps.size(); ++k)
    for (std::size_t i = 0; i < truth.size(); ++i)
      if (maps[k].state[i] != sim::Predicted::Unknown) eval[i] = 1;
  sc.region_cells = truth.size();
  for (std::size_t i = 0; i < truth.size(); ++i)
    if (eval[i]) {
      ++sc.evaluated_cells;
      (truth.occupiedAt(i) ? sc.truth_occupied : sc.truth_free) += 1;
    }
  for (const auto& m : maps) {
    sim::Evaluator ev;
    std::size_t observed = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      if (!eval[i]) continue;
      observed += m.state[i] != sim::Predicted::Unknown;
      ev.add(m.p[i], m.state[i], truth.occupiedAt(i));
    }
    MapResult r;
    r.scenario = scenario_name;
    r.map = m.name;
    r.insert_seconds = m.insert_seconds;
    r.observed_cells = observed;
    r.observed_outside = m.outside;
    r.metrics = ev.finish();
    // Class agreement with OctoMap's map over the evaluated cells.
    const auto octomap = std::find_if(maps.begin(), maps.end(), [](const MapView& v) { return v.name == "octomap"; });
    std::size_t same = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) same += eval[i] && m.state[i] == octomap->state[i];
    r.agreement_octomap = sc.evaluated_cells ? static_cast<double>(same) / static_cast<double>(sc.evaluated_cells) : 0.0;
    out.push_back(std::move(r));
  }
}

std::string mrptVersion() {
  std::ostringstream os;
  os << ((MRPT_VERSION >> 8) & 0xF) << '.' << ((MRPT_VERSION >> 4) & 0xF) << '.' << (MRPT_VERSION & 0xF);
  return os.str();
}

}  // namespace

Report run(const Config& cfg, std::ostream& log) {
  const auto t_start = Clock::now();
  Report rep;
  rep.config = cfg;
  rep.octomap_version = RTOG_OCTOMAP_VERSION;
  rep.mrpt_version = mrptVersion();

  const sim::World world = sim::World::generate(cfg.world, cfg.seed);
  rep.world_summary = world.summary();
  log << "world (seed " << cfg.seed << "): " << rep.world_summary << "\n";
  auto t0 = Clock::now();
  const sim::SimulatedLog simlog =
      sim::simulate(world, cfg.lidar, cfg.scanner, cfg.lidar_seed, cfg.scanner_seed, cfg.stride);
  log << "simulated " << simlog.lidar.size() << " LiDAR and " << simlog.planar.size() << " 2D scans in "
      << secondsSince(t0) << " s\n";

  const Lattice lat(cfg.resolution);
  const Box region3 = sim::worldKeyBox(world, lat, 2);

  // ---- 3D LiDAR ----
  {
    Scenario sc;
    sc.name = "lidar3d";
    std::ostringstream d;
    d << cfg.lidar.rings << "-ring LiDAR, " << cfg.lidar.azimuth_steps << " azimuth steps, elevation ["
      << cfg.lidar.elev_min_deg << ", " << cfg.lidar.elev_max_deg << "] deg, max range " << cfg.lidar.max_range
      << " m, sigma " << cfg.lidar.sigma << " m, " << cfg.lidar.height << " m above the floor";
    sc.description = d.str();
    sc.scans = simlog.lidar.size();
    for (const auto& s : simlog.lidar) {
      sc.beams += s.points.size();
      sc.returns += s.hits();
    }
    const sim::TruthGrid truth = sim::TruthGrid::rasterize(world, lat, region3);
    std::vector<MapView> maps;
    maps.push_back(buildRtog(simlog.lidar, cfg.resolution, cfg.lidar.max_range, truth));
    log << "  rtog        " << maps.back().insert_seconds << " s\n";
    maps.push_back(buildOctomap(simlog.lidar, cfg.resolution, cfg.lidar.max_range, truth));
    log << "  octomap     " << maps.back().insert_seconds << " s\n";
    maps.push_back(buildMrpt3D(simlog.lidar, cfg.resolution, cfg.lidar.max_range, truth));
    log << "  mrpt_grid3d " << maps.back().insert_seconds << " s\n";
    const std::size_t region_maps = maps.size();
    if (cfg.lidar.sigma > 0) {
      maps.push_back(buildRtog(simlog.lidar, cfg.resolution, cfg.lidar.max_range, truth, cfg.lidar.sigma));
      log << "  rtog_range_noise " << maps.back().insert_seconds << " s\n";
    }
    score(sc.name, maps, region_maps, truth, sc, rep.results);
    rep.scenarios.push_back(sc);
  }

  // ---- 2D scanner: the layer of cells containing the scan plane ----
  {
    Scenario sc;
    sc.name = "scanner2d";
    const double plane_z = simlog.planar.empty() ? world.floorZ() + cfg.scanner.height : simlog.planar.front().origin.z();
    const std::int32_t kz = static_cast<std::int32_t>(std::floor(lat.toLattice(plane_z)));
    std::ostringstream d;
    d << "planar scanner, " << cfg.scanner.fov_deg << " deg field of view in " << cfg.scanner.step_deg
      << " deg steps, max range " << cfg.scanner.max_range << " m, sigma " << cfg.scanner.sigma << " m, plane z = "
      << plane_z << " m (cell layer " << kz << ")";
    sc.description = d.str();
    sc.scans = simlog.planar.size();
    for (const auto& s : simlog.planar) {
      sc.beams += s.points.size();
      sc.returns += s.hits();
    }
    Box region2 = region3;
    region2.min.z = region2.max.z = kz;
    const sim::TruthGrid truth = sim::TruthGrid::rasterizeSlice(world, lat, region2, plane_z);
    std::vector<MapView> maps;
    maps.push_back(buildRtog(simlog.planar, cfg.resolution, cfg.scanner.max_range, truth));
    log << "  rtog        " << maps.back().insert_seconds << " s\n";
    maps.push_back(buildOctomap(simlog.planar, cfg.resolution, cfg.scanner.max_range, truth));
    log << "  octomap     " << maps.back().insert_seconds << " s\n";
    maps.push_back(buildMrpt2D(simlog.planar, simlog.poses, cfg.scanner, cfg.resolution, truth));
    log << "  mrpt_grid2d " << maps.back().insert_seconds << " s\n";
    const std::size_t region_maps = maps.size();
    if (cfg.scanner.sigma > 0) {
      maps.push_back(buildRtog(simlog.planar, cfg.resolution, cfg.scanner.max_range, truth, cfg.scanner.sigma));
      log << "  rtog_range_noise " << maps.back().insert_seconds << " s\n";
    }
    score(sc.name, maps, region_maps, truth, sc, rep.results);
    rep.scenarios.push_back(sc);
  }
  rep.total_seconds = secondsSince(t_start);
  return rep;
}

}  // namespace rtog::accuracy
