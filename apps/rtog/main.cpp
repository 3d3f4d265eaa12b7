// rtog: build, inspect and export R-tree occupancy grids.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <tuple>
#include <vector>

#include <CLI/CLI.hpp>

#include "commands.hpp"
#include "rtog/app/option_checks.hpp"

int main(int argc, char** argv) {
  using rtog::app::checks::kMaxCellLength;
  using rtog::app::checks::number;
  using rtog::app::checks::Sign;
  using rtog::app::checks::within;
  const CLI::Validator path = rtog::app::checks::path();
  CLI::App app{"rtog: R-tree occupancy grids for MRPT"};
  app.require_subcommand(1);

  rtog::cli::BuildOptions build;
  std::string model = "beam", merge = "clamped";
  auto* b = app.add_subcommand("build", "Build a map from real sensor data");
  auto* tum = b->add_option("--tum", build.tum_dir, "TUM RGB-D depth sequence directory")->check(CLI::ExistingDirectory);
  auto* rawlog = b->add_option("--rawlog", build.rawlog_path, "MRPT rawlog (odometry poses)")->check(CLI::ExistingFile);
  auto* simplemap = b->add_option("--simplemap", build.simplemap_path, "MRPT simplemap (.simplemap[.gz])")->check(CLI::ExistingFile);
  tum->excludes(rawlog)->excludes(simplemap);
  rawlog->excludes(simplemap);
  b->add_flag("--allow-truncated", build.allow_truncated,
             "--rawlog: read a log whose file ends inside an entry up to that entry (warns, counts what is dropped)")
      ->needs(rawlog);
  b->add_option("--ini", build.ini_path, "MRPT .ini with a CMultiMetricMap holding rtreeOccupancyGrid_count=1")->check(CLI::ExistingFile);
  b->add_option("--section", build.ini_section, "Section of the map definition in --ini")->capture_default_str();
  b->add_option("--out", build.out_path, "Output map (.rtog)")->check(path);
  auto* bres = b->add_option("--resolution", build.map.resolution, "Cell size [m]")
                   ->capture_default_str()
                   ->check(number(Sign::Positive, 1e3));
  auto* bmodel = b->add_option("--model", model, "Sensor model: beam | endpoint | rangeNoise")->capture_default_str();
  auto* noise = b->add_option("--range-noise-std", build.insert.range_noise_std,
                              "rangeNoise: range sigma at 0 m [m]")->capture_default_str()->check(number(Sign::NonNegative, kMaxCellLength));
  auto* noise_m = b->add_option("--range-noise-std-per-meter", build.insert.range_noise_std_per_meter,
                                "rangeNoise: growth of sigma with range [m per m]")
                      ->capture_default_str()
                      ->check(number(Sign::NonNegative, kMaxCellLength));
  auto* noise_cut = b->add_option("--range-noise-cutoff", build.insert.range_noise_cutoff,
                                  "rangeNoise: cells beyond the reading + this many sigma stay untouched (0.5 to 10)")
                        ->capture_default_str()
                        ->check(within(0.5, 10.0));
  auto* noise_share = b->add_option("--range-noise-shared-band", build.insert.range_noise_shared_band,
                                    "rangeNoise: beams ending in one cell, if at least this many, share one band (0: a band each)")
                          ->capture_default_str();
  auto* bmerge = b->add_option("--merge", merge, "Leaf merging: off | clamped | equal")->capture_default_str();
  // Beyond the lidars the tool reads (VLP-16 100 m, SICK LMS 80 m): a bound on one scan's reach.
  build.insert.max_range = 120.0;
  auto* bmax_range = b->add_option("--max-range", build.insert.max_range,
                "Cut beams longer than this [m] (0: no cut; beams longer than " +
                    std::to_string(rtog::InsertParams{}.max_ray_cells) +
                    " cells, and scans over the cell budget, are skipped and counted either way)")
      ->capture_default_str()
      ->check(number(Sign::NonNegative, 1e6));
  rtog::SensorChannel channel;
  auto* miss_rate = b->add_option("--miss-rate", channel.miss_rate,
                                  "The sensor as a channel: P(no detection | occupied), with --false-alarm-rate "
                                  "(replaces OctoMap's hit/miss probabilities)")
                        ->check(number(Sign::Positive, 1.0));
  auto* false_alarm = b->add_option("--false-alarm-rate", channel.false_alarm_rate,
                                    "The sensor as a channel: P(detection | free), with --miss-rate")
                          ->check(number(Sign::Positive, 1.0));
  miss_rate->needs(false_alarm);
  false_alarm->needs(miss_rate);
  auto* bpose_unc = b->add_flag("--pose-uncertainty", build.pose_uncertainty,
             "--simplemap: blur each frame by its pose covariance (poseUncertainty = on)");
  auto* bsonar = b->add_option("--sonar-cone-weighting", build.sonar_cone_weighting,
                "Sonar / IR readings: evidence across the cone, uniform | elfes (sonarConeWeighting)")
      ->capture_default_str()
      ->check(CLI::IsMember({"uniform", "elfes"}));
  auto* bthreads = b->add_option("--threads", build.insert.threads, "Threads tracing beams")->capture_default_str()->check(rtog::app::checks::integer(1, 256));
  auto* bdiscretize = b->add_flag("--discretize", build.insert.discretize, "Trace beams to end-cell centres, once per cell (OctoMap's discretize)");
  std::string scan_range;
  b->add_option("--scans", scan_range, "Only scans A <= i < B of the log (A:B, counted from 0; either may be left out)");
  b->add_option("--tiles", build.tiles,
                "Build the map as N tiles of space (or 'auto': four a rank under mpirun) into the directory --out");
  auto* bstride = b->add_option("--stride", build.stride, "Use every n-th pixel")->capture_default_str()->check(rtog::app::checks::integer(1, 1 << 16));

  std::string map_path;
  bool json = false;
  auto* i = app.add_subcommand("info", "Print a map's statistics");
  i->add_option("map", map_path, "Map file (.rtog, or a pipe such as /dev/stdin)")->required()->check(path);
  i->add_flag("--json", json, "JSON output");

  rtog::cli::ExportOptions ex;
  double slice_z = 0.0;
  auto* e = app.add_subcommand("export", "Export a map: mesh of occupied cuboids, OctoMap tree, image slice");
  e->add_option("map", ex.map_path, "Map file (.rtog, or a pipe such as /dev/stdin)")->required()->check(path);
  auto* ply = e->add_option("--ply", ex.ply_path, "Occupied cuboids as a triangle mesh (.ply)")->check(path);
  e->add_flag("--ascii", ex.ply_ascii, "Write the PLY as ASCII (default: binary little-endian)")->needs(ply);
  e->add_option("--bt", ex.bt_path, "OctoMap binary tree (.bt; octovis, OcTree::readBinary)")->check(path);
  e->add_option("--scene", ex.scene_path, "MRPT 3D scene of the occupied cuboids (.3Dscene; SceneViewer3D)")->check(path);
  auto* png = e->add_option("--png", ex.png_path, "Horizontal slice as an image (.png), with --slice-z")->check(path);
  auto* sz = e->add_option("--slice-z", slice_z, "Height of the slice [m]")->check(number(Sign::Any));
  auto* prob = e->add_flag("--png-probability", ex.png_probability,
                           "The slice shows each cell's P(occupied) as grey (unknown light blue), not its class");
  prob->needs(png);
  e->add_flag("--png-cells", ex.png_cells,
              "The PNG is one pixel a cell, nothing around it (for scripts), not the picture to look at")
      ->needs(png);
  png->needs(sz);
  sz->needs(png);

  rtog::cli::FuseOptions fu;
  std::vector<double> pose;
  auto* f = app.add_subcommand("fuse", "Fuse two maps (independent opinion pool: l = l1 + l2 - l0, clamped)");
  f->add_option("map_a", fu.map_a, "The map fused into (.rtog; its resolution and options are the result's)")
      ->required()
      ->check(path);
  f->add_option("map_b", fu.map_b, "The map whose evidence is added (.rtog)")->required()->check(path);
  f->add_option("--pose", pose, "map_b's frame in map_a's: x y z [m] yaw pitch roll [deg]")->expected(6);
  f->add_option("--out", fu.out_path, "Output map (.rtog)")->required()->check(path);
  f->add_flag("--register", fu.register_maps,
              "Estimate map_b's pose by ICP on the occupied cells (--pose: its guess, x y yaw) and fuse with its covariance");
  std::vector<double> band;
  f->add_option("--register-band", band, "--register: match occupied cells with centres in ZMIN ZMAX [m]")->expected(2);
  f->add_option("--threads", fu.threads, "Threads applying the update")->capture_default_str()->check(rtog::app::checks::integer(1, 256));

  rtog::cli::PriorOptions pr;
  std::vector<double> origin;
  auto* p = app.add_subcommand("prior", "Start a map from a prior: a blueprint image or an MRPT .gridmap");
  auto* image = p->add_option("--image", pr.image_path, "Blueprint image (PNG, ...): white free, black occupied, mid-grey unknown")
                    ->check(CLI::ExistingFile);
  auto* gridmap = p->add_option("--gridmap", pr.gridmap_path, "MRPT .gridmap or .gridmap.gz (its own geometry)")
                      ->check(CLI::ExistingFile);
  image->excludes(gridmap);
  auto* pres = p->add_option("--resolution", pr.resolution, "--image: metres per pixel")
                   ->capture_default_str()
                   ->check(number(Sign::Positive, 1e3));
  auto* porigin = p->add_option("--origin", origin, "--image: map coordinates X Y [m] of its lower-left corner")
                      ->expected(2)
                      ->check(within(-1e6, 1e6));
  pres->needs(image);
  porigin->needs(image);
  p->add_option("--confidence", pr.confidence, "How far the prior is trusted, in (0.5, 1]: black starts at this P(occupied)")
      ->capture_default_str()
      ->check(within(0.5, 1.0));
  p->add_option("--out", pr.out_path, "Output map (.rtog)")->required()->check(path);

  rtog::cli::PlanCommandOptions pl;
  std::vector<double> from, to, plan_band;
  auto* pn = app.add_subcommand("plan", "Plan a risk-aware path: least Te * sum P(occupied) + Ta * length");
  pn->add_option("map", pl.map_path, "Map file (.rtog)")->required()->check(path);
  pn->add_option("--from", from, "Start X Y [Z] [m] (with Z: a 3D plan through the cells)")->required()->expected(2, 3);
  pn->add_option("--to", to, "Goal X Y [Z] [m]")->required()->expected(2, 3);
  pn->add_option("--Te", pl.plan.te, "Weight of the summed risk")->required()->check(number(Sign::NonNegative));
  pn->add_option("--Ta", pl.plan.ta, "Weight of the length, per metre")->required()->check(number(Sign::NonNegative));
  pn->add_option("--unknown-cost", pl.plan.unknown_risk, "Risk of an unknown cell, in [0, 1]")
      ->capture_default_str()
      ->check(within(0.0, 1.0));
  pn->add_option("--radius", pl.plan.radius, "Robot radius [m]: the path keeps it from occupied cells")
      ->capture_default_str()
      ->check(number(Sign::NonNegative, kMaxCellLength));
  pn->add_option("--band", plan_band, "Height band ZMIN ZMAX [m] whose columns are planned on")->expected(2);
  pn->add_option("--out", pl.out_path, "The path (text, x y per line)")->required()->check(path);
  pn->add_option("--png", pl.png_path, "The planning grid with the path (.png; a 3D path seen from above)")->check(path);
  bool plan_cells = false;
  pn->add_flag("--cells", plan_cells, "2D: search every cell, not crossing the map's alike free cuboids whole (same path cost)");

  rtog::cli::ExploreCommandOptions xo;
  std::vector<double> x_from, x_band;
  std::string x_sensor = "laser2d";
  auto* xp = app.add_subcommand("explore", "Frontier regions and next-best views: expected information gain against path cost");
  xp->add_option("map", xo.map_path, "Map file (.rtog)")->required()->check(path);
  xp->add_option("--from", x_from, "The robot X Y [Z] [m] (with Z: 3D frontiers and views)")->required()->expected(2, 3);
  xp->add_option("--sensor", x_sensor, "laser2d | depth")->capture_default_str()->check(CLI::IsMember({"laser2d", "depth"}));
  xp->add_option("--max-range", xo.views.sensor.max_range, "Sensor range [m]")->capture_default_str()->check(number(Sign::Positive, 1000.0));
  xp->add_option("--aperture", xo.views.sensor.aperture, "laser2d: aperture [rad]")->capture_default_str()->check(within(1e-3, 6.2832));
  xp->add_option("--beams", xo.views.sensor.beams, "laser2d: beams")->capture_default_str()->check(rtog::app::checks::integer(1, 100000));
  xp->add_option("--stride", xo.views.sensor.stride, "depth: a ray every N-th pixel")
      ->capture_default_str()->check(rtog::app::checks::integer(1, 100000));
  std::vector<double> x_intrinsics;
  xp->add_option("--intrinsics", x_intrinsics, "depth: FX FY CX CY WIDTH HEIGHT [px] (Default: a Kinect's 525 525 319.5 239.5 640 480)")
      ->expected(6);
  xp->add_option("--Te", xo.views.plan.te, "Path cost: weight of the summed risk")->capture_default_str()->check(number(Sign::NonNegative));
  xp->add_option("--Ta", xo.views.plan.ta, "Path cost: weight of the length, per metre")->capture_default_str()->check(number(Sign::NonNegative));
  xp->add_option("--unknown-cost", xo.views.plan.unknown_risk, "Path cost: risk of an unknown cell, in [0, 1]")
      ->capture_default_str()->check(within(0.0, 1.0));
  xp->add_option("--band", x_band, "2D: the height band ZMIN ZMAX [m] of the frontiers and plans")->expected(2);
  xp->add_option("--sensor-z", xo.views.sensor_z, "2D: the sensor's height [m]")->capture_default_str()->check(number(Sign::Any));
  xp->add_option("--standoff", xo.views.standoff, "Candidates this far from a region's centroid [m]")->capture_default_str()->check(number(Sign::Positive, 1000.0));
  xp->add_option("--min-region", xo.views.frontiers.min_region_cells, "Frontier regions of fewer cells are dropped")
      ->capture_default_str()->check(rtog::app::checks::integer(1, 1000000000));
  xp->add_option("--lambda", xo.views.lambda, "Utility gain * exp(-lambda * path cost)")->capture_default_str()->check(number(Sign::NonNegative));
  xp->add_option("--radius", xo.views.plan.radius, "Robot radius [m]")->capture_default_str()->check(number(Sign::NonNegative, kMaxCellLength));
  xp->add_option("--out", xo.out_path, "Regions and ranked views (.json)")->required()->check(path);
  xp->add_option("--png", xo.png_path, "The band with the frontiers and the best views (.png)")->check(path);

  rtog::cli::ImageOptions im;
  std::vector<double> im_band;
  double im_slice = 0.0;
  auto* ig = app.add_subcommand("image", "Image operations on a height band: threshold, blur, open/close, Hough walls, regions");
  ig->add_option("map", im.map_path, "Map file (.rtog)")->required()->check(path);
  auto* isz = ig->add_option("--slice-z", im_slice, "The layer at height Z [m]")->check(number(Sign::Any));
  auto* iband = ig->add_option("--band", im_band, "The columns of ZMIN ZMAX [m] (their highest log-odds)")->expected(2);
  isz->excludes(iband);
  ig->add_option("--threshold", im.threshold, "Occupied at P >= this")->capture_default_str();
  ig->add_option("--blur", im.blur_sigma, "Gaussian blur of the probabilities, sigma [m]")
      ->check(number(Sign::Positive, kMaxCellLength));
  ig->add_option("--open", im.open_k, "Morphological opening of the occupied cells, K x K (odd)")->check(rtog::app::checks::integer(1, 1001));
  ig->add_option("--close", im.close_k, "Morphological closing of the occupied cells, K x K (odd)")->check(rtog::app::checks::integer(1, 1001));
  auto* hough = ig->add_flag("--hough", im.hough, "Wall segments (Hough transform) in metres");
  ig->add_option("--hough-min-length", im.hough_min_length, "Shortest segment [m]")
      ->capture_default_str()
      ->check(number(Sign::Positive, kMaxCellLength))
      ->needs(hough);
  ig->add_option("--hough-max-gap", im.hough_max_gap, "Longest gap a segment bridges [m]")
      ->capture_default_str()
      ->check(number(Sign::NonNegative, kMaxCellLength))
      ->needs(hough);
  ig->add_flag("--segment", im.segment, "Connected free regions (rooms)");
  ig->add_option("--out", im.out_path, "Results (.json)")->required()->check(path);
  ig->add_option("--png", im.png_path, "The band with walls and regions drawn (.png)")->check(path);
  ig->add_option("--prior-png", im.prior_png_path, "The processed band as an image `rtog prior --image` reads")->check(path);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& err) {
    if (err.get_exit_code() == 0) return app.exit(err);  // --help
    std::cerr << "rtog: error: " << err.what() << " (see --help)\n";
    return 2;
  }
  // An option that would have no effect is a usage error, not dropped without a word: beside
  // --ini, every map option (the .ini defines the map; its key named), and --stride without
  // --tum (only depth images have pixels to skip).
  if (b->parsed()) {
    std::string inert;
    if (!build.ini_path.empty())
      for (const auto& [opt, key] : std::vector<std::pair<CLI::Option*, const char*>>{
               {bres, "resolution in its _creationOpts"}, {bmodel, "sensorModel in its _insertOpts"},
               {noise, "rangeNoiseStd in its _insertOpts"}, {noise_m, "rangeNoiseStdPerMeter in its _insertOpts"},
               {noise_cut, "rangeNoiseCutoff in its _insertOpts"},
               {noise_share, "rangeNoiseSharedBand in its _insertOpts"}, {bmerge, "mergePolicy in its _insertOpts"},
               {bmax_range, "maxDistanceInsertion in its _insertOpts"},
               {miss_rate, "missRate and falseAlarmRate in its _insertOpts"},
               {false_alarm, "missRate and falseAlarmRate in its _insertOpts"},
               {bpose_unc, "poseUncertainty = on in its _insertOpts"},
               {bsonar, "sonarConeWeighting in its _insertOpts"}, {bthreads, "threads in its _insertOpts"},
               {bdiscretize, "discretize in its _insertOpts"}})
        if (opt->count() > 0) {
          inert = opt->get_name() + " has no effect with --ini (the .ini defines the map): set " + key + " instead";
          break;
        }
    if (inert.empty() && bstride->count() > 0 && build.tum_dir.empty())
      inert = "--stride has no effect without --tum (it skips depth image pixels)";
    if (!inert.empty()) {
      std::cerr << "rtog: error: " << inert << " (see --help)\n";
      return 2;
    }
  }
  try {
    if (b->parsed()) {
      build.insert.model = rtog::sensorModelFromString(model);
      build.map.merge = rtog::mergePolicyFromString(merge);
      const bool noise_flags = noise->count() + noise_m->count() + noise_cut->count() + noise_share->count() > 0;
      if (noise_flags && build.insert.model != rtog::SensorModel::RangeNoise)
        throw std::invalid_argument("--range-noise-*: only with --model rangeNoise");
      if (miss_rate->count() > 0) build.map.log_odds = rtog::withChannel(build.map.log_odds, channel);
      if (!scan_range.empty()) std::tie(build.scans_from, build.scans_to) = rtog::cli::parseScanRange(scan_range);
      build.progress_bar = isatty(STDOUT_FILENO) != 0;
      return rtog::cli::build(build, std::cout);
    }
    if (f->parsed()) {
      if (!pose.empty()) std::copy(pose.begin(), pose.end(), fu.pose.begin());
      if (!band.empty()) {
        if (!fu.register_maps) throw std::invalid_argument("--register-band: only with --register");
        fu.register_band = {band[0], band[1]};
      }
      return rtog::cli::fuse(fu, std::cout);
    }
    if (ig->parsed()) {
      if (isz->count() > 0) im.zmin = im.zmax = im_slice;
      if (!im_band.empty()) im.zmin = im_band[0], im.zmax = im_band[1];
      return rtog::cli::imageOps(im, std::cout);
    }
    if (xp->parsed()) {
      xo.three_d = x_from.size() == 3;
      if (xo.three_d && !x_band.empty()) throw std::invalid_argument("explore: --band is for 2D exploration (X Y), not 3D");
      xo.from = Eigen::Vector3d(x_from[0], x_from[1], xo.three_d ? x_from[2] : xo.views.sensor_z);
      if (!x_band.empty()) xo.views.frontiers.min_z = x_band[0], xo.views.frontiers.max_z = x_band[1];
      xo.views.sensor.kind = x_sensor == "depth" ? rtog::ViewSensor::Kind::Depth : rtog::ViewSensor::Kind::Laser2D;
      if (!x_intrinsics.empty()) {
        auto& s = xo.views.sensor;
        s.fx = x_intrinsics[0], s.fy = x_intrinsics[1], s.cx = x_intrinsics[2], s.cy = x_intrinsics[3];
        if (x_intrinsics[4] != std::floor(x_intrinsics[4]) || x_intrinsics[5] != std::floor(x_intrinsics[5]) ||
            !(x_intrinsics[4] >= 1 && x_intrinsics[4] <= 100000 && x_intrinsics[5] >= 1 && x_intrinsics[5] <= 100000))
          throw std::invalid_argument("explore: --intrinsics WIDTH and HEIGHT must be whole numbers in [1, 100000]");
        s.width = static_cast<int>(x_intrinsics[4]), s.height = static_cast<int>(x_intrinsics[5]);
      }
      return rtog::cli::explore(xo, std::cout);
    }
    if (pn->parsed()) {
      if (from.size() != to.size()) throw std::invalid_argument("plan: --from and --to need as many coordinates (X Y, or X Y Z)");
      pl.three_d = from.size() == 3;
      if (pl.three_d && !plan_band.empty()) throw std::invalid_argument("plan: --band is for 2D plans (X Y), not 3D ones");
      pl.from = Eigen::Vector3d(from[0], from[1], pl.three_d ? from[2] : 0.0);
      pl.to = Eigen::Vector3d(to[0], to[1], pl.three_d ? to[2] : 0.0);
      if (!plan_band.empty()) pl.plan.min_z = plan_band[0], pl.plan.max_z = plan_band[1];
      pl.plan.cross_free_cuboids = !plan_cells;
      return rtog::cli::plan(pl, std::cout);
    }
    if (p->parsed()) {
      if (!origin.empty()) pr.origin = {origin[0], origin[1]};
      return rtog::cli::prior(pr, std::cout);
    }
    if (e->parsed()) {
      if (sz->count() > 0) ex.slice_z = slice_z;
      return rtog::cli::exportMap(ex, std::cout);
    }
    return rtog::cli::info(map_path, json, std::cout);
  } catch (const std::exception& e) {
    // One line a person reads: MRPT's own exceptions carry a call stack (rtog::cli::oneLine).
    std::cerr << "rtog: error: " << rtog::cli::oneLine(e) << "\n";
    return 1;
  }
}
