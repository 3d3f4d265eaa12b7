#include "rtog/sim/calibration.hpp"

#include <cmath>
#include <stdexcept>

namespace rtog::sim {

InverseModelRates measureInverseModel(const TruthGrid& truth, const Lattice& lat, const std::vector<Scan>& scans) {
  std::size_t hit_occ = 0, hit_n = 0, miss_occ = 0, miss_n = 0;
  const Box& R = truth.region();
  const double step = 0.25 * lat.resolution();
  for (const Scan& s : scans)
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      const Eigen::Vector3d end = s.points[i].cast<double>();
      Key ke;
      if (!lat.tryKey(end, ke)) continue;
      const bool ret = s.is_hit[i] != 0;
      if (ret && R.contains(ke)) {
        ++hit_n;
        hit_occ += truth.occupied(ke);
      }
      const Eigen::Vector3d d = end - s.origin;
      const double len = d.norm();
      if (!(len > 0)) continue;
      const Eigen::Vector3d u = d / len;
      Key last{0, 0, 0};
      bool have_last = false;
      for (double t = 0.0; t < len; t += step) {
        Key k;
        if (!lat.tryKey(s.origin + u * t, k)) break;
        if (ret && k == ke) break;  // the end cell is the hit's, not a miss
        if (have_last && k == last) continue;
        last = k;
        have_last = true;
        if (!R.contains(k)) continue;
        ++miss_n;
        miss_occ += truth.occupied(k);
      }
    }
  if (hit_n == 0 || miss_n == 0) throw std::invalid_argument("rtog::sim::measureInverseModel: no beam sample in the region");
  InverseModelRates r;
  r.prob_hit = static_cast<double>(hit_occ) / static_cast<double>(hit_n);
  r.prob_miss = static_cast<double>(miss_occ) / static_cast<double>(miss_n);
  r.end_cells = hit_n;
  r.crossed_cells = miss_n;
  return r;
}

}  // namespace rtog::sim
