// Expected information gain of a view (rtog/core/explore.hpp): the sensor's rays walked through
// the cells (CellReader), the reach of each ray at each cell, each cell's gain under the map's own
// update once per scan.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

#include "explore/cell_reader.hpp"
#include "explore/views.hpp"
#include "rtog/core/explore.hpp"
#include "rtog/core/log_odds.hpp"
#include "rtog/core/ray_traversal.hpp"

namespace rtog {

std::vector<Eigen::Vector3d> ViewSensor::rays() const {
  const auto bad = [](const char* why) { throw std::invalid_argument(std::string("rtog::ViewSensor: ") + why); };
  if (!(std::isfinite(max_range) && max_range > 0.0)) bad("max_range must be positive and finite");
  std::vector<Eigen::Vector3d> out;
  if (kind == Kind::Laser2D) {
    if (!(aperture > 0.0 && aperture <= 2.0 * M_PI)) bad("the aperture must lie in (0, 2 pi]");
    if (beams < 1 || beams > 100000) bad("beams must lie in [1, 100000]");
    for (int i = 0; i < beams; ++i) {
      const double a = beams == 1 ? 0.0 : -0.5 * aperture + aperture * i / (beams - 1);
      out.emplace_back(std::cos(a), std::sin(a), 0.0);
    }
    return out;
  }
  if (width < 1 || height < 1 || width > 100000 || height > 100000) bad("width and height must lie in [1, 100000]");
  if (!(fx > 0.0 && fy > 0.0 && std::isfinite(fx) && std::isfinite(fy) && std::isfinite(cx) && std::isfinite(cy)))
    bad("the intrinsics must be finite, fx and fy positive");
  if (stride < 1) bad("stride must be at least 1");
  for (int v = 0; v < height; v += stride)
    for (int u = 0; u < width; u += stride) out.push_back(Eigen::Vector3d((u - cx) / fx, (v - cy) / fy, 1.0).normalized());
  return out;
}

namespace explore_detail {

double entropyBits(double p) {
  if (!(p > 0.0 && p < 1.0)) return 0.0;
  return -(p * std::log2(p) + (1.0 - p) * std::log2(1.0 - p));
}

double cellGain(const LogOddsModel& model, float log_odds) {
  const double p = probability(log_odds);
  const double hit = probability(model.update(log_odds, model.hitDelta()));
  const double miss = probability(model.update(log_odds, model.missDelta()));
  return entropyBits(p) - (p * entropyBits(hit) + (1.0 - p) * entropyBits(miss));
}

ViewGain gainOf(CellReader& cells, const OccupancyMap& map, const Eigen::Isometry3d& pose, const std::vector<Eigen::Vector3d>& rays,
                double max_range) {
  const Lattice& lattice = map.lattice();
  const LogOddsModel& model = map.logOddsModel();
  const float occupied = model.occupiedThreshold();
  struct Seen {
    double missed = 1.0;  // prod over rays of (1 - reach)
    float log_odds;
    bool known;
  };
  std::unordered_map<std::uint64_t, Seen> seen;
  const Eigen::Vector3d origin = pose.translation();
  Key from_key;
  if (!origin.allFinite() || !lattice.tryKey(origin, from_key)) return {};
  const Eigen::Vector3d from = lattice.toLattice(origin);
  for (const Eigen::Vector3d& r : rays) {
    const Eigen::Vector3d end = origin + pose.linear() * r * max_range;
    Key to_key;
    if (!lattice.tryKey(end, to_key)) continue;  // a ray out of the keys: not cast
    double reach = 1.0;
    traverseRay(from, lattice.toLattice(end), from_key, to_key, [&](const Key& k) {
      if (reach < kMinReach) return;  // stopped: the rest of the walk reads nothing
      const float v = cells.at(k);
      const bool known = !std::isnan(v);
      auto it = seen.try_emplace(packKey(k), Seen{1.0, known ? v : model.prior(), known}).first;
      it->second.missed *= 1.0 - reach;
      if (known && v >= occupied) reach *= 1.0 - probability(v);
    });
  }
  ViewGain g;
  for (const auto& [code, s] : seen) {
    const double observed = 1.0 - s.missed;
    g.bits += observed * cellGain(model, s.log_odds);
    if (observed > 0.5) ++g.cells, g.unknown_cells += !s.known;
  }
  return g;
}

}  // namespace explore_detail

ViewGain informationGain(const OccupancyMap& map, const Eigen::Isometry3d& sensor_pose, const ViewSensor& sensor) {
  explore_detail::CellReader cells(map);
  return explore_detail::gainOf(cells, map, sensor_pose, sensor.rays(), sensor.max_range);
}

}  // namespace rtog
