// rtog-bench: run by hand on a quiet machine (Release build); not a test.
#include <unistd.h>

#include <filesystem>
#include <iostream>

#include <CLI/CLI.hpp>

#include "bench.hpp"
#include "rtog/app/option_checks.hpp"

namespace {
/// rtog-first-scan beside this executable (both are built into the same directory).
std::string helperBesideThisExecutable() {
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("rtog-first-scan") : (self.parent_path() / "rtog-first-scan").string();
}
/// The rtog tool: beside this executable when installed, in ../rtog/ in the build tree.
std::string rtogCliNearThisExecutable() {
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return "rtog";
  for (const auto& p : {self.parent_path() / "rtog", self.parent_path().parent_path() / "rtog" / "rtog"})
    if (std::filesystem::is_regular_file(p)) return p.string();
  return "rtog";
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rtog-bench: rtog vs OctoMap and MRPT grids on real data, side by side"};
  rtog::bench::Command cmd;
  rtog::bench::Options& opts = cmd.opts;
  cmd.mrpt_datasets_dir = "/usr/share/mrpt/datasets";
  cmd.tum_dir = RTOG_DEFAULT_TUM_DIR;
  cmd.json = "benchmarks.json";
  cmd.markdown = "benchmarks.md";
  cmd.first_scan_helper = helperBesideThisExecutable();
  cmd.rtog_cli = rtogCliNearThisExecutable();
  app.add_option("--tum", cmd.tum_dir, "TUM depth sequence directory")->capture_default_str();
  app.add_option("--mrpt-datasets", cmd.mrpt_datasets_dir, "Debian mrpt-common datasets directory")->capture_default_str();
  app.add_option("--only", cmd.only, "Run only these datasets: tum, vlp16, rotscan, sena, plan, chunks");
  app.add_option("--merge-json", cmd.merge_json,
                 "Rows of the datasets this run does not measure are taken from this earlier JSON (with --only)");
  app.add_option("--rtog", cmd.rtog_cli, "The rtog executable (the chunked-build rows)")->capture_default_str();
  app.add_option("--methods", opts.methods,
                 "Run only methods whose name contains one of these (profiling; \"first scan\": the fresh-process rows)");
  app.add_option("--repeats", opts.repeats, "Rounds of builds, every method in each (median reported)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--min-seconds", opts.min_seconds,
                 "A fast method builds again in a round until its share of this much was timed")
      ->capture_default_str()
      ->check(rtog::app::checks::number(rtog::app::checks::Sign::NonNegative));
  app.add_option("--resolutions", opts.resolutions, "Cell sizes [m]")
      ->capture_default_str()
      ->check(rtog::app::checks::number(rtog::app::checks::Sign::Positive, 1000));
  app.add_option("--json", cmd.json, "JSON output")->capture_default_str();
  app.add_option("--markdown", cmd.markdown, "Markdown report")->capture_default_str();
  app.add_option("--img-dir", cmd.img_dir, "Directory for PNG plots")->capture_default_str()->check(CLI::ExistingDirectory);
  app.add_option("--from-json", cmd.from_json, "Render the Markdown report and plots from this JSON; measure nothing")
      ->check(CLI::ExistingFile);
  app.add_option("--app-rows", cmd.app_rows,
                 "app_rows.py --json files: the MRPT apps' rows join the report (repeatable)")
      ->check(CLI::ExistingFile);
  app.add_option("--raster-dir", opts.raster_dir, "Write each dataset's first rtog map as a byte-per-cell raster here")
      ->check(CLI::ExistingDirectory);
  app.add_option("--first-scan-helper", cmd.first_scan_helper, "The rtog-first-scan executable (fresh-process rows)")
      ->capture_default_str()
      ->check(CLI::ExistingFile);
  CLI11_PARSE(app, argc, argv);
  return rtog::bench::runCommand(cmd, std::cout, std::cerr);
}
