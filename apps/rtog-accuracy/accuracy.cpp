#include "accuracy.hpp"

#include <chrono>
#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

#include <mrpt/version.h>

#include "builders.hpp"
#include "rtog/sim/calibration.hpp"

#ifndef RTOG_OCTOMAP_VERSION
#define RTOG_OCTOMAP_VERSION "unknown"
#endif

namespace rtog::accuracy {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

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

/// The scans of one scenario, as the maps receive them.
struct ScenarioInput {
  Scenario sc;
  const std::vector<sim::Scan>* scans = nullptr;
  std::vector<sim::Pose> poses;  // as placed (believed)
  double max_range = 0, sigma = 0;
  bool calibrated = false;
  sim::InverseModelRates rates;  // measured in the calibration world, if calibrated
};

void runScenario(const Config& cfg, const ScenarioInput& in, const sim::TruthGrid& truth, std::ostream& log, Report& rep) {
  Scenario sc = in.sc;
  const auto& scans = *in.scans;
  sc.scans = scans.size();
  for (const auto& s : scans) {
    sc.beams += s.points.size();
    sc.returns += s.hits();
  }
  const double yaw_sigma = cfg.pose_sigma_yaw_deg * 3.14159265358979323846 / 180.0;
  const Eigen::Matrix3d cov =
      Eigen::Vector3d(cfg.pose_sigma_xy * cfg.pose_sigma_xy, cfg.pose_sigma_xy * cfg.pose_sigma_xy, yaw_sigma * yaw_sigma)
          .asDiagonal();
  log << sc.name << "\n";
  std::vector<MapView> maps;
  auto logged = [&](MapView v) {
    log << "  " << v.name << " " << v.insert_seconds << " s\n";
    maps.push_back(std::move(v));
  };
  logged(buildRtog(scans, cfg.resolution, in.max_range, truth, RtogVariant{"rtog", SensorModel::BeamBased, 0.0, false, {}}, cov));
  logged(buildOctomap(scans, cfg.resolution, in.max_range, truth));
  logged(sc.planar ? buildMrpt2D(scans, in.poses, cfg.scanner, cfg.resolution, truth)
                   : buildMrpt3D(scans, cfg.resolution, in.max_range, truth));
  const std::size_t region_maps = maps.size();
  std::vector<RtogVariant> more{{"rtog_endpoint", SensorModel::BeamEndPoint, 0.0, false, {}}};
  if (in.sigma > 0) more.push_back({"rtog_range_noise", SensorModel::RangeNoise, in.sigma, false, {}});
  if (sc.pose_noise) {
    const std::size_t n = more.size();
    more.insert(more.begin(), RtogVariant{"rtog", SensorModel::BeamBased, 0.0, false, {}});
    for (std::size_t k = 0; k <= n; ++k) {
      RtogVariant b = more[k];
      b.name += "_pose_blur";
      b.pose_blur = true;
      more.push_back(b);
    }
    more.erase(more.begin());
  }
  if (in.calibrated) {
    // The sensor stated by its rates measured in the calibration world, and the clamping at the
    // log-odds of calibrated_clamp_readings agreeing readings (prior 0.5).
    LogOddsParams lo;
    lo.prob_hit = in.rates.prob_hit;
    lo.prob_miss = in.rates.prob_miss;
    const double n = cfg.calibrated_clamp_readings;
    lo.clamp_min = probability(n * logit(in.rates.prob_miss));
    lo.clamp_max = probability(n * logit(in.rates.prob_hit));
    more.push_back({"rtog_calibrated", SensorModel::BeamBased, 0.0, false, lo});
    if (in.sigma > 0) {
      more.push_back({"rtog_range_noise_calibrated", SensorModel::RangeNoise, in.sigma, false, lo});
      if (sc.pose_noise)
        more.push_back({"rtog_range_noise_pose_blur_calibrated", SensorModel::RangeNoise, in.sigma, true, lo});
    }
  }
  for (const RtogVariant& v : more) logged(buildRtog(scans, cfg.resolution, in.max_range, truth, v, cov));
  // The same models in the MRPT map type's default preset, mrpt_grid: MRPT's grid steps and
  // sensor model, the graded models rounded onto its int8 cells (doc/mrpt_map.md).
  std::vector<RtogVariant> grid{{"rtog_mrpt_grid", SensorModel::BeamBased, 0.0, false, {}}};
  if (in.sigma > 0) grid.push_back({"rtog_mrpt_grid_range_noise", SensorModel::RangeNoise, in.sigma, false, {}});
  if (sc.pose_noise)
    for (std::size_t k = 0, n = grid.size(); k < n; ++k) {
      RtogVariant b = grid[k];
      b.name += "_pose_blur";
      b.pose_blur = true;
      grid.push_back(b);
    }
  for (const RtogVariant& v : grid)
    logged(buildRtogMrptGrid(scans, in.poses, sc.planar ? &cfg.scanner : nullptr, cfg.resolution, in.max_range, truth, v,
                             cov));
  score(sc.name, maps, region_maps, truth, sc, rep.results);
  rep.scenarios.push_back(sc);
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
  const bool pose_noise = cfg.pose_sigma_xy > 0 || cfg.pose_sigma_yaw_deg > 0;
  const std::vector<sim::PoseError> errors = sim::samplePoseErrors(
      simlog.poses.size(), cfg.pose_sigma_xy, cfg.pose_sigma_yaw_deg * 3.14159265358979323846 / 180.0, cfg.pose_seed,
      cfg.pose_correlation);
  std::vector<sim::Pose> believed = simlog.poses;
  for (std::size_t i = 0; i < believed.size(); ++i) {
    believed[i].position += Eigen::Vector3d(errors[i].dx, errors[i].dy, 0.0);
    believed[i].yaw += errors[i].dyaw;
  }
  auto displacedAll = [&](const std::vector<sim::Scan>& scans) {
    std::vector<sim::Scan> out;
    for (std::size_t i = 0; i < scans.size(); ++i) out.push_back(sim::displaced(scans[i], errors[i]));
    return out;
  };
  std::ostringstream pose_desc;
  pose_desc << "; believed poses off by Gauss-Markov errors, sigma_xy " << cfg.pose_sigma_xy << " m, sigma_yaw "
            << cfg.pose_sigma_yaw_deg << " deg, correlation " << cfg.pose_correlation << " (seed " << cfg.pose_seed << ")";

  const Lattice lat(cfg.resolution);
  const Box region3 = sim::worldKeyBox(world, lat, 2);

  // The calibration world: another seed's world, scanned at exact poses by the same sensors
  // (their own noise seeds), against its own truth.
  sim::InverseModelRates rates3, rates2;
  const bool calibrate = cfg.calibration_seed != cfg.seed;
  if (calibrate) {
    const sim::World cw = sim::World::generate(cfg.world, cfg.calibration_seed);
    const sim::SimulatedLog clog =
        sim::simulate(cw, cfg.lidar, cfg.scanner, cfg.lidar_seed + 1, cfg.scanner_seed + 1, cfg.stride);
    const Box cr = sim::worldKeyBox(cw, lat, 2);
    rates3 = sim::measureInverseModel(sim::TruthGrid::rasterize(cw, lat, cr), lat, clog.lidar);
    const double cz = clog.planar.front().origin.z();
    Box cr2 = cr;
    cr2.min.z = cr2.max.z = static_cast<std::int32_t>(std::floor(lat.toLattice(cz)));
    rates2 = sim::measureInverseModel(sim::TruthGrid::rasterizeSlice(cw, lat, cr2, cz), lat, clog.planar);
    log << "calibration world (seed " << cfg.calibration_seed << "): LiDAR prob_hit " << rates3.prob_hit << " prob_miss "
        << rates3.prob_miss << "; 2D scanner prob_hit " << rates2.prob_hit << " prob_miss " << rates2.prob_miss << "\n";
  }
  rep.calibration_lidar = rates3;
  rep.calibration_scanner = rates2;

  // ---- 3D LiDAR ----
  {
    std::ostringstream d;
    d << cfg.lidar.rings << "-ring LiDAR, " << cfg.lidar.azimuth_steps << " azimuth steps, elevation ["
      << cfg.lidar.elev_min_deg << ", " << cfg.lidar.elev_max_deg << "] deg, max range " << cfg.lidar.max_range
      << " m, sigma " << cfg.lidar.sigma << " m, " << cfg.lidar.height << " m above the floor";
    const sim::TruthGrid truth = sim::TruthGrid::rasterize(world, lat, region3);
    ScenarioInput in;
    in.sc.name = "lidar3d";
    in.sc.description = d.str();
    in.scans = &simlog.lidar;
    in.poses = simlog.poses;
    in.max_range = cfg.lidar.max_range;
    in.sigma = cfg.lidar.sigma;
    in.calibrated = calibrate;
    in.rates = rates3;
    runScenario(cfg, in, truth, log, rep);
    if (pose_noise) {
      const std::vector<sim::Scan> noisy = displacedAll(simlog.lidar);
      in.sc.name = "lidar3d_pose_noise";
      in.sc.description = d.str() + pose_desc.str();
      in.sc.pose_noise = true;
      in.scans = &noisy;
      in.poses = believed;
      runScenario(cfg, in, truth, log, rep);
    }
  }

  // ---- 2D scanner: the layer of cells containing the scan plane ----
  {
    const double plane_z = simlog.planar.empty() ? world.floorZ() + cfg.scanner.height : simlog.planar.front().origin.z();
    const std::int32_t kz = static_cast<std::int32_t>(std::floor(lat.toLattice(plane_z)));
    std::ostringstream d;
    d << "planar scanner, " << cfg.scanner.fov_deg << " deg field of view in " << cfg.scanner.step_deg
      << " deg steps, max range " << cfg.scanner.max_range << " m, sigma " << cfg.scanner.sigma << " m, plane z = "
      << plane_z << " m (cell layer " << kz << ")";
    Box region2 = region3;
    region2.min.z = region2.max.z = kz;
    const sim::TruthGrid truth = sim::TruthGrid::rasterizeSlice(world, lat, region2, plane_z);
    ScenarioInput in;
    in.sc.name = "scanner2d";
    in.sc.planar = true;
    in.sc.description = d.str();
    in.scans = &simlog.planar;
    in.poses = simlog.poses;
    in.max_range = cfg.scanner.max_range;
    in.sigma = cfg.scanner.sigma;
    in.calibrated = calibrate;
    in.rates = rates2;
    runScenario(cfg, in, truth, log, rep);
    if (pose_noise) {
      const std::vector<sim::Scan> noisy = displacedAll(simlog.planar);
      in.sc.name = "scanner2d_pose_noise";
      in.sc.description = d.str() + pose_desc.str();
      in.sc.pose_noise = true;
      in.scans = &noisy;
      in.poses = believed;
      runScenario(cfg, in, truth, log, rep);
    }
  }
  rep.total_seconds = secondsSince(t_start);
  return rep;
}

}  // namespace rtog::accuracy
