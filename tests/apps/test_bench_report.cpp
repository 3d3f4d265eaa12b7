// The benchmark's report on the committed run (doc/benchmarks.json): the JSON reads back as it
// was written, and the Markdown's insertion-speed verdicts follow from the raw build times. And
// the machine facts a report states, read from the system.
#include <gtest/gtest.h>

#include <iomanip>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "bench.hpp"
#include "rtog/app/output_files.hpp"

using namespace rtog::bench;

namespace {

const std::string kRun = RTOG_BENCH_JSON;

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeJsonFile(const std::vector<Result>& results, const RunInfo& run, const std::string& path) {
  rtog::app::OutputSet files;
  writeJson(results, run, files.add("--json", path));
  files.commit();
}

/// The Markdown report as rtog-bench writes it, its charts into `img_dir`.
std::string markdownOf(const std::vector<Result>& results, const RunInfo& run, const std::string& img_dir) {
  const std::string path = ::testing::TempDir() + "/bench_report.md";
  rtog::app::OutputSet files;
  writeMarkdown(results, run, files.add("--markdown", path), img_dir, files);
  files.commit();
  return slurp(path);
}

TEST(BenchReport, JsonReadsBackAsWritten) {
  RunInfo run;
  const std::vector<Result> results = readJson(kRun, run);
  ASSERT_GT(results.size(), 40u);
  // The bench's four datasets, the first scans of three of them (rot_scan has none), planning on
  // two maps and chunked builds of three logs.
  std::set<std::string> datasets, first_scans, plans;
  std::size_t chunks = 0;
  for (const auto& r : results) {
    if (r.extra.count("plan")) plans.insert(r.dataset);
    chunks += r.extra.count("chunks");
    if (rtog::bench::isTaskRow(r)) continue;
    (r.dataset.find(", first ") != std::string::npos ? first_scans : datasets).insert(r.dataset);
  }
  EXPECT_EQ(datasets.size(), 4u);
  EXPECT_EQ(first_scans.size(), 3u);
  EXPECT_EQ(plans.size(), 2u);
  EXPECT_EQ(chunks, 3u);
  EXPECT_FALSE(run.machine.at("cpu").empty());

  const std::string copy = ::testing::TempDir() + "/bench_copy.json";
  writeJsonFile(results, run, copy);
  RunInfo again;
  const std::vector<Result> back = readJson(copy, again);
  ASSERT_EQ(back.size(), results.size());
  EXPECT_EQ(again.machine, run.machine);
  EXPECT_EQ(again.repeats, run.repeats);
  for (std::size_t i = 0; i < back.size(); ++i) {
    EXPECT_EQ(back[i].method, results[i].method);
    EXPECT_EQ(back[i].insert_seconds, results[i].insert_seconds);
    EXPECT_EQ(back[i].build_seconds, results[i].build_seconds);
    EXPECT_EQ(back[i].structure_bytes, results[i].structure_bytes);
    EXPECT_EQ(back[i].extra, results[i].extra);
  }
}

TEST(BenchReport, BrokenJsonIsAnError) {
  RunInfo run;
  EXPECT_THROW(readJson(::testing::TempDir() + "/no_such_run.json", run), std::runtime_error);
  const std::string text = slurp(kRun);
  const std::string cut = ::testing::TempDir() + "/bench_cut.json";
  std::ofstream(cut) << text.substr(0, text.size() / 2);
  EXPECT_THROW(readJson(cut, run), std::runtime_error);
  const std::string wrong = ::testing::TempDir() + "/bench_wrong.json";
  std::ofstream(wrong) << R"({"machine": {}, "results": [{"dataset": "x", "method": 3}]})";
  EXPECT_THROW(readJson(wrong, run), std::runtime_error);
}

TEST(BenchReport, SpeedVerdictsFollowFromTheBuildTimes) {
  RunInfo run;
  const std::vector<Result> results = readJson(kRun, run);
  std::istringstream md(markdownOf(results, run, ::testing::TempDir()));
  int rows = 0;
  for (std::string line; std::getline(md, line);) {
    const std::string marker = "insertion ≥ 20× faster than OctoMap's best (";
    if (line.find(marker) == std::string::npos) continue;
    ++rows;
    // | dataset | res | target | measured | verdict |
    std::vector<std::string> cells;
    for (std::size_t p = 1, q; (q = line.find(" |", p)) != std::string::npos; p = q + 2)
      cells.push_back(line.substr(p + 1, q - p - 1));
    ASSERT_EQ(cells.size(), 5u) << line;
    const double res = std::stod(cells[1]);
    double octomap = std::numeric_limits<double>::infinity(), rtog = octomap;
    for (const auto& r : results) {
      if (r.dataset != cells[0] || r.resolution != res) continue;
      if (r.method.rfind("OctoMap", 0) == 0) octomap = std::min(octomap, r.insert_seconds);
      if (r.method == "rtog beam, merge equal" || r.method == "rtog beam, merge equal, 2 threads" ||
          r.method == "rtog beam discretize, merge equal, 2 threads")
        rtog = std::min(rtog, r.insert_seconds);
    }
    const double ratio = octomap / rtog;
    EXPECT_NEAR(std::stod(cells[3]), ratio, 0.006 * ratio) << line;
    const std::string want = res == 0.05 ? (ratio >= 20.0 ? "PASS" : "FAIL") : "– (target set at 0.05 m)";
    EXPECT_EQ(cells[4], want) << line;
  }
  EXPECT_EQ(rows, 6);  // three 3D datasets at two resolutions
}

// The planning and chunked-build sections: one table row per result, its figures the JSON's.
TEST(BenchReport, PlanningAndChunkedBuildRowsAreTheJsons) {
  RunInfo run;
  const std::vector<Result> results = readJson(kRun, run);
  const std::string md = markdownOf(results, run, ::testing::TempDir());
  ASSERT_NE(md.find("## Risk-aware planning beside MRPT's PlannerSimple2D"), std::string::npos);
  ASSERT_NE(md.find("## Building in chunks"), std::string::npos);
  std::size_t rows = 0;
  for (const auto& r : results) {
    if (!isTaskRow(r) || r.extra.count("app_row")) continue;  // the apps' rows: AppRowsJoinTheReport...
    std::ostringstream want;
    want << std::fixed << std::setprecision(r.extra.count("plan") ? 2 : 3)
         << (r.extra.count("plan") ? r.extra.at("length_m") : r.extra.at("one_process_s"));
    const std::string head = "| " + (r.extra.count("plan") ? r.method : r.dataset) + " | ";
    bool found = false;
    for (std::size_t at = md.find(head); at != std::string::npos && !found; at = md.find(head, at + 1))
      found = md.substr(at, md.find('\n', at) - at).find("| " + want.str() + " |") != std::string::npos;
    EXPECT_TRUE(found) << head << want.str();
    ++rows;
  }
  EXPECT_EQ(rows, 13u);  // 2 maps x (PlannerSimple2D + 4 rtog rows), 3 chunked logs
}

TEST(BenchReport, MachineFactsComeFromTheSystem) {
  const auto m = machineFacts();
  EXPECT_FALSE(m.at("cpu").empty());
  EXPECT_EQ(m.at("cores"), std::to_string(sysconf(_SC_NPROCESSORS_ONLN)));
  EXPECT_TRUE(std::regex_match(m.at("memory"), std::regex(R"([0-9]+\.[0-9] GiB)"))) << m.at("memory");
  EXPECT_EQ(m.at("os").rfind("Linux ", 0), 0u) << m.at("os");
  EXPECT_TRUE(std::regex_match(m.at("mrpt"), std::regex(R"([0-9]+\.[0-9]+\.[0-9]+)"))) << m.at("mrpt");
  EXPECT_TRUE(std::regex_match(m.at("octomap"), std::regex(R"([0-9]+\.[0-9]+\.[0-9]+)"))) << m.at("octomap");
  EXPECT_TRUE(std::regex_match(m.at("date"), std::regex(R"(20[0-9]{2}-[0-9]{2}-[0-9]{2}T[0-9]{2}:[0-9]{2}Z)")))
      << m.at("date");
  EXPECT_FALSE(m.at("compiler").empty());
}

}  // namespace

// The MRPT apps' rows (app_rows.py --json) join the report through --app-rows, render as their
// section, and survive a render from the bench's JSON; a file that is not such a list is refused.
TEST(BenchReport, AppRowsJoinTheReportAndSurviveTheJson) {
  const std::string dir = ::testing::TempDir() + "/app_rows_" + std::to_string(getpid());
  ASSERT_EQ(std::system(("mkdir -p " + dir).c_str()), 0);
  {
    std::ofstream f(dir + "/rows.json");
    f << R"([{"app": "rbpf-slam", "log": "SENA.rawlog", "particles": 25, "map": "COccupancyGridMap2D", "repeats": 3,
              "ok": true, "wall_s": 4.4, "peak_rss_mb": 503.2},
             {"app": "rbpf-slam", "log": "SENA.rawlog", "particles": 25, "map": "rtreeOccupancyGrid", "repeats": 3,
              "ok": true, "wall_s": 3.15, "peak_rss_mb": 203.8, "wall_ratio": 0.716, "rss_ratio": 0.406,
              "path_mean_m": 0.0, "path_max_m": 0.0},
             {"app": "rbpf-slam", "log": "SENA.rawlog", "particles": 100, "map": "rtreeOccupancyGrid", "repeats": 3,
              "ok": true, "wall_s": 11.92, "peak_rss_mb": 328.0, "wall_ratio": 0.77, "rss_ratio": 0.2,
              "path_mean_m": 0.0, "path_max_m": 0.0},
             {"app": "icp-slam", "log": "SENA.rawlog", "particles": null, "map": "rtreeGridMap2D", "repeats": 1,
              "ok": false}])";
  }
  const auto run = [&](const std::string& args) {
    FILE* p = popen((std::string(RTOG_BENCH_EXE) + " " + args + " 2>&1").c_str(), "r");
    std::string out;
    char buf[512];
    while (p && std::fgets(buf, sizeof buf, p)) out += buf;
    return std::make_pair(p ? pclose(p) : -1, out);
  };
  const auto [rc, out] = run("--from-json " + std::string(RTOG_BENCH_JSON) + " --app-rows " + dir +
                             "/rows.json --markdown " + dir + "/report.md --img-dir " + dir);
  ASSERT_EQ(rc, 0) << out;
  std::ifstream md(dir + "/report.md");
  std::stringstream text;
  text << md.rdbuf();
  const std::string report = text.str();
  EXPECT_NE(report.find("## The MRPT apps as processes"), std::string::npos);
  EXPECT_NE(report.find("| rbpf-slam | SENA.rawlog | 25 | `rtreeOccupancyGrid` | 3.15 (0.72×) | 204 (0.41×) | 0.000 / 0.000 | 3 |"),
            std::string::npos)
      << report.substr(report.find("## The MRPT apps"));
  EXPECT_NE(report.find("| rbpf-slam | SENA.rawlog | 100 | `rtreeOccupancyGrid` | 11.92 (0.77×)"), std::string::npos)
      << "a row of another particle count of the same app and map is kept";
  EXPECT_NE(report.find("| icp-slam | SENA.rawlog | – | `rtreeGridMap2D` | failed |"), std::string::npos);
  // Read back: the rows are results like the others.
  const auto rows = readAppRows(dir + "/rows.json");
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[1].method, "rbpf-slam | rtreeOccupancyGrid | 25 particles");
  EXPECT_EQ(rows[1].dataset, "MRPT apps: SENA.rawlog");
  EXPECT_TRUE(isTaskRow(rows[1]));
  {
    std::ofstream f(dir + "/bad.json");
    f << R"({"app": "rbpf-slam"})";
  }
  const auto [bad_rc, bad_out] = run("--from-json " + std::string(RTOG_BENCH_JSON) + " --app-rows " + dir +
                                     "/bad.json --markdown " + dir + "/bad.md --img-dir " + dir);
  EXPECT_NE(bad_rc, 0);
  EXPECT_NE(bad_out.find("not a list"), std::string::npos) << bad_out;
  EXPECT_FALSE(std::ifstream(dir + "/bad.md").good()) << "a refused run writes nothing";
}
