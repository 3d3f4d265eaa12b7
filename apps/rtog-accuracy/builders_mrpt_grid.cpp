// rtog's MRPT map type in its default preset, mrpt_grid (doc/mrpt_map.md): the MRPT grids' int8
// steps on their own rasters, the estimator's graded models rounded onto them. Fed as an MRPT
// user feeds it: the planar scenarios' CObservation2DRangeScans in a 2D section, the LiDAR
// scenarios' point clouds in a 3D section (the region's box, as buildMrpt3D's grid), at the
// believed pose or, with pose blur, at its Gaussian.
#include <chrono>

#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>

#include "builders.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog::accuracy {
namespace {

using Clock = std::chrono::steady_clock;

mrpt::poses::CPose3DPDFGaussian gaussianOf(const mrpt::poses::CPose3D& mean, const Eigen::Matrix3d& cov) {
  // (dx, dy, dyaw) of the scenarios' pose error, in MRPT's (x, y, z, yaw, pitch, roll).
  mrpt::math::CMatrixDouble66 c;
  c.setZero();
  const int at[3] = {0, 1, 3};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) c(at[i], at[j]) = cov(i, j);
  return mrpt::poses::CPose3DPDFGaussian(mean, c);
}

}  // namespace

MapView buildRtogMrptGrid(const std::vector<sim::Scan>& scans, const std::vector<sim::Pose>& poses,
                          const sim::ScannerParams* planar, double res, double max_range, const sim::TruthGrid& region,
                          const RtogVariant& v, const Eigen::Matrix3d& pose_cov) {
  CRTreeOccupancyGridMap map(res);
  auto& io = map.insertionOptions;
  io.sensorModelPreset = "mrpt_grid";
  io.maxOccupancyUpdateCertainty = kMrptOcc;  // the same sensor model as MRPT's grids here
  io.maxFreenessUpdateCertainty = kMrptFree;
  io.maxFreenessInvalidRanges = kMrptFree;
  io.maxDistanceInsertion = static_cast<float>(max_range + 1.0);
  io.considerInvalidRangesAsFreeSpace = true;
  io.wideningBeamsWithDistance = false;
  io.decimation = 1;
  io.sensorModel = v.model == SensorModel::RangeNoise ? "rangeNoise" : "beam";
  io.rangeNoiseStd = static_cast<float>(v.range_sigma);
  io.rangeNoiseStdPerMeter = 0.0f;
  io.poseUncertainty = v.pose_blur;
  const Box& R = region.region();
  if (planar)
    map.setGridFrame(static_cast<float>(R.min.x * res), static_cast<float>((R.max.x + 1) * res),
                     static_cast<float>(R.min.y * res), static_cast<float>((R.max.y + 1) * res));
  else
    map.setGridFrame3D(mrpt::math::TPoint3D(R.min.x * res, R.min.y * res, R.min.z * res),
                       mrpt::math::TPoint3D((R.max.x + 1) * res, (R.max.y + 1) * res, (R.max.z + 1) * res),
                       static_cast<float>(res));
  const auto t0 = Clock::now();
  for (std::size_t s = 0; s < scans.size(); ++s) {
    const sim::Scan& scan = scans[s];
    const sim::Pose& p = poses[s];
    mrpt::obs::CObservation::Ptr obs;
    mrpt::poses::CPose3D at;
    if (planar) {
      obs = std::make_shared<mrpt::obs::CObservation2DRangeScan>(scanObservation(scan, *planar));
      at = mrpt::poses::CPose3D(p.position.x(), p.position.y(), p.position.z(), p.yaw, 0, 0);
    } else {
      // The cloud in the sensor's frame (level, turned by the pose's yaw), returns first and then
      // the no-return beams, as buildMrpt3D inserts them.
      at = mrpt::poses::CPose3D(scan.origin.x(), scan.origin.y(), scan.origin.z(), p.yaw, 0, 0);
      auto cloud = mrpt::obs::CObservationPointCloud::Create();
      auto pts = mrpt::maps::CSimplePointsMap::Create();
      for (const bool hits : {true, false})
        for (std::size_t i = 0; i < scan.points.size(); ++i)
          if ((scan.is_hit[i] != 0) == hits) {
            double x, y, z;
            at.inverseComposePoint(scan.points[i].x(), scan.points[i].y(), scan.points[i].z(), x, y, z);
            pts->insertPointFast(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
          }
      cloud->pointcloud = pts;
      obs = cloud;
    }
    if (v.pose_blur)
      map.insertObservation(*obs, gaussianOf(at, pose_cov));
    else
      map.insertObservation(*obs, at);
  }
  MapView out(v.name, region.size());
  out.insert_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  // Read as the grids are read (readMrpt): a cell at exactly 0.5 is unknown, whether or not it was
  // observed, so that the preset and MRPT's grids are scored on the same cells.
  readRtog(map.map(), region, out);
  for (std::size_t i = 0; i < out.p.size(); ++i)
    if (out.p[i] == 0.5f) out.state[i] = sim::Predicted::Unknown;
  return out;
}

}  // namespace rtog::accuracy
