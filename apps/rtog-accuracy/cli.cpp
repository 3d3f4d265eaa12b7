// rtog-accuracy's command line (CLI11, with the value checks the rtog tool uses) and its files
// (one OutputSet: every file opened before the run, all written or none).
#include <cstdint>
#include <limits>
#include <ostream>
#include <stdexcept>

#include <CLI/CLI.hpp>

#include "accuracy.hpp"
#include "rtog/app/option_checks.hpp"
#include "rtog/app/output_files.hpp"

namespace rtog::accuracy {

int main(int argc, char** argv, std::ostream& out, std::ostream& err) {
  using app::checks::number;
  using app::checks::Sign;
  Config cfg;
  std::string json, markdown, png, reliability_png;
  double sigma = cfg.lidar.sigma;
  bool quick = false;
  CLI::App cli{"rtog-accuracy: rtog, OctoMap and MRPT's dense grids against the ground truth of a seeded synthetic world"};
  cli.add_option("--seed", cfg.seed, "World seed")
      ->capture_default_str()
      ->check(app::checks::integer(0, std::numeric_limits<std::uint32_t>::max()));
  cli.add_option("--resolution", cfg.resolution, "Cell size of every map [m]")->capture_default_str()->check(number(Sign::Positive));
  auto* stride = cli.add_option("--stride", cfg.stride, "Use every k-th trajectory pose")
                     ->capture_default_str()
                     ->check(app::checks::integer(1, 1 << 16));
  auto* sig = cli.add_option("--sigma", sigma, "Range noise of both sensors [m] (0: exact)")
                  ->capture_default_str()
                  ->check(number(Sign::NonNegative));
  cli.add_option("--pose-sigma-xy", cfg.pose_sigma_xy, "Pose error of the _pose_noise scenarios, x and y [m]")
      ->capture_default_str()
      ->check(number(Sign::NonNegative));
  cli.add_option("--pose-sigma-yaw", cfg.pose_sigma_yaw_deg, "Pose error of the _pose_noise scenarios, heading [deg]")
      ->capture_default_str()
      ->check(number(Sign::NonNegative));
  cli.add_option("--pose-correlation", cfg.pose_correlation, "Correlation of consecutive poses' errors, in [0, 1)")
      ->capture_default_str()
      ->check(app::checks::within(0.0, 0.999999));
  cli.add_option("--rooms-x", cfg.world.rooms_x, "Rooms of the world along x")
      ->capture_default_str()
      ->check(app::checks::integer(1, 16));
  cli.add_option("--rooms-y", cfg.world.rooms_y, "Rooms of the world along y")
      ->capture_default_str()
      ->check(app::checks::integer(1, 16));
  cli.add_option("--lidar-azimuth-steps", cfg.lidar.azimuth_steps, "LiDAR beams per ring")
      ->capture_default_str()
      ->check(app::checks::integer(1, 1 << 16));
  cli.add_option("--calibration-seed", cfg.calibration_seed, "World the _calibrated maps' sensor rates are measured in (= --seed: none)")
      ->capture_default_str()
      ->check(app::checks::integer(0, std::numeric_limits<std::uint32_t>::max()));
  cli.add_option("--calibrated-clamp-readings", cfg.calibrated_clamp_readings,
                 "The _calibrated maps clamp at the log-odds of this many agreeing readings")
      ->capture_default_str()
      ->check(app::checks::integer(1, 64));
  cli.add_flag("--quick", quick, "Every 4th pose (--stride 4)")->excludes(stride);
  cli.add_option("--json", json, "JSON report")->check(app::checks::path());
  cli.add_option("--markdown", markdown, "Markdown tables (also printed)")->check(app::checks::path());
  cli.add_option("--png", png, "ROC curves (PNG)")->check(app::checks::path());
  cli.add_option("--reliability-png", reliability_png, "Reliability diagrams (PNG)")->check(app::checks::path());
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return cli.exit(e, out, err);  // --help
    err << "rtog-accuracy: " << e.what() << " (see --help)\n";
    return 2;
  }
  if (quick) cfg.stride = 4;
  if (sig->count() > 0) cfg.lidar.sigma = cfg.scanner.sigma = sigma;
  try {
    // Opened before the run, so that a bad path fails at once and not after it.
    app::OutputSet files;
    std::ostream* json_out = json.empty() ? nullptr : &files.add("--json", json);
    std::ostream* md_out = markdown.empty() ? nullptr : &files.add("--markdown", markdown);
    std::ostream* png_out = png.empty() ? nullptr : &files.add("--png", png);
    std::ostream* rel_out = reliability_png.empty() ? nullptr : &files.add("--reliability-png", reliability_png);
    const Report rep = run(cfg, err);
    writeMarkdown(rep, out);
    if (json_out) writeJson(rep, *json_out);
    if (md_out) writeMarkdown(rep, *md_out);
    if (png_out) writeRocPng(rep, *png_out);
    if (rel_out) writeReliabilityPng(rep, *rel_out);
    files.commit();
    err << "total " << rep.total_seconds << " s\n";
  } catch (const std::exception& e) {
    err << "rtog-accuracy: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace rtog::accuracy
