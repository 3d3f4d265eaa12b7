// The accuracy report as JSON (nlohmann-json: every string escaped by the JSON rules, control
// characters included) and as Markdown tables.
#include <algorithm>
#include <iomanip>
#include <ostream>

#include <nlohmann/json.hpp>

#include "accuracy.hpp"

namespace rtog::accuracy {

namespace {
// ordered_json: the fields stay in the order a reader expects (config first, results last).
using Json = nlohmann::ordered_json;

Json configJson(const Config& c) {
  return Json{{"seed", c.seed},
              {"lidar_seed", c.lidar_seed},
              {"scanner_seed", c.scanner_seed},
              {"resolution", c.resolution},
              {"stride", c.stride},
              {"lidar",
               {{"rings", c.lidar.rings},
                {"azimuth_steps", c.lidar.azimuth_steps},
                {"elev_min_deg", c.lidar.elev_min_deg},
                {"elev_max_deg", c.lidar.elev_max_deg},
                {"max_range", c.lidar.max_range},
                {"sigma", c.lidar.sigma},
                {"height", c.lidar.height}}},
              {"scanner",
               {{"fov_deg", c.scanner.fov_deg},
                {"step_deg", c.scanner.step_deg},
                {"max_range", c.scanner.max_range},
                {"sigma", c.scanner.sigma},
                {"height", c.scanner.height}}},
              {"pose_noise",
               {{"sigma_xy", c.pose_sigma_xy}, {"sigma_yaw_deg", c.pose_sigma_yaw_deg}, {"correlation", c.pose_correlation}, {"seed", c.pose_seed}}},
              {"calibration_seed", c.calibration_seed},
              {"calibrated_clamp_readings", c.calibrated_clamp_readings}};
}

Json resultJson(const MapResult& m) {
  const sim::ClassMetrics& x = m.metrics;
  Json roc = Json::array();
  // A graded model has a point per distinct probability (about 10^5): at most ~256 are kept,
  // evenly by index, the ends included; the AUC above is computed from all of them.
  const std::size_t every = std::max<std::size_t>(1, x.roc.size() / 256);
  for (std::size_t i = 0; i < x.roc.size(); ++i)
    if (i % every == 0 || i + 1 == x.roc.size()) roc.push_back({x.roc[i].first, x.roc[i].second});
  Json reliability = Json::array();
  for (const auto& b : x.reliability)
    reliability.push_back({{"mean_p", b.mean_p}, {"occupied_share", b.occupied_share}, {"cells", b.cells}});
  return Json{{"scenario", m.scenario},
              {"map", m.map},
              {"insert_seconds", m.insert_seconds},
              {"observed_cells", m.observed_cells},
              {"observed_outside", m.observed_outside},
              {"class_agreement_with_octomap", m.agreement_octomap},
              {"cells", x.cells},
              {"pred_occupied", x.pred_occupied},
              {"pred_free", x.pred_free},
              {"unknown", x.unknown},
              {"tp_occupied", x.tp_occupied},
              {"tp_free", x.tp_free},
              {"precision_occupied", x.precision_occupied},
              {"recall_occupied", x.recall_occupied},
              {"precision_free", x.precision_free},
              {"recall_free", x.recall_free},
              {"auc", x.auc},
              {"brier", x.brier},
              {"nll", x.nll},
              {"ece", x.ece},
              {"reliability", reliability},
              {"roc", roc}};
}
}  // namespace

void writeJson(const Report& r, std::ostream& os) {
  Json j;
  j["config"] = configJson(r.config);
  j["world"] = r.world_summary;
  j["versions"] = {{"octomap", r.octomap_version}, {"mrpt", r.mrpt_version}};
  j["total_seconds"] = r.total_seconds;
  auto rates = [](const sim::InverseModelRates& x) {
    return Json{{"prob_hit", x.prob_hit}, {"prob_miss", x.prob_miss}, {"end_cells", x.end_cells}, {"crossed_cells", x.crossed_cells}};
  };
  j["calibration"] = {{"lidar3d", rates(r.calibration_lidar)}, {"scanner2d", rates(r.calibration_scanner)}};
  j["scenarios"] = Json::array();
  for (const Scenario& s : r.scenarios)
    j["scenarios"].push_back({{"name", s.name},
                              {"description", s.description},
                              {"scans", s.scans},
                              {"beams", s.beams},
                              {"returns", s.returns},
                              {"region_cells", s.region_cells},
                              {"evaluated_cells", s.evaluated_cells},
                              {"truth_occupied", s.truth_occupied},
                              {"truth_free", s.truth_free}});
  j["results"] = Json::array();
  for (const MapResult& m : r.results) j["results"].push_back(resultJson(m));
  os << j.dump(2) << "\n";
}

void writeMarkdown(const Report& r, std::ostream& os) {
  os << std::fixed;
  for (const Scenario& s : r.scenarios) {
    os << "**" << s.name << "** — " << s.description << "; " << s.scans << " scans, " << s.beams << " beams ("
       << s.returns << " returns); evaluated cells " << s.evaluated_cells << " (truth: " << s.truth_occupied
       << " occupied, " << s.truth_free << " free)\n\n";
    os << "| map | observed cells | occupied precision | occupied recall | free precision | free recall | ROC AUC | Brier | NLL [nats] | ECE | "
          "same class as OctoMap | insert time [s] |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const MapResult& m : r.results) {
      if (m.scenario != s.name) continue;
      const auto& x = m.metrics;
      os << "| " << m.map << " | " << m.observed_cells << " | " << std::setprecision(4) << x.precision_occupied
         << " | " << x.recall_occupied << " | " << x.precision_free << " | " << x.recall_free << " | " << x.auc
         << " | " << x.brier << " | " << x.nll << " | " << x.ece << " | " << m.agreement_octomap << " | " << std::setprecision(2) << m.insert_seconds << " |\n";
    }
    os << "\n";
  }
}

}  // namespace rtog::accuracy
