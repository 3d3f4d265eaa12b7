// The rtog tool as a user runs it: real data in, a map file out, errors reported cleanly.
#include <gtest/gtest.h>

#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CSetOfObjects.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "commands.hpp"
#include "rtog/core/mesh_export.hpp"
#include "rtog/core/octomap_export.hpp"
#include "rtog/image/slice.hpp"
#include "rtog/image/tum_dataset.hpp"

namespace {

int run(const std::string& args, std::string* output = nullptr) {
  // Per process: ctest runs the cases of this file in parallel processes.
  const std::string out_file = ::testing::TempDir() + "/rtog_cli_out_" + std::to_string(getpid()) + ".txt";
  const int rc = std::system((std::string(RTOG_EXE) + " " + args + " > " + out_file + " 2>&1").c_str());
  if (output) {
    std::ifstream in(out_file);
    std::stringstream ss;
    ss << in.rdbuf();
    *output = ss.str();
  }
  return WEXITSTATUS(rc);
}

TEST(Cli, BuildsFromBundledTumDataAndReportsInfo) {
  const std::string map = ::testing::TempDir() + "/cli_test.rtog";
  std::remove(map.c_str());
  std::string out;
  ASSERT_EQ(run(std::string("build --tum ") + RTOG_TEST_TUM_DIR + " --resolution 0.1 --stride 4 --merge equal --out " + map, &out), 0) << out;
  EXPECT_NE(out.find("inserted"), std::string::npos) << out;
  EXPECT_NE(out.find("leaves (cuboids)"), std::string::npos) << out;
  const rtog::OccupancyMap loaded = rtog::cli::loadMap(map);
  EXPECT_GT(loaded.leafCount(), 1000u);
  EXPECT_EQ(loaded.checkInvariants(), "");
  ASSERT_EQ(run("info --json " + map, &out), 0);
  EXPECT_NE(out.find("\"leaves\": " + std::to_string(loaded.leafCount())), std::string::npos) << out;
  const rtog::ClassCover cover = loaded.classCover();
  EXPECT_LT(cover.leaves(), loaded.leafCount());
  EXPECT_NE(out.find("\"occupied\": " + std::to_string(cover.occupied)), std::string::npos) << out;
}

// `build --tum` reports what it skipped: a copy of the bundled data with a block of pixels
// without depth in the first frame and the second frame's camera at the edge of the key range,
// looking out of it.
TEST(Cli, TumBuildReportsSkippedBeams) {
  const std::string dir = ::testing::TempDir() + "/rtog_tum_skips_" + std::to_string(getpid());
  ASSERT_EQ(std::system(("rm -rf " + dir + " && mkdir -p " + dir + "/depth").c_str()), 0);
  std::ifstream in(std::string(RTOG_TEST_TUM_DIR) + "/groundtruth_poses.txt");
  std::ofstream poses(dir + "/groundtruth_poses.txt");
  std::string line;
  int frames = 0;
  while (std::getline(in, line) && frames < 2) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    std::string rgb, depth;
    double t[3], q[4];
    ls >> rgb >> depth >> t[0] >> t[1] >> t[2] >> q[0] >> q[1] >> q[2] >> q[3];
    cv::Mat img = cv::imread(std::string(RTOG_TEST_TUM_DIR) + "/" + depth, cv::IMREAD_ANYDEPTH);
    ASSERT_FALSE(img.empty());
    if (frames == 0) img(cv::Rect(100, 100, 120, 80)).setTo(0);
    if (frames == 1) {
      // Which way along x the camera looks: its end points beyond the edge have no key.
      rtog::image::DepthFrame f;
      f.depth_path = std::string(RTOG_TEST_TUM_DIR) + "/" + depth;
      f.camera_to_world.linear() = Eigen::Quaterniond(q[3], q[0], q[1], q[2]).toRotationMatrix();
      f.camera_to_world.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
      const auto scan = rtog::image::loadDepthScan(f, {}, 4);
      double dx = 0;
      for (const auto& p : scan.points) dx += p.x() - t[0];
      t[0] = (dx > 0 ? 1.0 : -1.0) * (rtog::kKeyMax * 0.1 - 1.0);  // keys span +-2^20 cells
    }
    ASSERT_TRUE(cv::imwrite(dir + "/" + depth, img));
    poses << rgb << " " << depth << " " << t[0] << " " << t[1] << " " << t[2] << " " << q[0] << " " << q[1] << " "
          << q[2] << " " << q[3] << "\n";
    ++frames;
  }
  poses.close();
  ASSERT_EQ(frames, 2);
  // What the two frames hold, at the stride the build uses.
  const rtog::image::DepthSequence seq = rtog::image::readTumSequence(dir);
  std::size_t without = 0, far = 0;
  const rtog::Lattice lattice(0.1);
  for (std::size_t i = 0; i < seq.frames.size(); ++i) {
    const auto scan = rtog::image::loadDepthScan(seq.frames[i], seq.intrinsics, 4);
    without += scan.pixels_without_depth;
    rtog::Key k;
    for (const auto& p : scan.points) far += !lattice.tryKey(p.cast<double>(), k);
  }
  ASSERT_GT(without, 600u);
  ASSERT_GT(far, 1000u);
  std::string out;
  ASSERT_EQ(run("build --tum " + dir + " --resolution 0.1 --stride 4", &out), 0) << out;
  const std::size_t at = out.find("skipped: ");
  ASSERT_NE(at, std::string::npos) << out;
  std::size_t nonFinite = 0, zero = 0, range = 0, invalid = 0;
  ASSERT_EQ(std::sscanf(out.c_str() + at, "skipped: %zu non-finite, %zu zero-length, %zu out of range, %zu invalid",
                        &nonFinite, &zero, &range, &invalid),
            4)
      << out;
  EXPECT_EQ(range, far) << out;
  EXPECT_EQ(invalid, without) << out;
  std::system(("rm -rf " + dir).c_str());
}

TEST(Cli, BuildsFromMrptLogsWithAnIniMapDefinition) {
  const std::string datasets = RTOG_MRPT_DATASETS;
  const std::string map = ::testing::TempDir() + "/cli_malaga.rtog";
  std::string out;
  // A simplemap (poses from the map), options from the project's .ini.
  ASSERT_EQ(run("build --simplemap " + datasets + "/malaga-cs-fac-building.simplemap.gz --ini " + RTOG_CONFIG_DIR +
                    "/rtog_build.ini --out " + map,
                &out),
            0)
      << out;
  EXPECT_NE(out.find("from 99 scans"), std::string::npos) << out;
  ASSERT_EQ(run("info --json " + map, &out), 0);
  EXPECT_NE(out.find("\"resolution\": 0.1"), std::string::npos) << out;
  EXPECT_NE(out.find("\"merge\": \"equal\""), std::string::npos) << out;
  EXPECT_GT(rtog::cli::loadMap(map).statistics().occupied_cells, 1000);
  // A rawlog in actions/sensory-frame format (odometry poses), options from the command line.
  ASSERT_EQ(run("build --rawlog \"" + datasets + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog\" --resolution 0.1 "
                "--max-range 30 --out " + map, &out), 0) << out;
  EXPECT_NE(out.find("from 225 scans"), std::string::npos) << out;
  EXPECT_GT(rtog::cli::loadMap(map).statistics().occupied_cells, 1000);
  // An .ini that defines no R-tree map, a file that is no rawlog, two sources at once.
  const std::string grid_only = ::testing::TempDir() + "/grid_only.ini";
  std::ofstream(grid_only) << "[MappingApplication]\noccupancyGrid_count=1\n";
  EXPECT_NE(run("build --simplemap " + datasets + "/malaga-cs-fac-building.simplemap.gz --ini " + grid_only +
                    " --out " + map, &out), 0);
  EXPECT_NE(out.find("defines no rtreeOccupancyGrid map"), std::string::npos) << out;
  EXPECT_NE(run("build --rawlog " + map + " --out " + map + ".x", &out), 0);
  EXPECT_NE(out.find("cannot read rawlog"), std::string::npos) << out;
  EXPECT_NE(run("build --rawlog " + map + " --simplemap " + map, &out), 0);
}

TEST(Cli, BadArgumentsAndFilesGiveOneClearErrorAndNonZeroExit) {
  std::string out;
  EXPECT_NE(run("build --tum /nonexistent/dir", &out), 0);
  EXPECT_NE(run(std::string("build --tum ") + RTOG_TEST_TUM_DIR + " --resolution -1", &out), 0);
  EXPECT_NE(run(std::string("build --tum ") + RTOG_TEST_TUM_DIR + " --merge sometimes", &out), 0);
  EXPECT_NE(out.find("unknown merge policy"), std::string::npos) << out;
  const std::string junk = ::testing::TempDir() + "/junk.rtog";
  std::ofstream(junk) << "this is not a map";
  EXPECT_NE(run("info " + junk, &out), 0);
  EXPECT_NE(out.find("not an rtog map"), std::string::npos) << out;
  // A failed save leaves nothing behind.
  EXPECT_NE(run(std::string("build --tum ") + RTOG_TEST_TUM_DIR + " --stride 8 --out /nonexistent/dir/m.rtog", &out), 0);
}

bool exists(const std::string& path) { return std::ifstream(path).good(); }

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// A small map built by the tool from the bundled frames, shared by the export cases.
const std::string& builtMap() {
  static const std::string path = [] {
    const std::string p = ::testing::TempDir() + "/cli_export_" + std::to_string(getpid()) + ".rtog";
    std::string out;
    EXPECT_EQ(run(std::string("build --tum ") + RTOG_TEST_TUM_DIR + " --resolution 0.1 --stride 4 --merge equal --out " + p,
                  &out),
              0)
        << out;
    return p;
  }();
  return path;
}

TEST(Cli, ExportsEveryFormatInOneCall) {
  const std::string dir = ::testing::TempDir() + "/cli_export_";
  const std::string ply = dir + "m.ply", bt = dir + "m.bt", png = dir + "slice.png", ascii = dir + "a.ply";
  for (const auto& f : {ply, bt, png, ascii}) std::remove(f.c_str());
  std::string out;
  ASSERT_EQ(run("export " + builtMap() + " --ply " + ply + " --bt " + bt + " --png " + png + " --slice-z 0.3 --png-cells", &out), 0)
      << out;
  EXPECT_NE(out.find("wrote " + ply), std::string::npos) << out;
  EXPECT_NE(out.find("wrote " + bt), std::string::npos) << out;
  EXPECT_NE(out.find("wrote " + png), std::string::npos) << out;
  for (const auto& f : {ply, bt, png}) EXPECT_FALSE(exists(f + ".partial")) << f;

  // Each file is exactly what the library writes for the saved map.
  const rtog::OccupancyMap map = rtog::cli::loadMap(builtMap());
  std::ostringstream want_ply, want_bt;
  const rtog::MeshExportStats ms = rtog::writeOccupiedPly(map, want_ply);
  EXPECT_EQ(ms.cuboids, map.statistics().occupied_leaves);
  EXPECT_TRUE(readAll(ply) == want_ply.str()) << "PLY differs";
  rtog::writeOctoMapBinary(map, want_bt);
  EXPECT_TRUE(readAll(bt) == want_bt.str()) << ".bt differs";
  EXPECT_EQ(readAll(bt).rfind("# Octomap OcTree binary file\n", 0), 0u);
  const cv::Mat img = cv::imread(png, cv::IMREAD_UNCHANGED), want_img = rtog::image::rasterizeSliceZ(map, 0.3);
  ASSERT_FALSE(img.empty());
  ASSERT_EQ(img.type(), CV_8UC1);
  ASSERT_EQ(img.size(), want_img.size());
  EXPECT_EQ(cv::norm(img, want_img, cv::NORM_INF), 0.0);
  // Without --png-cells: the picture to look at (rtog/image/picture.hpp), as the library draws it.
  ASSERT_EQ(run("export " + builtMap() + " --png " + png + " --slice-z 0.3", &out), 0) << out;
  const cv::Mat pic = cv::imread(png, cv::IMREAD_UNCHANGED), want_pic = rtog::image::slicePicture(map, 0.3, false);
  ASSERT_EQ(pic.type(), CV_8UC3);
  ASSERT_EQ(pic.size(), want_pic.size());
  EXPECT_EQ(cv::norm(pic, want_pic, cv::NORM_INF), 0.0);
  EXPECT_GT(pic.cols, img.cols);

  // The SceneViewer3D scene: MRPT loads it back and finds the drawn cuboids.
  const std::string scene = dir + "m.3Dscene";
  ASSERT_EQ(run("export " + builtMap() + " --scene " + scene, &out), 0) << out;
  mrpt::opengl::COpenGLScene loaded;
  ASSERT_TRUE(loaded.loadFromFile(scene));
  std::size_t objects = 0;
  for (const auto& o : *loaded.getViewport())
    if (const auto set = std::dynamic_pointer_cast<mrpt::opengl::CSetOfObjects>(o)) objects += set->size();
  EXPECT_GT(objects, 0u);

  ASSERT_EQ(run("export " + builtMap() + " --ply " + ascii + " --ascii", &out), 0) << out;
  EXPECT_EQ(readAll(ascii).rfind("ply\nformat ascii 1.0\n", 0), 0u);
  EXPECT_NE(readAll(ascii).find("element vertex " + std::to_string(ms.vertices) + "\n"), std::string::npos);
  EXPECT_NE(readAll(ascii).find("element face " + std::to_string(ms.faces) + "\n"), std::string::npos);
}

TEST(Cli, ExportErrorsExitNonZeroAndWriteNothing) {
  const std::string dir = ::testing::TempDir() + "/cli_export_bad_";
  const std::string ply = dir + "m.ply", bt = dir + "m.bt", png = dir + "s.png";
  const auto nothing_written = [&] {
    for (const auto& f : {ply, bt, png}) {
      EXPECT_FALSE(exists(f)) << f;
      EXPECT_FALSE(exists(f + ".partial")) << f;
    }
  };
  for (const auto& f : {ply, bt, png}) std::remove(f.c_str());
  const std::string& map = builtMap();
  std::string out;
  const auto expect_error = [&](const std::string& args, const std::string& message) {
    EXPECT_NE(run(args, &out), 0) << args;
    EXPECT_NE(out.find("rtog: error: "), std::string::npos) << args << ": " << out;
    EXPECT_NE(out.find(message), std::string::npos) << args << ": " << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << "one error line expected: " << out;
    nothing_written();
  };
  expect_error("export " + map, "nothing to do");
  expect_error("export", "map is required");
  expect_error("export " + map + " --png " + png, "--slice-z");
  expect_error("export " + map + " --slice-z 0.3", "--png");
  expect_error("export " + map + " --png " + png + " --slice-z high", "high");
  expect_error("export " + map + " --png " + png + " --slice-z 40", "outside the map's height range");
  expect_error("export " + map + " --ascii", "--ply");
  expect_error("export " + map + " --ply " + ply + " --bt " + ply, "named twice");
  expect_error("export /nonexistent/m.rtog --ply " + ply, "cannot open map file");
  const std::string junk = ::testing::TempDir() + "/junk_export.rtog";
  std::ofstream(junk) << "this is not a map";
  expect_error("export " + junk + " --bt " + bt, "not an rtog map");
  // One output failing leaves none of the others behind.
  expect_error("export " + map + " --ply " + ply + " --png " + png + " --slice-z 0.3 --bt /nonexistent/dir/m.bt",
               "/nonexistent/dir/m.bt");

  // Cells beyond OctoMap's 16-bit keys (here 4 km out at 10 cm): a clear error, no .bt.
  rtog::MapParams p;
  p.resolution = 0.1;
  rtog::OccupancyMap far(p);
  rtog::InsertParams ip;
  ip.model = rtog::SensorModel::BeamEndPoint;
  far.insertPointCloud(Eigen::Vector3d(4000.05, 0.05, 0.05), {Eigen::Vector3f(4000.35f, 0.05f, 0.05f)}, ip);
  const std::string far_map = ::testing::TempDir() + "/far.rtog";
  rtog::cli::saveMap(far, far_map);
  expect_error("export " + far_map + " --bt " + bt, "outside OctoMap's key range");
}

}  // namespace
