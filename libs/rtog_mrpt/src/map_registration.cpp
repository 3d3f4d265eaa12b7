// Registration of two maps before fusion: ICP on their occupied cells (map_registration.h).
#include "rtog/mrpt/map_registration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/slam/CICP.h>

#include "registration_covariance.hpp"
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
      !(o.headingSpanDeg > 0.0 && o.headingSpanDeg <= 360.0) || !(o.endDistance >= 0.0) ||
      !(o.startDistance > 0.0 && o.startDistance >= o.endDistance) || o.maxPoints < 10 ||
      !(o.minGoodness >= 0.0 && o.minGoodness <= 1.0) ||
      !std::isfinite(o.guessX + o.guessY + o.guessYaw + o.startDistance))
    throw std::invalid_argument(
        "rtog::registerMaps: need minZ <= maxZ, headingStepDeg and headingSpanDeg in (0, 360], "
        "startDistance >= endDistance >= 0 (startDistance > 0), maxPoints >= 10, minGoodness in [0, 1] "
        "and a finite guess");
  const auto pa = bandPoints(a, o, o.maxPoints), pb = bandPoints(b, o, o.maxPoints);
  if (pa.size() < 10 || pb.size() < 10)
    throw std::runtime_error("rtog::registerMaps: each map needs 10 occupied cells in the band to be registered (" +
                             std::to_string(pa.size()) + " and " + std::to_string(pb.size()) + ")");
  const double res = std::max(a.resolution(), b.resolution());
  const double end = o.endDistance > 0.0 ? o.endDistance : 0.75 * res;
  mrpt::slam::CICP icp;
  icp.options.maxIterations = 200;
  icp.options.thresholdDist = std::max(o.startDistance, end);
  icp.options.thresholdAng = 0.0;
  icp.options.ALFA = 0.8;  // the distance shrinks slowly: a start a few metres off still converges
  icp.options.smallestThresholdDist = end;
  icp.options.corresponding_points_decimation = 1;
  icp.options.skip_cov_calculation = true;  // its covariance is not used (registration_covariance.cpp)
  TMapRegistration best;
  best.pointsA = pa.size(), best.pointsB = pb.size();
  // Each cell centre is its cell's points to within a uniform error of res^2 / 12 per axis.
  const double q = (a.resolution() * a.resolution() + b.resolution() * b.resolution()) / 12.0;
  // The covariance's pairs: a cell of the second map and the nearest of the first within 1.5
  // cells, the matched cell's 8-neighbourhood (at most sqrt(2) cells away): one wall placed a
  // cell differently by the two maps, a disagreement endDistance leaves out of the matching but
  // not out of the pose's uncertainty.
  const double wide = std::max(end, 1.5 * res);
  detail::RegistrationFit fit;
  mrpt::poses::CPose2D found;
  bool any = false;
  const int starts = std::max(1, static_cast<int>(std::ceil(o.headingSpanDeg / o.headingStepDeg - 1e-9)));
  for (int i = 0; i < starts; ++i) {
    const double yaw = o.guessYaw + (i * o.headingStepDeg - 0.5 * o.headingSpanDeg) * M_PI / 180.0;
    const auto pdf = icp.Align(&pa, &pb, mrpt::poses::CPose2D(o.guessX, o.guessY, yaw));
    if (!pdf) continue;
    mrpt::poses::CPose2D mean;
    pdf->getMean(mean);
    // The start that matches most cells within the final distance, judged by one rule for all.
    detail::RegistrationFit f = detail::registrationCovariance(pa, pb, mean, end, wide, q);
    if (any && !(f.goodness > fit.goodness)) continue;
    any = true;
    fit = f, found = mean;
  }
  best.goodness = fit.goodness, best.matched = fit.matched, best.pairs = fit.pairs, best.rmsResidual = fit.rms;
  mrpt::poses::CPosePDFGaussian g(found, mrpt::math::CMatrixDouble33(fit.cov));
  best.pose = mrpt::poses::CPose3DPDFGaussian(g);
  const auto fail = [&](const std::string& why) {
    best.converged = false;
    best.failure = why;
    return best;
  };
  char why[200];
  std::snprintf(why, sizeof why,
                "the maps share too little to be registered: at best %.1f %% of the second map's %zu occupied cells "
                "matched within %.3g m (minGoodness %.3g)",
                100.0 * fit.goodness, pb.size(), end, o.minGoodness);
  if (!any || fit.goodness < o.minGoodness) return fail(why);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(fit.cov);
  if (!fit.cov.allFinite() || !(eig.eigenvalues().minCoeff() > 0.0))
    return fail("the registration is degenerate: its covariance is not finite and positive definite (" +
                std::to_string(fit.pairs) + " cells paired)");
  best.converged = true;
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
