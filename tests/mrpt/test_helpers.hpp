// Shared helpers of the MRPT map tests: real rawlogs from Debian's mrpt-common.
#pragma once

#include <string>
#include <vector>

#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>

namespace rtog_test {

inline std::string dataset(const std::string& name) { return std::string(RTOG_MRPT_DATASETS) + "/" + name; }
inline const std::string kSena = "2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";

struct PosedFrame {
  mrpt::poses::CPose3D pose;
  mrpt::obs::CSensoryFrame::Ptr sf;
};

/// Sensory frames of an action/observation rawlog with the odometry-integrated robot pose.
inline std::vector<PosedFrame> loadOdometryFrames(const std::string& file, std::size_t max_frames = 1u << 30) {
  mrpt::obs::CRawlog rl;
  if (!rl.loadFromRawLogFile(file)) throw std::runtime_error("cannot load " + file);
  std::vector<PosedFrame> out;
  mrpt::poses::CPose2D pose;
  for (std::size_t i = 0; i < rl.size() && out.size() < max_frames; ++i) {
    if (rl.getType(i) == mrpt::obs::CRawlog::etActionCollection) {
      auto acts = rl.getAsAction(i);
      mrpt::poses::CPose3D inc;
      if (acts->getFirstMovementEstimationMean(inc)) pose = pose + mrpt::poses::CPose2D(inc);
    } else if (rl.getType(i) == mrpt::obs::CRawlog::etSensoryFrame) {
      out.push_back({mrpt::poses::CPose3D(pose), rl.getAsObservations(i)});
    }
  }
  return out;
}

/// The first observation of an observation-only rawlog.
inline mrpt::obs::CObservation::Ptr firstObservation(const std::string& file) {
  mrpt::obs::CRawlog rl;
  if (!rl.loadFromRawLogFile(file)) throw std::runtime_error("cannot load " + file);
  for (std::size_t i = 0; i < rl.size(); ++i)
    if (rl.getType(i) == mrpt::obs::CRawlog::etObservation) return rl.getAsObservation(i);
  throw std::runtime_error("no observation in " + file);
}

}  // namespace rtog_test
