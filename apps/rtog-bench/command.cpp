// rtog-bench's run: the datasets it was asked for, every method on each, the first-scan rows in
// fresh processes, then the report's files through one OutputSet (opened before the run, so that
// a bad path fails at once; the JSON, the Markdown and the charts are written all or none).
#include <algorithm>
#include <ostream>
#include <set>
#include <stdexcept>

#include "bench.hpp"
#include "first_scan.hpp"
#include "rtog/app/output_files.hpp"

namespace rtog::bench {

int runCommand(const Command& cmd, std::ostream& out, std::ostream& err) {
  try {
    std::vector<app::InputFile> inputs;
    if (!cmd.from_json.empty()) inputs.push_back({"--from-json", cmd.from_json});
    if (!cmd.merge_json.empty()) inputs.push_back({"--merge-json", cmd.merge_json});
    for (const auto& f : cmd.app_rows) inputs.push_back({"--app-rows", f});
    app::OutputSet files(std::move(inputs));
    std::ostream* json = cmd.from_json.empty() ? &files.add("--json", cmd.json) : nullptr;
    std::ostream& markdown = files.add("--markdown", cmd.markdown);
    RunInfo run;
    std::vector<Result> results;
    if (!cmd.from_json.empty()) {
      results = readJson(cmd.from_json, run);
    } else {
      run = currentRun(cmd.opts);
      const auto wanted = [&](const std::string& n) {
        return cmd.only.empty() || std::find(cmd.only.begin(), cmd.only.end(), n) != cmd.only.end();
      };
      const std::string vlp16 = cmd.mrpt_datasets_dir + "/test_velodyne_VLP16.rawlog";
      const std::string sena = cmd.mrpt_datasets_dir + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";
      std::vector<Dataset> sets;
      if (wanted("tum")) sets.push_back(loadTum(cmd.tum_dir));
      if (wanted("vlp16")) sets.push_back(loadRawlog3D(vlp16, "Velodyne VLP-16 (test_velodyne_VLP16)"));
      if (wanted("rotscan"))
        sets.push_back(loadRawlog3D(cmd.mrpt_datasets_dir + "/rot_scan_velodyne.rawlog",
                                    "Velodyne rotating scan (rot_scan_velodyne)"));
      if (wanted("sena")) run2D(sena, cmd.opts, results, out);
      for (const auto& data : sets) {
        out << data.name << ": " << data.points() << " points\n";
        runDataset(data, cmd.opts, results, out);
      }
      // rot_scan_velodyne has none: MRPT 2.5's COctoMap does not insert a CObservationRotatingScan.
      std::vector<FirstScanSource> first;
      if (wanted("tum")) first.push_back({"tum", cmd.tum_dir, "TUM fr2/pioneer_slam2, first frame"});
      if (wanted("vlp16")) first.push_back({"rawlog3d", vlp16, "Velodyne VLP-16 (test_velodyne_VLP16), first scan"});
      if (wanted("sena")) first.push_back({"rawlog2d", sena, "SENA 2D laser, first scan"});
      if (!first.empty()) out << "first scans, each in a fresh process (" << cmd.first_scan_helper << ")\n";
      runFirstScans(cmd.first_scan_helper, first, cmd.opts, results, out);
      if (wanted("plan")) runPlanning(cmd.mrpt_datasets_dir, cmd.opts, results, out);
      if (wanted("chunks")) runChunkedBuilds(cmd.rtog_cli, chunkedLogs(cmd.tum_dir, sena), cmd.opts, results, out);
      if (!cmd.merge_json.empty()) {
        // The rows of the datasets this run did not measure, from the earlier report.
        RunInfo earlier;
        std::set<std::string> measured;
        for (const auto& r : results) measured.insert(r.dataset);
        for (auto& r : readJson(cmd.merge_json, earlier))
          if (!measured.count(r.dataset)) results.push_back(std::move(r));
        // The dates of the runs the kept rows come from (an earlier report may itself be merged).
        const auto when = earlier.machine.find("date");
        const auto before = earlier.machine.find("merged_rows_date");
        run.machine["merged_rows_date"] = (before == earlier.machine.end() ? std::string() : before->second + ", ") +
                                          (when == earlier.machine.end() ? std::string("?") : when->second);
        // And their machines' CPUs, each once: the report says where the kept rows were measured.
        const auto cpus = earlier.machine.find("merged_rows_cpu");
        const auto cpu = earlier.machine.find("cpu");
        std::string kept = cpus == earlier.machine.end() ? std::string() : cpus->second;
        const std::string that = cpu == earlier.machine.end() ? std::string("?") : cpu->second;
        if (kept.empty() && cpus == earlier.machine.end()) kept = that;
        else if (("; " + kept + "; ").find("; " + that + "; ") == std::string::npos) kept += "; " + that;
        run.machine["merged_rows_cpu"] = kept;
      }
    }
    for (const auto& file : cmd.app_rows)
      for (auto& row : readAppRows(file)) {
        results.erase(std::remove_if(results.begin(), results.end(),
                                     [&](const Result& r) { return r.dataset == row.dataset && r.method == row.method; }),
                      results.end());
        results.push_back(std::move(row));
      }
    if (json) writeJson(results, run, *json);
    writeMarkdown(results, run, markdown, cmd.img_dir, files);
    files.commit();
    out << "wrote " << (json ? cmd.json + ", " : "") << cmd.markdown << "\n";
  } catch (const std::exception& e) {
    err << "rtog-bench: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace rtog::bench
