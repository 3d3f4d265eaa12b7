#include "methods.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <utility>

#include <mrpt/maps/COccupancyGridMap3D.h>
#include <mrpt/maps/COctoMap.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <octomap/OcTree.h>

#include <Eigen/Geometry>

#include "rtog/core/occupancy_map.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog::bench {
namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }


template <class Fn>
double timeQueries(const std::vector<Eigen::Vector3d>& pts, Fn&& fn) {
  std::size_t sink = 0;
  const auto t0 = Clock::now();
  for (const auto& p : pts) sink += fn(p);
  const double s = seconds(t0, Clock::now());
  if (sink == std::size_t(-1)) std::puts("");  // keeps the loop observable
  return pts.empty() ? 0.0 : s / double(pts.size()) * 1e9;
}

class RtogMethod : public Method {
 public:
  RtogMethod(std::string label, double res, MergePolicy merge, InsertParams ip)
      : label_(std::move(label)), ip_(ip) {
    params_.resolution = res;
    params_.merge = merge;
  }
  std::string name() const override { return label_; }
  double build(const Dataset& d) override {
    map_ = std::make_unique<OccupancyMap>(params_);
    const auto t0 = Clock::now();
    for (const Scan& s : d.scans) map_->insertPointCloud(s.origin, s.points, ip_);
    map_->flush();  // a no-op unless planar scans wait in the cache
    return seconds(t0, Clock::now());
  }
  std::size_t structureBytes() const override { return map_->memoryBytes(); }
  std::size_t leaves() const override { return map_->leafCount(); }
  double queryNs(const std::vector<Eigen::Vector3d>& pts) const override {
    return timeQueries(pts, [&](const Eigen::Vector3d& p) { return std::size_t(map_->stateAt(p)); });
  }
  std::size_t fileBytes() const override {
    std::ostringstream os;
    map_->write(os);
    return os.str().size();
  }
  const OccupancyMap* rtogMap() const override { return map_.get(); }

 private:
  std::string label_;
  MapParams params_;
  InsertParams ip_;
  std::unique_ptr<OccupancyMap> map_;
};

/// A scan taken from an uncertain pose, blurred into the map (doc/pose-uncertainty.md): a planar
/// pose covariance diag(sigma^2, sigma^2, sigma_yaw^2) about each scan's origin, its six sigma
/// poses as moves of the scan (timed: a user's adapter does the same), inserted blurred.
class RtogBlurredMethod : public Method {
 public:
  RtogBlurredMethod(std::string label, double res, InsertParams ip, double sigma, double sigma_yaw)
      : label_(std::move(label)), ip_(ip) {
    params_.resolution = res;
    params_.merge = MergePolicy::Equal;
    Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(3, 3);
    cov(0, 0) = cov(1, 1) = sigma * sigma;
    cov(2, 2) = sigma_yaw * sigma_yaw;
    sigma_ = sigmaPoints(cov);
  }
  std::string name() const override { return label_; }
  double build(const Dataset& d) override {
    map_ = std::make_unique<OccupancyMap>(params_);
    std::vector<PoseMove> moves(sigma_.size());
    const auto t0 = Clock::now();
    for (const Scan& s : d.scans) {
      for (std::size_t i = 0; i < sigma_.size(); ++i) {
        const Eigen::VectorXd& o = sigma_[i].offset;
        moves[i] = planarMove(sigma_[i].weight, s.origin, o[0], o[1], o[2]);
      }
      map_->insertBlurred(s.origin, s.points.data(), s.points.size(), moves.data(), moves.size(), ip_);
    }
    return seconds(t0, Clock::now());
  }
  std::size_t structureBytes() const override { return map_->memoryBytes(); }
  std::size_t leaves() const override { return map_->leafCount(); }
  double queryNs(const std::vector<Eigen::Vector3d>& pts) const override {
    return timeQueries(pts, [&](const Eigen::Vector3d& p) { return std::size_t(map_->stateAt(p)); });
  }
  const OccupancyMap* rtogMap() const override { return map_.get(); }

 private:
  std::string label_;
  MapParams params_;
  InsertParams ip_;
  std::vector<SigmaPoint> sigma_;
  std::unique_ptr<OccupancyMap> map_;
};

class OctomapMethod : public Method {
 public:
  OctomapMethod(double res, bool lazy, bool discretize, double max_range)
      : res_(res), lazy_(lazy), discretize_(discretize), max_range_(max_range) {}
  std::string name() const override {
    return std::string("OctoMap") + (lazy_ ? " lazy" : "") + (discretize_ ? " discretize" : "");
  }
  double build(const Dataset& d) override {
    tree_ = std::make_unique<octomap::OcTree>(res_);
    std::vector<octomap::Pointcloud> clouds(d.scans.size());
    for (std::size_t i = 0; i < d.scans.size(); ++i)
      for (const auto& q : d.scans[i].points) clouds[i].push_back(q.x(), q.y(), q.z());
    const auto t0 = Clock::now();
    for (std::size_t i = 0; i < d.scans.size(); ++i) {
      const auto& o = d.scans[i].origin;
      tree_->insertPointCloud(clouds[i], octomap::point3d(float(o.x()), float(o.y()), float(o.z())), max_range_, lazy_,
                              discretize_);
    }
    if (lazy_) tree_->updateInnerOccupancy();
    return seconds(t0, Clock::now());
  }
  std::size_t structureBytes() const override { return tree_->memoryUsage(); }
  std::size_t leaves() const override { return tree_->getNumLeafNodes(); }
  double queryNs(const std::vector<Eigen::Vector3d>& pts) const override {
    return timeQueries(pts, [&](const Eigen::Vector3d& p) {
      const auto* n = tree_->search(p.x(), p.y(), p.z());
      return n ? std::size_t(tree_->isNodeOccupied(n)) + 1 : 0;
    });
  }
  std::size_t fileBytes() const override {
    std::ostringstream os;
    tree_->write(os);  // .ot with full probabilities, like rtog's file (.bt keeps only classes)
    return os.str().size();
  }
  const octomap::OcTree* octree() const override { return tree_.get(); }

 private:
  double res_;
  bool lazy_, discretize_;
  double max_range_;
  std::unique_ptr<octomap::OcTree> tree_;
};

mrpt::maps::CSimplePointsMap toPointsMap(const Scan& s) {
  mrpt::maps::CSimplePointsMap pm;
  pm.reserve(s.points.size());
  for (const auto& q : s.points) pm.insertPointFast(q.x(), q.y(), q.z());
  return pm;
}

class MrptOctoMapMethod : public Method {
 public:
  explicit MrptOctoMapMethod(double res) : res_(res) {}
  std::string name() const override { return "MRPT COctoMap"; }
  double build(const Dataset& d) override {
    map_ = std::make_unique<mrpt::maps::COctoMap>(res_);
    std::vector<mrpt::maps::CSimplePointsMap> clouds;
    for (const Scan& s : d.scans) clouds.push_back(toPointsMap(s));
    const auto t0 = Clock::now();
    for (std::size_t i = 0; i < d.scans.size(); ++i) {
      const auto& o = d.scans[i].origin;
      map_->insertPointCloud(clouds[i], float(o.x()), float(o.y()), float(o.z()));
    }
    return seconds(t0, Clock::now());
  }
  std::size_t structureBytes() const override { return map_->memoryUsage(); }
  std::size_t leaves() const override { return 0; }  // not exposed by COctoMap (pimpl)
  double queryNs(const std::vector<Eigen::Vector3d>& pts) const override {
    return timeQueries(pts, [&](const Eigen::Vector3d& p) {
      double prob = 0;
      return std::size_t(map_->getPointOccupancy(float(p.x()), float(p.y()), float(p.z()), prob)) + (prob > 0.5);
    });
  }

 private:
  double res_;
  std::unique_ptr<mrpt::maps::COctoMap> map_;
};

/// Seconds inserting each scan's cloud into `map` (COccupancyGridMap3D's insertPointCloud, or
/// the MRPT map type's), the clouds made before.
template <class Grid>
double timeCloudInsertion(Grid& map, const Dataset& d) {
  std::vector<mrpt::maps::CSimplePointsMap> clouds;
  for (const Scan& s : d.scans) clouds.push_back(toPointsMap(s));
  const auto t0 = Clock::now();
  for (std::size_t i = 0; i < d.scans.size(); ++i) {
    const auto& o = d.scans[i].origin;
    map.insertPointCloud(mrpt::math::TPoint3D(o.x(), o.y(), o.z()), clouds[i]);
  }
  return seconds(t0, Clock::now());
}

/// The box a COccupancyGridMap3D of the data needs: every origin and point, a cell of margin.
std::pair<Eigen::Vector3d, Eigen::Vector3d> gridBox(const Dataset& d, double res) {
  Eigen::Vector3d lo = d.scans.front().origin, hi = lo;
  for (const Scan& s : d.scans) {
    lo = lo.cwiseMin(s.origin), hi = hi.cwiseMax(s.origin);
    for (const auto& q : s.points) lo = lo.cwiseMin(q.cast<double>()), hi = hi.cwiseMax(q.cast<double>());
  }
  lo.array() -= res, hi.array() += res;
  return {lo, hi};
}

class DenseGridMethod : public Method {
 public:
  explicit DenseGridMethod(double res) : res_(res) {}
  std::string name() const override { return "MRPT COccupancyGridMap3D (dense)"; }
  bool heavy() const override { return true; }
  double build(const Dataset& d) override {
    map_.reset();  // not two grids at once
    const auto [lo, hi] = gridBox(d, res_);
    map_ = std::make_unique<mrpt::maps::COccupancyGridMap3D>(mrpt::math::TPoint3D(lo.x(), lo.y(), lo.z()),
                                                             mrpt::math::TPoint3D(hi.x(), hi.y(), hi.z()), float(res_));
    map_->insertionOptions.maxDistanceInsertion = 1e6f;
    map_->insertionOptions.decimation = 1;
    cells_ = 1;
    for (int a = 0; a < 3; ++a) cells_ *= static_cast<std::size_t>(std::ceil((hi[a] - lo[a]) / res_));
    return timeCloudInsertion(*map_, d);
  }
  std::size_t structureBytes() const override {
    return cells_ * sizeof(mrpt::maps::COccupancyGridMap3D::voxelType);
  }
  std::size_t leaves() const override { return cells_; }
  double queryNs(const std::vector<Eigen::Vector3d>& pts) const override {
    return timeQueries(pts, [&](const Eigen::Vector3d& p) {
      return std::size_t(map_->getFreenessByPos(float(p.x()), float(p.y()), float(p.z())) > 0.5f);
    });
  }

 private:
  double res_;
  std::size_t cells_ = 0;
  std::unique_ptr<mrpt::maps::COccupancyGridMap3D> map_;
};

/// The MRPT map type with a 3D section of the dense grid's box: COccupancyGridMap3D's cells
/// (mrpt_grid preset, doc/mrpt_map.md), stored as cuboids; the same clouds by insertPointCloud.
class RtogGrid3DMethod : public Method {
 public:
  explicit RtogGrid3DMethod(double res) : res_(res) {}
  std::string name() const override { return "rtog mrpt_grid 3D section (COccupancyGridMap3D's cells)"; }
  double build(const Dataset& d) override {
    const auto [lo, hi] = gridBox(d, res_);
    map_ = std::make_unique<CRTreeOccupancyGridMap>(res_);
    map_->insertionOptions.decimation = 1;
    map_->setGridFrame3D(mrpt::math::TPoint3D(lo.x(), lo.y(), lo.z()), mrpt::math::TPoint3D(hi.x(), hi.y(), hi.z()),
                         float(res_));
    return timeCloudInsertion(*map_, d);
  }
  std::size_t structureBytes() const override { return map_->map().memoryBytes(); }
  std::size_t leaves() const override { return map_->map().leafCount(); }
  double queryNs(const std::vector<Eigen::Vector3d>& pts) const override {
    return timeQueries(pts, [&](const Eigen::Vector3d& p) { return std::size_t(map_->map().stateAt(p)); });
  }
  const OccupancyMap* rtogMap() const override { return &map_->map(); }

 private:
  double res_;
  std::unique_ptr<CRTreeOccupancyGridMap> map_;
};

/// Not a map of its own but a yardstick of the machine: two independent one-thread builds at
/// once, one on a second thread. Built turn by turn with the maps, its throughput over one
/// build's is what two vCPUs gave rtog's work at those moments, nothing shared (this VM has
/// spells in which two busy vCPUs each run slower than one). Not a bound: two maps fill twice
/// the cache that one map built on two threads does.
class RtogPairMethod : public Method {
 public:
  RtogPairMethod(double res, MergePolicy merge, InsertParams ip)
      : first_("first", res, merge, ip), second_("second", res, merge, ip) {}
  std::string name() const override { return "rtog beam, merge equal, two 1-thread builds at once"; }
  bool calibration() const override { return true; }
  double build(const Dataset& d) override {
    // Each build times its own insertion, not the freeing of its previous map.
    double second_seconds = 0;
    std::thread other([&] { second_seconds = second_.build(d); });
    const double first_seconds = first_.build(d);
    other.join();
    if (first_.leaves() != second_.leaves()) throw std::logic_error("two builds of the same scans differ");
    return std::max(first_seconds, second_seconds);
  }
  std::size_t structureBytes() const override { return 0; }
  std::size_t leaves() const override { return 0; }
  double queryNs(const std::vector<Eigen::Vector3d>&) const override { return 0; }

 private:
  RtogMethod first_, second_;
};

}  // namespace

std::vector<std::unique_ptr<Method>> methodsFor(const Dataset& d, double res, const Options& o) {
  std::vector<std::unique_ptr<Method>> m;
  InsertParams beam, endpoint, disc, disc2;
  beam.max_range = endpoint.max_range = disc.max_range = disc2.max_range = o.max_range;
  endpoint.model = SensorModel::BeamEndPoint;
  disc.discretize = disc2.discretize = true;
  beam.threads = endpoint.threads = disc.threads = 1;  // the one-thread rows, whatever the machine
  disc2.threads = 2;
  InsertParams beam2 = beam;
  beam2.threads = 2;
  InsertParams noise = beam;  // the range-noise model at a Kinect-like sigma (doc/range-noise.md)
  noise.model = SensorModel::RangeNoise;
  noise.range_noise_std = 0.02;
  noise.range_noise_std_per_meter = 0.01;
  m.push_back(std::make_unique<RtogMethod>("rtog beam, merge equal", res, MergePolicy::Equal, beam));
  m.push_back(std::make_unique<RtogMethod>("rtog beam, merge equal, 2 threads", res, MergePolicy::Equal, beam2));
  m.push_back(std::make_unique<RtogMethod>("rtog beam, merge off", res, MergePolicy::Off, beam));
  m.push_back(std::make_unique<RtogMethod>("rtog beam, merge clamped", res, MergePolicy::Clamped, beam));
  m.push_back(std::make_unique<RtogMethod>("rtog beam discretize, merge equal", res, MergePolicy::Equal, disc));
  m.push_back(std::make_unique<RtogMethod>("rtog beam discretize, merge equal, 2 threads", res, MergePolicy::Equal, disc2));
  m.push_back(std::make_unique<RtogMethod>("rtog end point, merge equal", res, MergePolicy::Equal, endpoint));
  m.push_back(std::make_unique<RtogMethod>("rtog range noise (sigma 0.02 m + 0.01 m/m), merge equal", res,
                                           MergePolicy::Equal, noise));
  m.push_back(std::make_unique<RtogBlurredMethod>("rtog beam, pose blur (sigma 0.05 m, 1 deg), merge equal", res,
                                                  beam, 0.05, 1.0 * M_PI / 180.0));
  m.push_back(std::make_unique<RtogBlurredMethod>(
      "rtog range noise (sigma 0.02 m + 0.01 m/m), pose blur (sigma 0.05 m, 1 deg), merge equal", res, noise, 0.05,
      1.0 * M_PI / 180.0));
  for (const bool lazy : {false, true})
    for (const bool discretize : {false, true})
      m.push_back(std::make_unique<OctomapMethod>(res, lazy, discretize, o.max_range));
  m.push_back(std::make_unique<MrptOctoMapMethod>(res));
  m.push_back(std::make_unique<DenseGridMethod>(res));
  m.push_back(std::make_unique<RtogGrid3DMethod>(res));
  m.push_back(std::make_unique<RtogPairMethod>(res, MergePolicy::Equal, beam));
  (void)d;
  m.erase(std::remove_if(m.begin(), m.end(), [&](const auto& method) { return !selected(o, method->name()); }),
          m.end());
  return m;
}

}  // namespace rtog::bench
