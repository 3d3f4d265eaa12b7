// The helper process of the first-scan rows: loads one observation, makes the map from an .ini
// section, inserts, measures and prints. Everything it does before insertObservation is not
// measured; everything after it (counting points) comes after the measurement.
#include <malloc.h>

#include <chrono>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include <CLI/CLI.hpp>

#include "rtog/app/option_checks.hpp"
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/COctoMap.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/maps/TMetricMapInitializer.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationVelodyneScan.h>
#include <mrpt/obs/CRawlog.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "first_scan.hpp"
#include "rtog/image/tum_dataset.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "rtog/mrpt/rawlog_poses.h"

namespace rtog::bench {
namespace {

using Clock = std::chrono::steady_clock;

struct Observation {
  mrpt::obs::CObservation::Ptr obs;
  mrpt::poses::CPose3D robot;  // identity unless the source gives a pose
};

Observation tumFirstFrame(const std::string& dir) {
  const image::DepthSequence seq = image::readTumSequence(dir);
  if (seq.frames.empty()) throw std::runtime_error(dir + ": no depth frames");
  return {tumDepthObservation(seq.frames.front(), seq.intrinsics), mrpt::poses::CPose3D()};
}

Observation rawlogFirst(const std::string& path, bool planar) {
  mrpt::obs::CRawlog log;
  if (!log.loadFromRawLogFile(path)) throw std::runtime_error("cannot read rawlog " + path);
  Observation found;
  if (planar) {
    forEachOdometryObservation(log, [&](const mrpt::obs::CObservation::Ptr& obs, const mrpt::poses::CPose3D& robot,
                                        std::size_t) {
      if (!found.obs && std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(obs)) found = {obs, robot};
    });
  } else {
    for (std::size_t i = 0; i < log.size() && !found.obs; ++i)
      if (log.getType(i) == mrpt::obs::CRawlog::etObservation) found.obs = log.getAsObservation(i);
  }
  if (!found.obs) throw std::runtime_error(path + ": no " + (planar ? "2D laser scan" : "observation"));
  return found;
}

/// The observation in a form every compared map type inserts, with the same points for each
/// (MRPT 2.5's COctoMap takes a 2D scan, a CObservationPointCloud, or a CObservation3DRangeScan
/// only with its points): a depth image unprojected into its points, which replace the image
/// (rtog would otherwise read the image, decimated by its decimation_3d_range); a Velodyne
/// scan's packets decoded into a point cloud in the sensor frame. Made before the measurement,
/// as a recording of points would have it.
mrpt::obs::CObservation::Ptr insertableByEveryMap(const mrpt::obs::CObservation::Ptr& obs) {
  if (auto depth = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(obs)) {
    if (!depth->hasPoints3D) depth->unprojectInto(*depth);
    depth->hasRangeImage = false;
    depth->rangeImage.resize(0, 0);
    return depth;
  }
  if (const auto velo = std::dynamic_pointer_cast<mrpt::obs::CObservationVelodyneScan>(obs)) {
    mrpt::obs::CObservationVelodyneScan decoded = *velo;
    if (decoded.point_cloud.size() == 0) decoded.generatePointCloud();
    auto points = mrpt::maps::CSimplePointsMap::Create();
    const auto& pc = decoded.point_cloud;
    points->reserve(pc.x.size());
    for (std::size_t i = 0; i < pc.x.size(); ++i) points->insertPointFast(pc.x[i], pc.y[i], pc.z[i]);
    auto cloud = mrpt::obs::CObservationPointCloud::Create();
    cloud->pointcloud = points;
    cloud->sensorPose = velo->sensorPose;
    cloud->timestamp = velo->timestamp;
    cloud->sensorLabel = velo->sensorLabel;
    return cloud;
  }
  return obs;
}

/// The .ini as MRPT's applications read it: one map of the type, default options but the
/// resolution (the same for every map type, so that they store the same cells).
std::string iniFor(const std::string& map_type, double resolution) {
  std::ostringstream ini;
  ini.precision(17);
  ini << "[map]\n" << map_type << "_count=1\n[map_" << map_type << "_00_creationOpts]\nresolution=" << resolution << "\n";
  return ini.str();
}

std::size_t mapBytes(const mrpt::maps::CMetricMap& m) {
  if (const auto* r = dynamic_cast<const CRTreeOccupancyGridMap*>(&m)) return r->map().memoryBytes();
  if (const auto* o = dynamic_cast<const mrpt::maps::COctoMap*>(&m)) return o->memoryUsage();
  if (const auto* g = dynamic_cast<const mrpt::maps::COccupancyGridMap2D*>(&m))
    return g->getRawMap().size() * sizeof(mrpt::maps::COccupancyGridMap2D::cellType);
  throw std::logic_error("first scan: no byte count for " + std::string(m.GetRuntimeClass()->className));
}

/// The points (or beams) of an observation in insertableByEveryMap's form.
std::size_t pointsOf(const mrpt::obs::CObservation& obs) {
  if (const auto* scan = dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(&obs)) return scan->getScanSize();
  if (const auto* pc = dynamic_cast<const mrpt::obs::CObservationPointCloud*>(&obs))
    return pc->pointcloud ? pc->pointcloud->size() : 0;
  if (const auto* depth = dynamic_cast<const mrpt::obs::CObservation3DRangeScan*>(&obs)) return depth->points3D_x.size();
  throw std::logic_error(std::string("first scan: no point count for ") + obs.GetRuntimeClass()->className);
}

double heapInUse(bool with_mmap) {
  const struct mallinfo2 mi = mallinfo2();
  return double(mi.uordblks) + (with_mmap ? double(mi.hblkhd) : 0.0);
}

}  // namespace

std::shared_ptr<mrpt::obs::CObservation3DRangeScan> tumDepthObservation(const image::DepthFrame& f,
                                                                        const image::DepthIntrinsics& k) {
  const cv::Mat depth = cv::imread(f.depth_path, cv::IMREAD_UNCHANGED);
  if (depth.empty() || depth.type() != CV_16UC1) throw std::runtime_error(f.depth_path + ": not a 16-bit depth image");
  auto o = mrpt::obs::CObservation3DRangeScan::Create();
  o->hasRangeImage = true;
  o->range_is_depth = true;
  o->rangeUnits = float(1.0 / k.depth_scale);
  o->rangeImage.resize(depth.rows, depth.cols);
  for (int r = 0; r < depth.rows; ++r)
    for (int c = 0; c < depth.cols; ++c) o->rangeImage(r, c) = depth.at<std::uint16_t>(r, c);
  o->cameraParams.ncols = static_cast<uint32_t>(depth.cols);
  o->cameraParams.nrows = static_cast<uint32_t>(depth.rows);
  o->cameraParams.setIntrinsicParamsFromValues(k.fx, k.fy, k.cx, k.cy);
  o->cameraParamsIntensity = o->cameraParams;
  // MRPT's range camera frame has x forward, y left, z up; TUM's optical frame x right, y down,
  // z forward: optical = R * mrpt.
  Eigen::Matrix3d R;
  R << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  const Eigen::Matrix3d rot = f.camera_to_world.linear() * R;
  const Eigen::Vector3d t = f.camera_to_world.translation();
  mrpt::math::CMatrixDouble44 H;
  H.setIdentity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) H(i, j) = rot(i, j);
    H(i, 3) = t[i];
  }
  o->sensorPose = mrpt::poses::CPose3D(H);
  return o;
}

int firstScanMain(int argc, char** argv, std::ostream& out, std::ostream& err) {
  CLI::App cli{"rtog-first-scan: one observation into a fresh MRPT map in this process (a helper of rtog-bench)"};
  std::string kind, path, map_type;
  double resolution = 0.05;
  bool as_recorded = false;
  cli.add_option("--kind", kind, "tum | rawlog3d | rawlog2d")->required()->check(CLI::IsMember({"tum", "rawlog3d", "rawlog2d"}));
  cli.add_option("--path", path, "TUM directory or rawlog")->required()->check(CLI::ExistingPath);
  cli.add_option("--map", map_type, "CMultiMetricMap .ini map name")
      ->required()
      ->check(CLI::IsMember({"rtreeOccupancyGrid", "octoMap", "occupancyGrid"}));
  cli.add_option("--resolution", resolution, "Cell size [m]")
      ->required()
      ->check(rtog::app::checks::number(rtog::app::checks::Sign::Positive, 1000));
  cli.add_flag("--as-recorded", as_recorded, "Insert the observation as recorded (default: as every map type takes it)");
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return cli.exit(e, out, err);
    err << "rtog-first-scan: " << e.what() << "\n";
    return 2;
  }
  try {
    Observation o = kind == "tum" ? tumFirstFrame(path) : rawlogFirst(path, kind == "rawlog2d");
    if (!as_recorded) o.obs = insertableByEveryMap(o.obs);
    FirstScanSample s;
    const mrpt::config::CConfigFileMemory cfg(iniFor(map_type, resolution));
    mrpt::maps::TSetOfMetricMapInitializers inits;
    inits.loadFromConfigFile(cfg, "map");
    mrpt::maps::CMultiMetricMap maps;
    const auto t0 = Clock::now();
    maps.setListOfMaps(inits);
    s.create_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    if (maps.maps.size() != 1) throw std::runtime_error("the .ini made " + std::to_string(maps.maps.size()) + " maps");
    mrpt::maps::CMetricMap& map = *maps.maps.front();

    const double heap0 = heapInUse(true), arena0 = heapInUse(false);
    const auto t1 = Clock::now();
    const bool inserted = map.insertObservation(*o.obs, o.robot);
    s.insert_seconds = std::chrono::duration<double>(Clock::now() - t1).count();
    s.heap_held_bytes = heapInUse(true) - heap0;
    s.heap_held_uordblks = heapInUse(false) - arena0;
    s.map_bytes = mapBytes(map);
    if (!inserted) {
      err << "rtog-first-scan: " << map.GetRuntimeClass()->className << " does not insert a "
          << o.obs->GetRuntimeClass()->className << "\n";
      return 2;
    }
    const std::string observation = o.obs->GetRuntimeClass()->className;
    s.points = pointsOf(*insertableByEveryMap(o.obs));  // (the map is done with the observation)
    out << nlohmann::json{{"observation", observation},
                          {"create_seconds", s.create_seconds},
                          {"insert_seconds", s.insert_seconds},
                          {"heap_held_bytes", s.heap_held_bytes},
                          {"heap_held_uordblks", s.heap_held_uordblks},
                          {"map_bytes", s.map_bytes},
                          {"points", s.points}}
               .dump()
        << "\n";
  } catch (const std::exception& e) {
    err << "rtog-first-scan: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace rtog::bench
