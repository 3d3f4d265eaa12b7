// `rtog plan` as a user runs it, on a map `rtog build` makes from Debian's Malaga simplemap: the
// path written is the library's (rtog::planPath2D on the loaded map) point for point, the picture
// decodes, and bad requests are one error line, a non-zero exit and no output.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/serialization/CArchive.h>
#include <opencv2/imgcodecs.hpp>

#include "cli_helpers.hpp"
#include "commands.hpp"
#include "rtog/image/tum_dataset.hpp"

namespace {
using rtog_cli_test::entries;
using rtog_cli_test::run;
using rtog_cli_test::scratch;

const std::string kMalaga = std::string(RTOG_MRPT_DATASETS) + "/malaga-cs-fac-building.simplemap.gz";

std::vector<Eigen::Vector2d> robotPositions() {
  mrpt::maps::CSimpleMap sm;
  mrpt::io::CFileGZInputStream f(kMalaga);
  auto ar = mrpt::serialization::archiveFrom(f);
  ar >> sm;
  std::vector<Eigen::Vector2d> out;
  for (const auto& pair : sm) out.emplace_back(pair.pose->getMeanVal().x(), pair.pose->getMeanVal().y());
  return out;
}

std::string xy(const Eigen::Vector2d& p) { return std::to_string(p.x()) + " " + std::to_string(p.y()); }

/// A path file as `rtog plan` writes it: the comment line, then `dims` numbers a line.
std::pair<std::string, std::vector<std::vector<double>>> readPath(const std::string& file, int dims) {
  std::ifstream in(file);
  std::pair<std::string, std::vector<std::vector<double>>> r;
  std::getline(in, r.first);
  for (std::vector<double> p(static_cast<std::size_t>(dims)); in >> p[0] >> p[1] && (dims == 2 || in >> p[2]);) r.second.push_back(p);
  return r;
}

/// Whether `got` is `want` point for point (to the text's precision).
template <class Points>
void expectSamePath(const std::vector<std::vector<double>>& got, const Points& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i)
    for (std::size_t a = 0; a < got[i].size(); ++a) EXPECT_NEAR(got[i][a], want[i][int(a)], 1e-6) << "point " << i;
}
}  // namespace

TEST(CliPlan, ThePathIsTheLibrarysAndThePictureDecodes) {
  const std::string d = scratch("plan");
  std::string out;
  ASSERT_EQ(run("build --simplemap " + kMalaga + " --resolution 0.1 --out " + d + "/m.rtog", &out), 0) << out;
  const auto robot = robotPositions();
  const Eigen::Vector2d from = robot.front(), to = robot[robot.size() / 2];
  ASSERT_EQ(run("plan " + d + "/m.rtog --from " + xy(from) + " --to " + xy(to) +
                    " --Te 2 --Ta 1 --radius 0.3 --unknown-cost 0.9 --out " + d + "/p.txt --png " + d + "/p.png",
                &out),
            0)
      << out;
  EXPECT_NE(out.find("path of "), std::string::npos) << out;
  rtog::PlanOptions o;
  o.te = 2, o.ta = 1, o.radius = 0.3, o.unknown_risk = 0.9;
  // The tool parses the decimal text it was given: so does the library call.
  const Eigen::Vector2d f2(std::stod(std::to_string(from.x())), std::stod(std::to_string(from.y())));
  const Eigen::Vector2d t2(std::stod(std::to_string(to.x())), std::stod(std::to_string(to.y())));
  const rtog::PlanResult want = rtog::planPath2D(rtog::cli::loadMap(d + "/m.rtog"), f2, t2, o);
  ASSERT_TRUE(want.found);
  const auto [head, got] = readPath(d + "/p.txt", 2);
  EXPECT_EQ(head.rfind("# x y [m]", 0), 0u) << head;
  expectSamePath(got, want.path);
  const cv::Mat img = cv::imread(d + "/p.png");
  EXPECT_FALSE(img.empty());
  EXPECT_GE(std::max(img.cols, img.rows), 700);
}

// --cells searches every cell instead of crossing the alike free cuboids whole: the same cost,
// more nodes expanded.
TEST(CliPlan, CrossingFreeCuboidsWholeGivesTheCellSearchsCost) {
  const std::string d = scratch("plan_cells");
  std::string out;
  ASSERT_EQ(run("build --simplemap " + kMalaga + " --resolution 0.1 --out " + d + "/m.rtog", &out), 0) << out;
  const auto robot = robotPositions();
  const std::string args = "plan " + d + "/m.rtog --from " + xy(robot.front()) + " --to " + xy(robot[robot.size() / 3]) +
                           " --Te 5 --Ta 1 --radius 0.2 --out " + d + "/p.txt";
  std::string whole, cells;
  ASSERT_EQ(run(args, &whole), 0) << whole;
  ASSERT_EQ(run(args + " --cells", &cells), 0) << cells;
  const auto field = [](const std::string& s, const std::string& key) {
    const auto at = s.find(key);
    return at == std::string::npos ? std::nan("") : std::stod(s.substr(at + key.size()));
  };
  EXPECT_NEAR(field(whole, "cost "), field(cells, "cost "), 1e-4) << whole << cells;
  EXPECT_LT(field(whole, "; "), field(cells, "; ")) << whole << cells;  // nodes expanded
  EXPECT_NE(whole.find("free cuboids crossed whole"), std::string::npos) << whole;
  EXPECT_EQ(whole.find(", 0 free cuboids"), std::string::npos) << whole;
  EXPECT_NE(cells.find(", 0 free cuboids"), std::string::npos) << cells;
}

// With X Y Z: a 3D plan through the cells of a map of the TUM frames, the library's point for point.
TEST(CliPlan, ThreeDimensionalPlanIsTheLibrarys) {
  const std::string d = scratch("plan_3d");
  std::string out;
  ASSERT_EQ(run(std::string("build --tum ") + RTOG_TEST_TUM_DIR + " --resolution 0.1 --stride 4 --out " + d + "/m.rtog", &out), 0)
      << out;
  const rtog::image::DepthSequence seq = rtog::image::readTumSequence(RTOG_TEST_TUM_DIR);
  // The camera's first and last positions, as the command line gives them (six decimals).
  const auto asGiven = [](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(std::stod(std::to_string(p.x())), std::stod(std::to_string(p.y())), std::stod(std::to_string(p.z())));
  };
  const Eigen::Vector3d from = asGiven(seq.frames.front().camera_to_world.translation());
  const Eigen::Vector3d to = asGiven(seq.frames.back().camera_to_world.translation());
  const auto xyz = [](const Eigen::Vector3d& p) {
    return std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z());
  };
  ASSERT_EQ(run("plan " + d + "/m.rtog --from " + xyz(from) + " --to " + xyz(to) + " --Te 2 --Ta 1 --radius 0.2 --out " + d +
                    "/p.txt --png " + d + "/p.png",
                &out),
            0)
      << out;
  EXPECT_EQ(out.rfind("3D path of ", 0), 0u) << out;
  rtog::PlanOptions o;
  o.te = 2, o.ta = 1, o.radius = 0.2;
  const rtog::PlanResult3D want = rtog::planPath3D(rtog::cli::loadMap(d + "/m.rtog"), from, to, o);
  ASSERT_TRUE(want.found);
  const auto [head, got] = readPath(d + "/p.txt", 3);
  EXPECT_EQ(head.rfind("# x y z [m]", 0), 0u) << head;
  expectSamePath(got, want.path);
  EXPECT_GT(got.size(), 5u);
  EXPECT_FALSE(cv::imread(d + "/p.png").empty());
}

TEST(CliPlan, BadRequestsAreOneErrorLineAndNoOutput) {
  const std::string d = scratch("plan_bad");
  std::string out;
  ASSERT_EQ(run("build --simplemap " + kMalaga + " --resolution 0.2 --scans 0:10 --out " + d + "/m.rtog", &out), 0) << out;
  const auto before = entries(d);
  const auto robot = robotPositions();
  const std::string a = xy(robot.front());
  const std::string outs = " --out " + d + "/p.txt --png " + d + "/p.png";
  for (const auto& [args, code] : std::vector<std::pair<std::string, int>>{
           {"plan " + d + "/m.rtog --from " + a + " --to 5000 5000 --Te 1 --Ta 1" + outs, 1},   // too far: 2^26 cells
           {"plan " + d + "/m.rtog --from " + a + " --to nan 0 --Te 1 --Ta 1" + outs, 1},
           {"plan " + d + "/m.rtog --from " + a + " --to " + a + " --Te 0 --Ta 0" + outs, 1},
           {"plan " + d + "/m.rtog --from " + a + " --to " + a + " --Te 1 --Ta 1 --band 1 0" + outs, 1},
           {"plan " + d + "/m.rtog --from " + a + " --to " + a + " --Te -1 --Ta 1" + outs, 2},
           {"plan " + d + "/m.rtog --from " + a + " --Te 1 --Ta 1" + outs, 2},
           {"plan " + d + "/m.rtog --from " + a + " --to " + a + " 0.1 --Te 1 --Ta 1" + outs, 1},  // 2D to 3D
           {"plan " + d + "/m.rtog --from " + a + " 0.1 --to " + a + " 0.1 --Te 1 --Ta 1 --band 0 1" + outs, 1},
           {"plan " + d + "/missing.rtog --from " + a + " --to " + a + " --Te 1 --Ta 1" + outs, 1},
           {"plan " + d + "/m.rtog --from " + a + " --to " + a + " --Te 1 --Ta 1 --out " + d + "/m.rtog", 1}}) {
    EXPECT_EQ(run(args, &out), code) << args << "\n" << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << args << "\n" << out;
    EXPECT_EQ(out.rfind("rtog: error: ", 0), 0u) << out;
  }
  EXPECT_EQ(entries(d), before);
}

// Radii of more cells than the bound: one error line naming the radius and the bound, 2D and 3D
// (before: 1e18 planned as radius 0 in 2D and crashed in 3D; 1e9 to 1e17 failed allocating).
// Beyond 10 km the option parser refuses the value itself (exit 2); below it, the planner's
// bound in cells (2D 4,000, 3D 200; at 0.2 m: 800 m and 40 m) refuses it (exit 1).
TEST(CliPlan, HugeRadiiAreOneErrorLineNamingTheBound) {
  const std::string d = scratch("plan_huge_radius");
  std::string out;
  ASSERT_EQ(run("build --simplemap " + kMalaga + " --resolution 0.2 --scans 0:10 --out " + d + "/m.rtog", &out), 0) << out;
  const std::string a = xy(robotPositions().front());
  struct Case {
    std::string ends, radius;
    int code;
    std::string says;
  };
  for (const Case& c : std::vector<Case>{
           {a + " --to " + a, "1e18", 2, "--radius: must be at most 10000"},
           {a + " --to " + a, "1e12", 2, "--radius: must be at most 10000"},
           {a + " --to " + a, "5000", 1, ", more than the bound of"},
           {a + " --to " + a, "900", 1, ", more than the bound of"},
           {a + " 0.3 --to " + a + " 0.3", "1e18", 2, "--radius: must be at most 10000"},
           {a + " 0.3 --to " + a + " 0.3", "1000", 1, ", more than the bound of"},
           {a + " 0.3 --to " + a + " 0.3", "50", 1, ", more than the bound of"}}) {
    const std::string args = "plan " + d + "/m.rtog --from " + c.ends + " --Te 1 --Ta 1 --radius " + c.radius + " --out " + d + "/p.txt";
    EXPECT_EQ(run(args, &out, "timeout 60 "), c.code) << args << "\n" << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << args << "\n" << out;
    EXPECT_EQ(out.rfind("rtog: error: ", 0), 0u) << out;
    EXPECT_NE(out.find(c.says), std::string::npos) << args << "\n" << out;
    if (c.code == 1) {
      EXPECT_NE(out.find("the radius " + c.radius + " m"), std::string::npos) << out;
    }
  }
  EXPECT_EQ(entries(d), std::vector<std::string>{"m.rtog"});
}

// A start kept off by a large radius (75 m at 5 cm: 1,500 cells, within the bound) is refused at
// once, from the map's leaves near it (before: a disc of 7 million cells stamped about each of the
// map's 7,312 occupied cells first, minutes). The tool must finish within 60 s.
TEST(CliPlan, ALargeRadiusRefusesABlockedStartPromptly) {
  const std::string d = scratch("plan_large_radius");
  std::string out;
  ASSERT_EQ(run("build --simplemap " + kMalaga + " --resolution 0.05 --out " + d + "/m.rtog", &out), 0) << out;
  const std::string a = xy(robotPositions().front());
  const int rc = run("plan " + d + "/m.rtog --from " + a + " --to " + a + " --Te 1 --Ta 1 --radius 75 --out " + d + "/p.txt",
                     &out, "timeout 60 ");
  EXPECT_EQ(rc, 1) << out;
  EXPECT_NE(out.find("the start is occupied or nearer than the radius to an occupied cell"), std::string::npos) << out;
  EXPECT_EQ(entries(d), std::vector<std::string>{"m.rtog"});
}
