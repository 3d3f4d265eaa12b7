// Decoding a CObservationRotatingScan's range image into sensor-frame points.
#include "rotating_scan.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>
#include <string>

#include <mrpt/obs/CObservationRotatingScan.h>
#include <mrpt/obs/VelodyneCalibration.h>

namespace rtog::detail {

namespace {

// A Velodyne model fromVelodyne() can have written: MRPT's name of its default calibration and
// when, within one column (firing sequence), each laser fires, as a fraction of the column
// (Velodyne's firing timing: VLP-16 2.304 us per laser of a 55.296 us sequence, HDL-32E 1.152 us
// of 46.08 us; HDL-64 banks fire together). The azimuth keeps turning while a column fires.
struct VelodyneModel {
  const char* calibrationName;
  std::size_t lasers;
  double laserFraction;
};

bool velodyneModel(const std::string& lidarModel, VelodyneModel& out) {
  std::string n;
  for (char ch : lidarModel)
    if (std::isalnum(static_cast<unsigned char>(ch))) n += static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  if (n.rfind("VLP16", 0) == 0) out = {"VLP16", 16, 2.304 / 55.296};
  else if (n.rfind("HDL32", 0) == 0) out = {"HDL32", 32, 1.152 / 46.08};
  else if (n.rfind("HDL64", 0) == 0) out = {"HDL64", 64, 0.0};
  else return false;
  return true;
}

[[noreturn]] void refuse(const mrpt::obs::CObservationRotatingScan& rot, const std::string& why) {
  throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: cannot decode the CObservationRotatingScan (lidarModel '" +
                              rot.lidarModel + "', " + std::to_string(rot.rowCount) + " rows): " + why +
                              "; set insertOpts rotatingScan_minElevation_deg/rotatingScan_maxElevation_deg to "
                              "give evenly spaced rings explicitly");
}

bool validRange(const mrpt::obs::CObservationRotatingScan& rot, std::uint16_t raw, double& range) {
  range = raw * rot.rangeResolution;
  return raw != 0 && range >= rot.minRange && range <= rot.maxRange;
}

}  // namespace

void decodeRotatingScan(const mrpt::obs::CObservationRotatingScan& rot, std::size_t decimation,
                        float minElevation_deg, float maxElevation_deg, std::vector<Eigen::Vector3f>& pts,
                        std::size_t& invalid) {
  const std::size_t rows = static_cast<std::size_t>(rot.rangeImage.rows());
  const std::size_t cols = static_cast<std::size_t>(rot.rangeImage.cols());
  const std::size_t dec = std::max<std::size_t>(decimation, 1);
  if (rows == 0 || cols == 0) return;
  const bool explicitRings = std::isfinite(minElevation_deg) && std::isfinite(maxElevation_deg);
  const auto overrideElevation = [&](std::size_t r) {
    const double e0 = minElevation_deg * M_PI / 180.0, e1 = maxElevation_deg * M_PI / 180.0;
    return rows > 1 ? e0 + (e1 - e0) * double(r) / double(rows - 1) : e0;
  };

  VelodyneModel model{};
  if (velodyneModel(rot.lidarModel, model)) {
    // fromVelodyne's layout: row = laser ID, column = firing sequence, columnCount/rowCount of
    // them (half that in dual-return mode), spread over azimuthSpan.
    if (rows != model.lasers) refuse(rot, "a " + rot.lidarModel + " has " + std::to_string(model.lasers) + " lasers");
    const bool dual = rot.rangeOtherLayers.count("STRONGEST") != 0;
    const std::size_t filled = std::min(cols, cols / rows / (dual ? 2 : 1));
    if (filled == 0) return;
    const mrpt::obs::VelodyneCalibration* calib = nullptr;
    if (!explicitRings) {
      calib = &mrpt::obs::VelodyneCalibration::LoadDefaultCalibration(model.calibrationName);
      if (calib->laser_corrections.size() != rows)
        refuse(rot, std::string("MRPT's default calibration '") + model.calibrationName + "' could not be loaded");
    }
    const double step = rot.azimuthSpan / double(filled);
    for (std::size_t r = 0; r < rows; ++r) {
      double cosV, sinV, horz = 0.0, vert = 0.0;
      if (calib) {
        const auto& lc = calib->laser_corrections[r];
        cosV = lc.cosVertCorrection, sinV = lc.sinVertCorrection;
        horz = lc.horizontalOffsetCorrection, vert = lc.verticalOffsetCorrection;
      } else {
        cosV = std::cos(overrideElevation(r)), sinV = std::sin(overrideElevation(r));
      }
      const double laserOffset = model.laserFraction * double(r);
      for (std::size_t c = 0; c < filled; c += dec) {
        double d;
        if (!validRange(rot, rot.rangeImage(r, c), d)) {
          ++invalid;
          continue;
        }
        // The Velodyne azimuth a turns clockwise: MRPT +x = cos a, +y = -sin a (as generatePointCloud).
        const double a = rot.startAzimuth + step * (double(c) + laserOffset);
        const double ca = std::cos(a), sa = std::sin(a);
        const double xy = d * cosV + vert * sinV;
        pts.emplace_back(static_cast<float>(xy * ca + horz * sa), static_cast<float>(-(xy * sa - horz * ca)),
                         static_cast<float>(d * sinV + vert));
      }
    }
    return;
  }

  // The documented layout: columns evenly over azimuthSpan (counter-clockwise positive).
  if (rows > 1 && !explicitRings)
    refuse(rot, "the observation carries no ring calibration and MRPT has none for this model");
  for (std::size_t r = 0; r < rows; ++r) {
    const double el = explicitRings ? overrideElevation(r) : 0.0;
    const double ce = std::cos(el), se = std::sin(el);
    for (std::size_t c = 0; c < cols; c += dec) {
      double d;
      if (!validRange(rot, rot.rangeImage(r, c), d)) {
        ++invalid;
        continue;
      }
      const double az = rot.startAzimuth + (cols > 1 ? rot.azimuthSpan * double(c) / double(cols - 1) : 0.0);
      pts.emplace_back(static_cast<float>(d * ce * std::cos(az)), static_cast<float>(d * ce * std::sin(az)),
                       static_cast<float>(d * se));
    }
  }
}

}  // namespace rtog::detail
