// rtog-simlog's command line (CLI11, with the value checks the other rtog tools use).
#include <cstdint>
#include <limits>
#include <ostream>
#include <stdexcept>

#include <CLI/CLI.hpp>
#include <mrpt/core/exceptions.h>

#include "rtog/app/option_checks.hpp"
#include "simlog.hpp"

namespace rtog::simlog {

int main(int argc, char** argv, std::ostream& out, std::ostream& err) {
  using app::checks::number;
  using app::checks::Sign;
  Options o;
  long scans = long(o.scans);
  CLI::App cli{"rtog-simlog: a 2D laser rawlog simulated along a closed loop through an MRPT gridmap's free space"};
  cli.add_option("gridmap", o.gridmap, "The map (.gridmap or .gridmap.gz: a serialized COccupancyGridMap2D)")
      ->required()
      ->check(app::checks::path());
  cli.add_option("rawlog", o.rawlog, "Output rawlog (action/sensory-frame pairs, laser label LASER)")
      ->required()
      ->check(app::checks::path());
  cli.add_option("--scans", scans, "Scans (action/sensory-frame pairs) along one lap of the loop")
      ->capture_default_str()
      ->check(app::checks::integer(2, 10'000'000));
  cli.add_option("--seed", o.seed, "Seed of the odometry and range noise")
      ->capture_default_str()
      ->check(app::checks::integer(0, std::numeric_limits<std::uint32_t>::max()));
  cli.add_option("--odometry-noise", o.odometry_noise,
                 "Scales the odometry's error (1: 1 % bias and 3 % noise of distance and turn, 1 deg/m heading noise; 0: exact)")
      ->capture_default_str()
      ->check(number(Sign::NonNegative, 100.0));
  cli.add_flag("--reverse", o.reverse, "Drive the loop the other way round");
  cli.add_option("--gt", o.gt, "Ground-truth path, t x y phi per line [s m m rad], in the gridmap's frame")->check(app::checks::path());
  cli.add_option("--png", o.png, "The map with the loop drawn (PNG; the start in green)")->check(app::checks::path());
  cli.add_option("--clearance", o.loop.clearance, "The loop keeps this far from walls and unknown space [m]")
      ->capture_default_str()
      ->check(number(Sign::Positive, 100.0));
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return cli.exit(e, out, err);  // --help
    err << "rtog-simlog: error: " << e.what() << " (see --help)\n";
    return 2;
  }
  try {
    o.scans = std::size_t(scans);
    run(o, out);
  } catch (const std::exception& e) {
    // MRPT's exceptions carry a call stack: the first line is the message.
    const auto* m = dynamic_cast<const mrpt::ExceptionWithCallBackBase*>(&e);
    std::string s = m ? m->originalWhat : e.what();
    err << "rtog-simlog: error: " << s.substr(0, s.find('\n')) << "\n";
    return 1;
  }
  return 0;
}

}  // namespace rtog::simlog
