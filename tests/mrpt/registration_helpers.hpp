// Maps of parts of two real logs, built in frames moved by known offsets, for the registration
// tests (test_registration*.cpp).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/serialization/CArchive.h>

#include "rtog/mrpt/map_registration.h"
#include "test_helpers.hpp"

namespace rtog_test {

/// Frames of a simplemap with their poses' means (Malaga's are corrected poses).
inline std::vector<PosedFrame> simplemapFrames(const std::string& file) {
  mrpt::maps::CSimpleMap sm;
  mrpt::io::CFileGZInputStream f(file);
  auto ar = mrpt::serialization::archiveFrom(f);
  ar >> sm;
  std::vector<PosedFrame> out;
  for (const auto& pair : sm) out.push_back({pair.pose->getMeanVal(), pair.sf});
  return out;
}

/// The map (0.05 m, defaults) of frames [from, to) as seen from a frame whose pose in the log's is
/// `frame`: registered back, it must be found at `frame`.
inline rtog::CRTreeOccupancyGridMap::Ptr buildPart(const std::vector<PosedFrame>& frames, std::size_t from,
                                                   std::size_t to, const mrpt::poses::CPose3D& frame = {}) {
  auto m = mapFromIni("");
  const mrpt::poses::CPose3D inv = -frame;
  for (std::size_t i = from; i < to; ++i)
    for (const auto& obs : *frames[i].sf) m->insertObservation(*obs, inv + frames[i].pose);
  return m;
}

/// The error of a registration against the known offset: x, y [m], yaw [rad] (wrapped).
inline Eigen::Vector3d registrationError(const rtog::TMapRegistration& r, const mrpt::poses::CPose3D& truth) {
  const auto& m = r.pose.mean;
  return {m.x() - truth.x(), m.y() - truth.y(), std::remainder(m.yaw() - truth.yaw(), 2 * M_PI)};
}

/// The reported covariance of x, y and yaw.
inline Eigen::Matrix3d planarCov(const rtog::TMapRegistration& r) {
  Eigen::Matrix3d c;
  const int idx[3] = {0, 1, 3};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) c(i, j) = r.pose.cov(idx[i], idx[j]);
  return c;
}

/// The squared Mahalanobis distance of the error in the reported covariance. The "2-sigma
/// ellipsoid" of the tests is d^2 <= 8.02: the chi-square quantile in 3 degrees of freedom (x, y,
/// yaw) of 95.45 %, the share of a normal within 2 sigma in one.
inline double mahalanobis2(const rtog::TMapRegistration& r, const mrpt::poses::CPose3D& truth) {
  const Eigen::Vector3d e = registrationError(r, truth);
  return e.dot(planarCov(r).ldlt().solve(e));
}
constexpr double kTwoSigma3Dof = 8.02;

}  // namespace rtog_test
