// Registration of two maps before fusion: ICP on their occupied cells (map_registration.h).
#include "rtog/mrpt/map_registration.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/slam/CICP.h>

#include "rtog/core/pose_blur.hpp"

namespace rtog {

namespace {

/// The occupied cells' centres of `m` within the band, as 2D points, at most `cap` (taken evenly).
mrpt::maps::CSimplePointsMap bandPoints(const CRTreeOccupancyGridMap& m, const TMapRegistrationOptions& o,
                                        std::size_t cap) {
  std::vector<Eigen::Vector2f> pts;
  const Lattice& lat = m.map().lattice();
  const LogOddsModel& model = m.map().logOddsModel();
  m.map().forEachLeaf([&](const Box& b, float v) {
    if (model.classify(v) != CellState::Occupied) return;
    for (std::int32_t z = b.min.z; z <= b.max.z; ++z)
      for (std::int32_t y = b.min.y; y <= b.max.y; ++y)
        for (std::int32_t x = b.min.x; x <= b.max.x; ++x) {
          const Eigen::Vector3d c = lat.cellCenter(Key{x, y, z});
          if (c.z() >= o.minZ && c.z() <= o.maxZ) pts.emplace_back(static_cast<float>(c.x()), static_cast<float>(c.y()));
        }
  });
  mrpt::maps::CSimplePointsMap out;
  const std::size_t step = pts.size() > cap ? (pts.size() + cap - 1) / cap : 1;
  for (std::size_t i = 0; i < pts.size(); i += step) out.insertPoint(pts[i].x(), pts[i].y(), 0.0f);
  return out;
}

}  // namespace

TMapRegistration registerMaps(const CRTreeOccupancyGridMap& a, const CRTreeOccupancyGridMap& b,
                              const TMapRegistrationOptions& o) {
  if (!(o.minZ <= o.maxZ) || !(o.headingStepDeg > 0.0 && o.headingStepDeg <= 360.0) ||
      !(o.startDistance >= o.endDistance && o.endDistance > 0.0) || o.maxPoints < 10 ||
      !std::isfinite(o.guessX + o.guessY + o.guessYaw))
    throw std::invalid_argument(
        "rtog::registerMaps: need minZ <= maxZ, headingStepDeg in (0, 360], startDistance >= endDistance > 0, "
        "maxPoints >= 10 and a finite guess");
  const auto pa = bandPoints(a, o, o.maxPoints), pb = bandPoints(b, o, o.maxPoints);
  if (pa.size() < 10 || pb.size() < 10)
    throw std::runtime_error("rtog::registerMaps: each map needs 10 occupied cells in the band to be registered (" +
                             std::to_string(pa.size()) + " and " + std::to_string(pb.size()) + ")");
  mrpt::slam::CICP icp;
  icp.options.maxIterations = 200;
  icp.options.thresholdDist = o.startDistance;
  icp.options.thresholdAng = 0.0;
  icp.options.ALFA = 0.8;  // the distance shrinks slowly: a start a few metres off still converges
  icp.options.smallestThresholdDist = o.endDistance;
  icp.options.corresponding_points_decimation = 1;
  TMapRegistration best;
  best.goodness = -1.0;
  const int starts = static_cast<int>(std::ceil(360.0 / o.headingStepDeg));
  for (int i = 0; i < starts; ++i) {
    const double yaw = o.guessYaw + (i * o.headingStepDeg - 180.0) * M_PI / 180.0;
    mrpt::slam::CICP::TReturnInfo info;
    const auto pdf = icp.Align(&pa, &pb, mrpt::poses::CPose2D(o.guessX, o.guessY, yaw), info);
    if (!pdf || !(info.goodness > best.goodness)) continue;
    mrpt::poses::CPosePDFGaussian g;
    g.copyFrom(*pdf);
    best.goodness = info.goodness;
    best.pose = mrpt::poses::CPose3DPDFGaussian(g);
  }
  best.pointsA = pa.size(), best.pointsB = pb.size();
  return best;
}

InsertStats fuseUncertain(CRTreeOccupancyGridMap& into, const CRTreeOccupancyGridMap& other,
                          const mrpt::poses::CPose3DPDFGaussian& pose) {
  Eigen::MatrixXd cov(6, 6);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) cov(r, c) = pose.cov(r, c);
  const std::vector<SigmaPoint> sigma = sigmaPoints(cov);  // throws for a matrix that is not a covariance
  // As CPose3DPDFGaussian draws samples (and the pose-uncertainty insertion takes its sigma
  // points): offsets added to the mean's six parameters.
  const mrpt::poses::CPose3D& m = pose.mean;
  std::vector<OccupancyMap::WeightedPose> poses;
  for (const SigmaPoint& s : sigma) {
    const Eigen::VectorXd& d = s.offset;
    const mrpt::poses::CPose3D p(m.x() + d[0], m.y() + d[1], m.z() + d[2], m.yaw() + d[3], m.pitch() + d[4],
                                 m.roll() + d[5]);
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.matrix() = p.getHomogeneousMatrixVal<mrpt::math::CMatrixDouble44>().asEigen();
    poses.push_back({t, s.weight});
  }
  const int threads = into.insertionOptions.threads > 0 ? into.insertionOptions.threads : defaultThreadCount();
  const InsertStats st = into.map().fuse(other.map(), poses, threads);
  into.notifyMapChanged();
  return st;
}

}  // namespace rtog
