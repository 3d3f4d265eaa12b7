#include "sonar_cones.hpp"

#include <algorithm>
#include <utility>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "mrpt_grid.hpp"

namespace rtog::sonar {

using mrpt::poses::CPose3D;

std::vector<ConeReading> readings(const mrpt::obs::CObservationRange& o, const CPose3D& robotPose,
                                  const CRTreeOccupancyGridMap::TInsertionOptions& io, std::size_t& invalid) {
  constexpr double kPi = 3.14159265358979323846;
  const double aperture = o.sensorConeApperture;
  if (!(aperture >= 0.0 && aperture <= kPi))
    throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: a CObservationRange's sensorConeApperture must lie in "
                                "[0, pi] rad, got " + std::to_string(aperture));
  const double max_sensor = o.maxSensorDistance;
  if (!(max_sensor > 0.0 && std::isfinite(max_sensor)))
    throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: a CObservationRange's maxSensorDistance must be "
                                "positive and finite, got " + std::to_string(max_sensor));
  // Each reading has its own sensor pose: a non-finite one (any component: a NaN roll still
  // tilts the cone) is a bad sensor description, as a bad aperture is, refused before any change.
  for (std::size_t k = 0; k < o.sensedData.size(); ++k)
    for (int i = 0; i < 6; ++i)
      if (!std::isfinite(o.sensedData[k].sensorPose[i]))
        throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: a CObservationRange's reading " + std::to_string(k) +
                                    " has a non-finite sensor pose (" + o.sensedData[k].sensorPose.asString() + ")");
  const double cut = io.maxDistanceInsertion > 0.0f ? static_cast<double>(io.maxDistanceInsertion)
                                                    : std::numeric_limits<double>::infinity();
  std::vector<ConeReading> out;
  invalid = 0;
  for (const auto& d : o.sensedData) {
    const CPose3D sensor = robotPose + CPose3D(d.sensorPose);
    if (io.useMapAltitude && std::fabs(io.mapAltitude - sensor.z()) > 0.001) continue;  // as the grid filters
    ConeReading r;
    r.origin = Eigen::Vector3d(sensor.x(), sensor.y(), sensor.z());
    r.yaw = sensor.yaw();
    r.aperture = aperture;
    const double z = d.sensedDistance;
    if (!std::isfinite(z) || !(z > 0.0)) {  // no reading at all (MRPT's sonarSimulator writes 0)
      ++invalid;
      continue;
    }
    r.hit = z < max_sensor;
    r.range = r.hit ? z : max_sensor;
    if (!r.hit && !io.considerInvalidRangesAsFreeSpace) {
      ++invalid;
      continue;
    }
    if (r.range > cut) {  // cut as beams are: free up to maxDistanceInsertion, no arc
      r.range = cut;
      r.hit = false;
    }
    out.push_back(r);
  }
  return out;
}

InsertStats insertOnGrid(OccupancyMap& map, TGridFrame2D& frame, const std::vector<ConeReading>& cones,
                         const CRTreeOccupancyGridMap::TInsertionOptions& io) {
  InsertStats stats;
  if (cones.empty()) return stats;
  const double res = map.resolution();
  TGridFrame2D grown = frame;
  if (!grown.has_layer) {
    Key k;
    if (!map.lattice().tryKey(cones.front().origin, k))
      throw std::out_of_range("rtog::CRTreeOccupancyGridMap: a sonar reading's height has no key");
    grown.has_layer = true;
    grown.layer = k.z;
  }
  const std::uint32_t max_cells = io.toInsertParams().max_ray_cells;  // 0: unbounded
  std::vector<std::vector<ConeCell>> cells(cones.size());
  float x0 = std::numeric_limits<float>::max(), x1 = -x0, y0 = x0, y1 = -x0;
  for (std::size_t i = 0; i < cones.size(); ++i) {
    ConeReading r = cones[i];
    r.origin.z() = (grown.layer + 0.5) * res;
    if (max_cells > 0 && r.range / res > max_cells) {  // bounded as a beam is
      ++stats.skipped_too_long;
      continue;
    }
    coneCells(map.lattice(), r, coneWeightingFromString(io.sonarConeWeighting), cells[i], nullptr);
    ++(r.hit ? stats.rays_hit : stats.rays_truncated);
    for (const ConeCell& c : cells[i]) {
      x0 = std::min(x0, static_cast<float>(c.x * res)), x1 = std::max(x1, static_cast<float>((c.x + 1) * res));
      y0 = std::min(y0, static_cast<float>(c.y * res)), y1 = std::max(y1, static_cast<float>((c.y + 1) * res));
    }
  }
  if (x0 <= x1) {
    float g[4];
    mrpt_grid::growRect(grown, x0, x1, y0, y1, g);
    mrpt_grid::resize(grown, g[0], g[1], g[2], g[3]);
    // Reading after reading, each of its cells once with its kind's step scaled by the cell's
    // weight and rounded to whole int8 units (half away from zero; a step of 0 leaves the cell as
    // it was). The cells of one kind and step go together: a whole step under the grid's own rule
    // (uniform: every cell), a smaller one saturating within itself of the bound, as the grid
    // saturates within its step.
    const mrpt_grid::Steps full = mrpt_grid::stepsOf(io);
    const StepRule grid_rule = mrpt_grid::stepRule(full);
    const auto wholeStep = [&](StepKind k) {
      return k == StepKind::Occupied ? full.occupied : k == StepKind::FreeNoEcho ? full.noecho : full.free;
    };
    const auto stepOf = [&](const ConeCell& c) {
      return static_cast<int>(std::lround(double{c.weight} * wholeStep(c.kind)));
    };
    std::vector<OccupancyMap::StepRun> runs;
    for (const auto& rc : cells) {
      std::vector<std::pair<StepKind, int>> groups;
      for (const ConeCell& c : rc) {
        const std::pair<StepKind, int> g{c.kind, stepOf(c)};
        if (g.second > 0 && std::find(groups.begin(), groups.end(), g) == groups.end()) groups.push_back(g);
      }
      std::sort(groups.begin(), groups.end());
      for (const auto& [kind, k] : groups) {
        runs.clear();
        for (const ConeCell& c : rc) {
          if (c.kind != kind || stepOf(c) != k) continue;
          OccupancyMap::StepRun s{};
          s.x = c.x, s.y = c.y;
          s.kind = c.kind;
          s.count = c.kind == StepKind::Occupied ? 0 : 1;
          s.end = c.kind == StepKind::Occupied;
          s.end_x = c.x, s.end_y = c.y;
          runs.push_back(s);
        }
        StepRule rule = grid_rule;
        if (k != wholeStep(kind)) {
          const auto i = static_cast<std::size_t>(kind);
          rule.delta[i] = mrpt_grid::valueOfCell(kind == StepKind::Occupied ? -k : k);
          rule.limit[i] = mrpt_grid::stepLimit(kind, k, full);
        }
        stats += map.applyStepRuns(grown.layer, runs.data(), runs.size(), rule);
      }
    }
    frame = grown;
  }
  return stats;
}

bool scorable(const mrpt::obs::CObservationRange& o, const CPose3D& pose) {
  if (!(std::isfinite(pose.x()) && std::isfinite(pose.y()) && std::isfinite(pose.yaw()))) return false;
  const double aperture = o.sensorConeApperture, max_range = o.maxSensorDistance;
  return (aperture >= 0.0 && aperture <= 3.14159265358979323846) && (max_range > 0.0 && std::isfinite(max_range));
}

std::optional<double> likelihood(const mrpt::obs::CObservationRange& o, const CPose3D& pose,
                                 const CRTreeOccupancyGridMap::TLikelihoodOptions& lo,
                                 const mrpt::maps::COccupancyGridMap2D& grid) {
  // A sonar echoes from the nearest surface anywhere in its cone: the reading expected from a
  // pose is the shortest of rays cast across the aperture on the 2D view (as MRPT's
  // sonarSimulator computes a reading), and each echo scores a Gaussian of rayTracing_stdHit
  // about it mixed with LF_zHit / LF_zRandom, as the ray-tracing likelihood of beams. A surface
  // nearer than the echo inside the cone counts against a pose, which a likelihood field of the
  // axis's end point cannot see (MRPT's grid scores that, doc/sonar.md).
  const double aperture = o.sensorConeApperture, max_range = o.maxSensorDistance;
  const double inv2var = 1.0 / (2.0 * double(lo.rayTracing_stdHit) * lo.rayTracing_stdHit);
  const double z_random = double(lo.LF_zRandom) / lo.LF_maxRange;
  const double res = grid.getResolution();
  double sum = 0.0;
  for (const auto& d : o.sensedData) {
    const double z = d.sensedDistance;
    if (!std::isfinite(z) || !(z > 0.0) || !(z < max_range)) continue;  // echoes only
    const CPose3D sensor = pose + CPose3D(d.sensorPose);
    if (!(std::isfinite(sensor.x()) && std::isfinite(sensor.y()) && std::isfinite(sensor.yaw()))) return std::nullopt;
    // Rays half a cell apart at the far end of the cone.
    const auto n = static_cast<int>(std::min(512.0, std::ceil(aperture * max_range / (0.5 * res)))) + 1;
    double expected = max_range;
    for (int j = 0; j < n; ++j) {
      const double a = sensor.yaw() + (n == 1 ? 0.0 : aperture * (static_cast<double>(j) / (n - 1) - 0.5));
      float r = 0.0f;
      bool valid = false;
      grid.simulateScanRay(sensor.x(), sensor.y(), a, r, valid, max_range, 0.5f, 0.0, 0.0);
      if (valid) expected = std::min<double>(expected, r);
    }
    const double e = z - expected;
    sum += std::log(z_random + lo.LF_zHit * std::exp(-e * e * inv2var));
  }
  return sum;
}

void endPoints(const mrpt::obs::CObservationRange& o, const CPose3D& robotPose, ObservationBeams& out) {
  // The likelihood of a reading is that of its axis's end point, as COccupancyGridMap2D scores a
  // CObservationRange (a points map of the readings, then its likelihood field).
  const CPose3D first = o.sensedData.empty() ? robotPose : robotPose + CPose3D(o.sensedData.front().sensorPose);
  out.origin = Eigen::Vector3d(first.x(), first.y(), first.z());
  for (const auto& d : o.sensedData) {
    const double z = d.sensedDistance;
    if (!std::isfinite(z) || !(z > 0.0) || !(z < o.maxSensorDistance)) {
      ++out.invalid;
      continue;
    }
    const CPose3D sensor = robotPose + CPose3D(d.sensorPose);
    double gx = 0, gy = 0, gz = 0;
    sensor.composePoint(z, 0.0, 0.0, gx, gy, gz);
    out.points.emplace_back(static_cast<float>(gx), static_cast<float>(gy), static_cast<float>(gz));
    out.is_hit.push_back(1);
    out.ranges.push_back(static_cast<float>(z));
  }
}

}  // namespace rtog::sonar
