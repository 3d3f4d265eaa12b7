// The maps of the comparison: rtog (its sensor models, with and without pose blur), OctoMap
// and MRPT's dense grids, each read back cell by cell over the evaluation region.
#include "builders.hpp"

#include <chrono>
#include <cmath>
#include <functional>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/COccupancyGridMap3D.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose3D.h>
#include <octomap/octomap.h>

#include "rtog/core/occupancy_map.hpp"
#include "rtog/core/pose_blur.hpp"

namespace rtog::accuracy {

// ---- rtog ------------------------------------------------------------------------------

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

constexpr double kPi = 3.14159265358979323846;

}  // namespace

MapView buildRtog(const std::vector<sim::Scan>& scans, double res, double max_range, const sim::TruthGrid& region,
                  const RtogVariant& v, const Eigen::Matrix3d& pose_cov) {
  MapParams mp;
  mp.resolution = res;
  mp.log_odds = v.log_odds;
  OccupancyMap map(mp);
  InsertParams ip;
  ip.model = v.model;
  ip.range_noise_std = v.range_sigma;
  ip.max_range = max_range;
  // The sigma points of the pose error, each a (dx, dy, dyaw) to apply to the believed scan.
  const std::vector<SigmaPoint> sigma = v.pose_blur ? sigmaPoints(pose_cov) : std::vector<SigmaPoint>{};
  const auto t0 = Clock::now();
  std::vector<PoseMove> moves;
  for (const auto& s : scans) {
    if (!v.pose_blur) {
      map.insertPointCloud(s.origin, s.points.data(), s.points.size(), ip, s.is_hit.data());
      continue;
    }
    moves.clear();
    for (const SigmaPoint& sp : sigma) moves.push_back(planarMove(sp.weight, s.origin, sp.offset[0], sp.offset[1], sp.offset[2]));
    map.insertBlurred(s.origin, s.points.data(), s.points.size(), moves.data(), moves.size(), ip, s.is_hit.data());
  }
  MapView out(v.name, region.size());
  out.insert_seconds = secondsSince(t0);
  readRtog(map, region, out);
  return out;
}

void readRtog(const OccupancyMap& map, const sim::TruthGrid& region, MapView& out) {
  const Box& R = region.region();
  const LogOddsModel& model = map.logOddsModel();
  map.forEachLeaf([&](const Box& b, float value) {
    const Box c = b.intersection(R);
    out.outside += static_cast<std::size_t>(b.volume() - (c.isEmpty() ? 0 : c.volume()));
    if (c.isEmpty()) return;
    const float prob = static_cast<float>(probability(value));
    const sim::Predicted st =
        model.classify(value) == CellState::Occupied ? sim::Predicted::Occupied : sim::Predicted::Free;
    forEachCell(c, [&](const Key& k) {
      const std::size_t i = region.index(k);
      out.p[i] = prob;
      out.state[i] = st;
    });
  });
}

// ---- OctoMap ----------------------------------------------------------------------------

MapView buildOctomap(const std::vector<sim::Scan>& scans, double res, double max_range, const sim::TruthGrid& region) {
  octomap::OcTree tree(res);  // OctoMap's defaults: hit 0.7, miss 0.4, clamp 0.1192/0.971
  const auto t0 = Clock::now();
  for (const auto& s : scans) {
    octomap::Pointcloud pc;
    pc.reserve(s.points.size());
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      Eigen::Vector3f p = s.points[i];
      if (!s.is_hit[i]) {  // no return: place it beyond max_range so OctoMap only clears up to it
        const Eigen::Vector3f o = s.origin.cast<float>();
        p = o + (p - o).normalized() * static_cast<float>(max_range + 1.0);
      }
      pc.push_back(p.x(), p.y(), p.z());
    }
    tree.insertPointCloud(pc, octomap::point3d(static_cast<float>(s.origin.x()), static_cast<float>(s.origin.y()),
                                               static_cast<float>(s.origin.z())),
                          max_range);
  }
  MapView v("octomap", region.size());
  v.insert_seconds = secondsSince(t0);
  const Box& R = region.region();
  const int depth = static_cast<int>(tree.getTreeDepth());
  const std::int32_t off = std::int32_t{1} << (depth - 1);  // OctoMap key of cell 0 (32768)
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const octomap::OcTreeKey k0 = it.getIndexKey();
    const std::int32_t n = 1 << (depth - static_cast<int>(it.getDepth()));
    const Key lo{static_cast<std::int32_t>(k0[0]) - off, static_cast<std::int32_t>(k0[1]) - off,
                 static_cast<std::int32_t>(k0[2]) - off};
    const Box b{lo, Key{lo.x + n - 1, lo.y + n - 1, lo.z + n - 1}};
    const Box c = b.intersection(R);
    v.outside += static_cast<std::size_t>(b.volume() - (c.isEmpty() ? 0 : c.volume()));
    if (c.isEmpty()) continue;
    const float prob = static_cast<float>(it->getOccupancy());
    const sim::Predicted st = tree.isNodeOccupied(*it) ? sim::Predicted::Occupied : sim::Predicted::Free;
    forEachCell(c, [&](const Key& k) {
      const std::size_t i = region.index(k);
      v.p[i] = prob;
      v.state[i] = st;
    });
  }
  return v;
}

// ---- MRPT --------------------------------------------------------------------------------

namespace {

void readMrpt(MapView& v, const sim::TruthGrid& region, double res, const std::function<float(double, double, double)>& freeness) {
  for (std::size_t i = 0; i < region.size(); ++i) {
    const Key k = region.key(i);
    const float f = freeness((k.x + 0.5) * res, (k.y + 0.5) * res, (k.z + 0.5) * res);
    if (f == 0.5f) continue;  // log-odds 0: never observed (or observed to exactly the prior)
    v.p[i] = 1.0f - f;
    v.state[i] = f < 0.5f ? sim::Predicted::Occupied : sim::Predicted::Free;
  }
}

}  // namespace

mrpt::obs::CObservation2DRangeScan scanObservation(const sim::Scan& scan, const sim::ScannerParams& sp) {
  const int n = sp.beams();
  mrpt::obs::CObservation2DRangeScan obs;
  obs.aperture = static_cast<float>(sp.fov_deg * kPi / 180.0);
  obs.rightToLeft = true;
  obs.maxRange = static_cast<float>(sp.max_range);
  obs.sensorPose = mrpt::poses::CPose3D(0, 0, sp.height, 0, 0, 0);
  obs.resizeScan(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    obs.setScanRange(static_cast<std::size_t>(i), scan.range[static_cast<std::size_t>(i)]);
    obs.setScanRangeValidity(static_cast<std::size_t>(i), scan.is_hit[static_cast<std::size_t>(i)] != 0);
  }
  return obs;
}

MapView buildMrpt3D(const std::vector<sim::Scan>& scans, double res, double max_range, const sim::TruthGrid& region) {
  const Box& R = region.region();
  mrpt::maps::COccupancyGridMap3D grid(mrpt::math::TPoint3D(R.min.x * res, R.min.y * res, R.min.z * res),
                                       mrpt::math::TPoint3D((R.max.x + 1) * res, (R.max.y + 1) * res, (R.max.z + 1) * res),
                                       static_cast<float>(res));
  grid.insertionOptions.maxOccupancyUpdateCertainty = kMrptOcc;
  grid.insertionOptions.maxFreenessUpdateCertainty = kMrptFree;
  grid.insertionOptions.maxDistanceInsertion = static_cast<float>(max_range + 1.0);
  grid.insertionOptions.decimation = 1;
  const auto t0 = Clock::now();
  for (const auto& s : scans) {
    mrpt::maps::CSimplePointsMap pts;
    pts.reserve(s.points.size());
    const mrpt::math::TPoint3D o(s.origin.x(), s.origin.y(), s.origin.z());
    for (std::size_t i = 0; i < s.points.size(); ++i)
      if (s.is_hit[i]) pts.insertPointFast(s.points[i].x(), s.points[i].y(), s.points[i].z());
    grid.insertPointCloud(o, pts);
    for (std::size_t i = 0; i < s.points.size(); ++i)
      if (!s.is_hit[i])
        grid.insertRay(o, mrpt::math::TPoint3D(s.points[i].x(), s.points[i].y(), s.points[i].z()), false);
  }
  MapView v("mrpt_grid3d", region.size());
  v.insert_seconds = secondsSince(t0);
  readMrpt(v, region, res, [&](double x, double y, double z) {
    return grid.getFreenessByPos(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  });
  return v;
}

MapView buildMrpt2D(const std::vector<sim::Scan>& scans, const std::vector<sim::Pose>& poses,
                    const sim::ScannerParams& sp, double res, const sim::TruthGrid& region) {
  const Box& R = region.region();
  mrpt::maps::COccupancyGridMap2D grid(static_cast<float>(R.min.x * res), static_cast<float>((R.max.x + 1) * res),
                                       static_cast<float>(R.min.y * res), static_cast<float>((R.max.y + 1) * res),
                                       static_cast<float>(res));
  grid.insertionOptions.maxOccupancyUpdateCertainty = kMrptOcc;
  grid.insertionOptions.maxFreenessUpdateCertainty = kMrptFree;
  grid.insertionOptions.maxFreenessInvalidRanges = kMrptFree;
  grid.insertionOptions.maxDistanceInsertion = static_cast<float>(sp.max_range + 1.0);
  grid.insertionOptions.considerInvalidRangesAsFreeSpace = true;
  grid.insertionOptions.wideningBeamsWithDistance = false;
  const auto t0 = Clock::now();
  for (std::size_t s = 0; s < scans.size(); ++s) {
    const sim::Pose& p = poses[s];
    grid.insertObservation(scanObservation(scans[s], sp),
                           mrpt::poses::CPose3D(p.position.x(), p.position.y(), p.position.z(), p.yaw, 0, 0));
  }
  MapView v("mrpt_grid2d", region.size());
  v.insert_seconds = secondsSince(t0);
  readMrpt(v, region, res, [&](double x, double y, double) {
    return grid.getPos(static_cast<float>(x), static_cast<float>(y));
  });
  return v;
}

}  // namespace rtog::accuracy
