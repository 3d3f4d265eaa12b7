// libFuzzer target: insertion from structured input. The bytes are decoded (FuzzedDataProvider)
// into a resolution, insertion options, a robot pose and a few observations (2D scans, point
// clouds, rotating scans, depth images up to 16 x 16; a pose PDF with poseUncertainty) for CRTreeOccupancyGridMap /
// CRTreeBackedGridMap2D, or into an origin, points and InsertParams for the core OccupancyMap
// (plain or blurred over a few shifted poses). After every insertion the map must be sound;
// each observation is also scored, and a few queries run.
//
// Sizes are bounded (48 beams or points, ranges of 4 m) so that one input takes about a
// millisecond: a long ray or a big scan is no more interesting than a short one to the code under
// test, and grown inputs at twice these bounds ran at 450-600 per second. Values outside the bounds come in as special values (NaN,
// +-Inf, 0, negative, huge) instead, which is where input handling goes wrong.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <fuzzer/FuzzedDataProvider.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRotatingScan.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>

#include "rtog/core/occupancy_map.hpp"
#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "rtog/mrpt/register_classes.h"
#include "null_stderr.hpp"

namespace {

using rtog::CRTreeOccupancyGridMap;
using Fdp = FuzzedDataProvider;

constexpr double kMaxRange = 4.0;   // metres, in-bounds ranges and coordinates
constexpr std::size_t kMaxBeams = 48;
constexpr std::size_t kMaxPoints = 48;
// The range-noise model paints a band of cutoff * sigma about each end point: at 0.3 m + 5 %/m and
// 10 sigma a 4 m beam painted 9 m of cells in 3D, and those inputs (p99 of a grown corpus: 0.3 s) held
// the whole target near 130 inputs per second. A band of at most 0.7 m reaches the same code.
constexpr double kMaxNoiseStd = 0.1, kMaxNoisePerMeter = 0.02, kMaxNoiseCutoff = 4.0;
// A special sigma (1e9 m per metre) stretches a beam's band to the walk limit, 65,536 cells by
// default: bounded, but 22,000 cells a beam held inputs to a quarter of a second. The core path
// takes a limit a little above what in-bounds beams need (4.7 m at 0.05 m), so the limit itself is
// met often and cheaply; the plugin path keeps the default.
constexpr std::uint32_t kMaxRayCells = 128;

[[noreturn]] void fail(const std::string& why) {
  std::fprintf(stderr, "rtog_fuzz_insert: %s\n", why.c_str());
  std::abort();
}

/// Mostly a value in [lo, hi]; sometimes one of the values input handling must survive.
double value(Fdp& in, double lo, double hi) {
  if (in.ConsumeIntegralInRange<int>(0, 15) != 0) return in.ConsumeFloatingPointInRange<double>(lo, hi);
  constexpr double special[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                                -std::numeric_limits<double>::infinity(), 0.0, -1.0, 1e-30, 1e9, -1e9};
  return special[in.ConsumeIntegralInRange<int>(0, 7)];
}

mrpt::poses::CPose3D pose(Fdp& in, double extent) {
  const double x = value(in, -extent, extent), y = value(in, -extent, extent), z = value(in, -1.0, 1.0);
  const double yaw = value(in, -M_PI, M_PI);
  const bool level = in.ConsumeBool();  // most sensors are level: exercises the planar paths
  const double pitch = level ? 0.0 : value(in, -0.5, 0.5), roll = level ? 0.0 : value(in, -0.5, 0.5);
  return mrpt::poses::CPose3D(x, y, z, yaw, pitch, roll);
}

CRTreeOccupancyGridMap::TInsertionOptions insertionOptions(Fdp& in) {
  CRTreeOccupancyGridMap::TInsertionOptions io;
  io.sensorModelPreset = in.ConsumeBool() ? "mrpt_grid" : "octomap";
  const char* models[] = {"beam", "endpoint", "rangeNoise"};  // rangeNoise with mrpt_grid: refused
  io.sensorModel = models[in.ConsumeIntegralInRange<int>(0, 2)];
  io.rangeNoiseStd = static_cast<float>(value(in, 0.0, kMaxNoiseStd));
  io.rangeNoiseStdPerMeter = static_cast<float>(value(in, 0.0, kMaxNoisePerMeter));
  io.rangeNoiseCutoff = static_cast<float>(value(in, 0.5, kMaxNoiseCutoff));
  const char* merges[] = {"off", "clamped", "equal"};
  io.mergePolicy = merges[in.ConsumeIntegralInRange<int>(0, 2)];
  io.maxOccupancyUpdateCertainty = static_cast<float>(value(in, 0.5, 1.0));
  io.maxFreenessUpdateCertainty = static_cast<float>(value(in, 0.0, 1.0));
  io.maxFreenessInvalidRanges = static_cast<float>(value(in, 0.0, 1.0));
  io.considerInvalidRangesAsFreeSpace = in.ConsumeBool();
  io.clampingMin = static_cast<float>(value(in, 0.0, 0.5));
  io.clampingMax = static_cast<float>(value(in, 0.5, 1.0));
  io.occupiedThreshold = static_cast<float>(value(in, 0.0, 1.0));
  // Always a range limit: unlimited rays are a known slow path, not a new finding.
  io.maxDistanceInsertion = static_cast<float>(in.ConsumeFloatingPointInRange<double>(0.1, kMaxRange));
  io.decimation = in.ConsumeIntegralInRange<std::uint16_t>(0, 4);
  io.decimation_3d_range = in.ConsumeIntegralInRange<std::uint16_t>(0, 9);
  io.discretize = in.ConsumeBool();
  io.planarCache = in.ConsumeBool();
  io.useMapAltitude = in.ConsumeBool();
  io.mapAltitude = static_cast<float>(value(in, -1.0, 1.0));
  io.horizontalTolerance = static_cast<float>(value(in, 0.0, 0.2));
  io.threads = in.ConsumeIntegralInRange<int>(0, 7) == 0 ? 2 : 1;
  io.poseUncertainty = in.ConsumeBool();  // with mrpt_grid: refused
  if (in.ConsumeBool()) {
    io.rotatingScan_minElevation_deg = static_cast<float>(value(in, -30.0, 0.0));
    io.rotatingScan_maxElevation_deg = static_cast<float>(value(in, 0.0, 30.0));
  }
  return io;
}

float range(Fdp& in) { return static_cast<float>(value(in, 0.0, kMaxRange)); }

std::shared_ptr<mrpt::obs::CObservation> observation(Fdp& in) {
  switch (in.ConsumeIntegralInRange<int>(0, 3)) {
    case 0: {
      auto s = std::make_shared<mrpt::obs::CObservation2DRangeScan>();
      const std::size_t n = in.ConsumeIntegralInRange<std::size_t>(0, kMaxBeams);
      s->aperture = static_cast<float>(value(in, 0.01, 2 * M_PI));
      s->rightToLeft = in.ConsumeBool();
      s->maxRange = static_cast<float>(value(in, 0.5, kMaxRange));
      s->sensorPose = pose(in, 0.5);
      s->resizeScan(n);
      for (std::size_t i = 0; i < n; ++i) {
        s->setScanRange(i, range(in));
        s->setScanRangeValidity(i, in.ConsumeIntegralInRange<int>(0, 7) != 0);
      }
      return s;
    }
    case 1: {
      auto pc = std::make_shared<mrpt::obs::CObservationPointCloud>();
      auto pts = mrpt::maps::CSimplePointsMap::Create();
      const std::size_t n = in.ConsumeIntegralInRange<std::size_t>(0, kMaxPoints);
      for (std::size_t i = 0; i < n; ++i) {
        const float x = range(in) - 4.0f, y = range(in) - 4.0f, z = static_cast<float>(value(in, -2.0, 2.0));
        pts->insertPoint(x, y, z);
      }
      pc->pointcloud = pts;
      pc->sensorPose = pose(in, 0.5);
      return pc;
    }
    case 3: {
      // A depth (or range) camera: a small image, read through its camera model, decimated by
      // decimation_3d_range (sizes not a multiple of it, or not the model's, must be refused).
      auto d = std::make_shared<mrpt::obs::CObservation3DRangeScan>();
      const int rows = in.ConsumeIntegralInRange<int>(0, 16), cols = in.ConsumeIntegralInRange<int>(0, 16);
      d->hasRangeImage = in.ConsumeIntegralInRange<int>(0, 7) != 0;
      d->rangeImage.resize(rows, cols);
      for (int i = 0; i < rows; ++i)
        for (int j = 0; j < cols; ++j) d->rangeImage(i, j) = in.ConsumeIntegralInRange<std::uint16_t>(0, 8000);
      d->rangeUnits = static_cast<float>(value(in, 1e-4, 0.01));
      d->range_is_depth = in.ConsumeBool();
      const bool model_fits = in.ConsumeIntegralInRange<int>(0, 7) != 0;
      d->cameraParams.ncols = static_cast<uint32_t>(model_fits ? cols : in.ConsumeIntegralInRange<int>(0, 16));
      d->cameraParams.nrows = static_cast<uint32_t>(model_fits ? rows : in.ConsumeIntegralInRange<int>(0, 16));
      d->cameraParams.setIntrinsicParamsFromValues(value(in, 1.0, 50.0), value(in, 1.0, 50.0), value(in, -2.0, 18.0),
                                                   value(in, -2.0, 18.0));
      if (in.ConsumeBool()) {
        d->cameraParams.distortion = mrpt::img::DistortionModel::plumb_bob;
        for (int k = 0; k < 5; ++k) d->cameraParams.dist[static_cast<std::size_t>(k)] = value(in, -0.5, 0.5);
      }
      if (!d->hasRangeImage || in.ConsumeIntegralInRange<int>(0, 7) == 0) {
        // Only points (or both): the stored point cloud, in the sensor frame.
        d->hasPoints3D = true;
        const std::size_t n = in.ConsumeIntegralInRange<std::size_t>(0, kMaxPoints);
        for (std::size_t i = 0; i < n; ++i) {
          d->points3D_x.push_back(range(in));
          d->points3D_y.push_back(range(in) - 4.0f);
          d->points3D_z.push_back(static_cast<float>(value(in, -2.0, 2.0)));
        }
      }
      d->sensorPose = pose(in, 0.5);
      return d;
    }
    default: {
      auto r = std::make_shared<mrpt::obs::CObservationRotatingScan>();
      r->rowCount = in.ConsumeIntegralInRange<std::uint16_t>(0, 8);
      r->columnCount = in.ConsumeIntegralInRange<std::uint16_t>(0, 24);
      r->rangeImage.resize(r->rowCount, r->columnCount);
      r->rangeResolution = value(in, 0.001, 0.05);
      for (int i = 0; i < r->rowCount; ++i)
        for (int j = 0; j < r->columnCount; ++j) r->rangeImage(i, j) = in.ConsumeIntegralInRange<std::uint16_t>(0, 400);
      r->startAzimuth = value(in, -M_PI, M_PI);
      r->azimuthSpan = value(in, -2 * M_PI, 2 * M_PI);
      r->minRange = value(in, 0.0, 1.0);
      r->maxRange = value(in, 1.0, kMaxRange);
      const char* models[] = {"UNKNOWN_SCANNER", "VLP16", "HDL32"};
      r->lidarModel = models[in.ConsumeIntegralInRange<int>(0, 2)];
      r->sensorPose = pose(in, 0.5);
      return r;
    }
  }
}

void checkSound(const rtog::OccupancyMap& m) {
  if (const std::string why = m.checkInvariants(); !why.empty()) fail("map unsound after insertion: " + why);
}

void fuzzPlugin(Fdp& in) {
  const double res = in.ConsumeFloatingPointInRange<double>(0.05, 0.5);
  const auto io = insertionOptions(in);
  const bool backed = in.ConsumeIntegralInRange<int>(0, 3) == 0;
  std::unique_ptr<CRTreeOccupancyGridMap> plain;
  std::unique_ptr<rtog::CRTreeBackedGridMap2D> grid;
  try {
    if (backed) {
      grid = std::make_unique<rtog::CRTreeBackedGridMap2D>(res);
      grid->rtreeMap() = CRTreeOccupancyGridMap(res, io);
    } else {
      plain = std::make_unique<CRTreeOccupancyGridMap>(res, io);
    }
  } catch (const std::exception&) {
    return;  // invalid options are refused: fine
  }
  mrpt::maps::CMetricMap& m = backed ? static_cast<mrpt::maps::CMetricMap&>(*grid) : *plain;
  const CRTreeOccupancyGridMap& r = backed ? grid->rtreeMap() : *plain;
  auto& lo = const_cast<CRTreeOccupancyGridMap&>(r).likelihoodOptions;
  lo.likelihoodMethod = static_cast<CRTreeOccupancyGridMap::TLikelihoodMethod>(in.ConsumeIntegralInRange<int>(0, 6));
  lo.scanLikelihoodOnGridView = in.ConsumeBool();
  const int count = in.ConsumeIntegralInRange<int>(1, 3);
  for (int k = 0; k < count && in.remaining_bytes() > 0; ++k) {
    const auto obs = observation(in);
    const auto p = pose(in, 4.0);
    const bool uncertain = !backed && in.ConsumeBool();
    try {
      if (uncertain) {
        // A pose PDF: a diagonal covariance of fuzzed variances (bad ones must be refused).
        mrpt::poses::CPose3DPDFGaussian pdf(p);
        pdf.cov.setZero();
        for (int d = 0; d < 6; ++d) pdf.cov(d, d) = in.ConsumeBool() ? 0.0 : value(in, 0.0, 0.01);
        plain->insertObservation(*obs, pdf);
      } else {
        m.insertObservation(*obs, p);
      }
    } catch (const std::exception&) {
      // refused with a reason (e.g. a rotating scan of an unknown lidar, a covariance that is none)
    }
    checkSound(r.map());
    // Scoring must not crash on any input; its values are the likelihood tests' business.
    try {
      (void)m.computeObservationLikelihood(*obs, p);
    } catch (const std::exception&) {
    }
  }
  (void)r.castRay({0.01, 0.02, 0.03}, {1.0, 0.3, 0.0}, kMaxRange);
  (void)r.nearestObstacleDistance({0.01, 0.02, 0.03}, 1.0);
  (void)r.map().statistics();
}

void fuzzCore(Fdp& in) {
  rtog::MapParams mp;
  mp.resolution = in.ConsumeFloatingPointInRange<double>(0.05, 0.5);
  const rtog::MergePolicy merges[] = {rtog::MergePolicy::Off, rtog::MergePolicy::Clamped, rtog::MergePolicy::Equal};
  mp.merge = merges[in.ConsumeIntegralInRange<int>(0, 2)];
  rtog::InsertParams ip;
  const rtog::SensorModel models[] = {rtog::SensorModel::BeamBased, rtog::SensorModel::BeamEndPoint,
                                      rtog::SensorModel::RangeNoise};
  ip.model = models[in.ConsumeIntegralInRange<int>(0, 2)];
  ip.range_noise_std = value(in, 0.0, kMaxNoiseStd);
  ip.range_noise_std_per_meter = value(in, 0.0, kMaxNoisePerMeter);
  ip.range_noise_cutoff = value(in, 0.5, kMaxNoiseCutoff);
  ip.max_range = in.ConsumeFloatingPointInRange<double>(0.1, kMaxRange);
  ip.max_ray_cells = kMaxRayCells;
  ip.discretize = in.ConsumeBool();
  ip.planar_cache = in.ConsumeBool();
  rtog::OccupancyMap map(mp);
  const int scans = in.ConsumeIntegralInRange<int>(1, 3);
  for (int s = 0; s < scans && in.remaining_bytes() > 0; ++s) {
    const Eigen::Vector3d origin(value(in, -4, 4), value(in, -4, 4), value(in, -1, 1));
    const bool planar = in.ConsumeBool();
    const std::size_t n = in.ConsumeIntegralInRange<std::size_t>(0, kMaxPoints);
    std::vector<Eigen::Vector3f> pts;
    std::vector<std::uint8_t> hit;
    for (std::size_t i = 0; i < n; ++i) {
      const float x = static_cast<float>(value(in, -kMaxRange, kMaxRange));
      const float y = static_cast<float>(value(in, -kMaxRange, kMaxRange));
      const float z = planar ? static_cast<float>(origin.z()) : static_cast<float>(value(in, -2, 2));
      pts.emplace_back(x, y, z);
      hit.push_back(in.ConsumeIntegralInRange<int>(0, 7) != 0);
    }
    const std::uint8_t* hits = in.ConsumeBool() ? hit.data() : nullptr;
    try {
      if (in.ConsumeIntegralInRange<int>(0, 3) == 0) {
        // The scan from a few shifted poses, blurred (weights may be bad: refused).
        const int poses = in.ConsumeIntegralInRange<int>(1, 4);
        std::vector<std::vector<Eigen::Vector3f>> moved(static_cast<std::size_t>(poses));
        std::vector<rtog::WeightedScan> scans;
        for (int i = 0; i < poses; ++i) {
          const Eigen::Vector3f shift(static_cast<float>(value(in, -0.2, 0.2)), static_cast<float>(value(in, -0.2, 0.2)), 0.0f);
          for (const auto& p : pts) moved[static_cast<std::size_t>(i)].push_back(p + shift);
          scans.push_back(rtog::WeightedScan{value(in, 0.01, 1.0), origin + shift.cast<double>(),
                                             moved[static_cast<std::size_t>(i)].data(), pts.size(), hits});
        }
        map.insertBlurred(scans, ip);
      } else {
        map.insertPointCloud(origin, pts.data(), pts.size(), ip, hits);
      }
    } catch (const std::exception&) {
    }
    checkSound(map);
  }
  (void)map.castRay({0.01, 0.02, 0.03}, {1.0, 0.3, 0.0}, kMaxRange);
  (void)map.classCover();
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  rtog::registerMrptClasses();
  rtog_fuzz::discardStdErr();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Fdp in(data, size);
  if (in.ConsumeBool())
    fuzzPlugin(in);
  else
    fuzzCore(in);
  // The pool keeps insertion buffers for the next map: an input that leaves more allocations
  // than it found makes libFuzzer run a whole LeakSanitizer pass, which costs more than the input.
  rtog::OccupancyMap::releaseInsertBuffers();
  return 0;
}
