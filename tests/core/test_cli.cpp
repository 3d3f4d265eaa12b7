// The rtog tool as a user runs it: real data in, a map file out, errors reported cleanly.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "commands.hpp"

namespace {

int run(const std::string& args, std::string* output = nullptr) {
  const std::string out_file = ::testing::TempDir() + "/rtog_cli_out.txt";
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

}  // namespace
