// rtog::CRTreeOccupancyGridMap: versioned CSerializable and files.
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>

#include "rtog/image/slice.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "archive_read.hpp"
#include "cuboid_scene.hpp"
#include "mrpt_grid.hpp"
#include "mrpt_grid3d.hpp"
#include "stream_input.hpp"
#include "util/sink_buf.hpp"
#include "rtog/mrpt/register_classes.h"

namespace rtog {


// Version 0: genericMapParams, insertion and likelihood options, then the core map's own
// binary format (doc/format.md) as a length-prefixed byte block. Version 1 adds
// insertionOptions.planarCache after the rotating-scan elevations. Version 2 adds the update
// preset with the mrpt_grid options and the grid geometry (TGridFrame2D) (older maps were built
// with OctoMap's rule and load as the octomap preset), lets the elevations be NaN (unset: the
// lidar's calibration decides), numbers the likelihood method as COccupancyGridMap2D (0 was the
// likelihood field before) and adds the options of its methods, the 2D view's band and
// matchingOptions after the likelihood options. Version 3 adds the range-noise options
// (rangeNoiseStd, rangeNoiseStdPerMeter, rangeNoiseCutoff) after matchingOptions. Version 4 adds
// insertionOptions.poseUncertainty after them. Version 5 adds the 3D grid's geometry
// (TGridFrame3D: defined, then its extent and sizes if so) after that. Version 6 adds
// insertionOptions.rangeNoiseSharedBand after it (older maps load with sharing off, as built).
uint8_t CRTreeOccupancyGridMap::serializeGetVersion() const { return 6; }

void CRTreeOccupancyGridMap::serializeTo(mrpt::serialization::CArchive& out) const {
  out << genericMapParams;
  const auto& io = insertionOptions;
  out << io.sensorModel << io.maxOccupancyUpdateCertainty << io.maxFreenessUpdateCertainty << io.clampingMin
      << io.clampingMax << io.occupiedThreshold << io.maxDistanceInsertion << io.decimation << io.decimation_3d_range
      << io.mergePolicy << io.discretize << static_cast<int32_t>(io.threads) << io.rotatingScan_minElevation_deg
      << io.rotatingScan_maxElevation_deg << io.planarCache;
  out << io.sensorModelPreset << io.maxFreenessInvalidRanges << io.considerInvalidRangesAsFreeSpace
      << io.horizontalTolerance << io.useMapAltitude << io.mapAltitude << io.wideningBeamsWithDistance;
  out << frame_.x_min << frame_.x_max << frame_.y_min << frame_.y_max << frame_.resolution << frame_.size_x
      << frame_.size_y << frame_.has_layer << frame_.layer;
  const auto& lo = likelihoodOptions;
  out << static_cast<int32_t>(lo.likelihoodMethod) << lo.LF_stdHit << lo.LF_zHit << lo.LF_zRandom << lo.LF_maxRange
      << lo.LF_decimation << lo.LF_maxCorrsDistance << lo.LF_useSquareDist << lo.enableLikelihoodCache
      << lo.rayTracing_decimation << lo.rayTracing_stdHit;
  out << lo.LF_alternateAverageMethod << lo.MI_exponent << lo.MI_skip_rays << lo.MI_ratio_max_distance
      << lo.rayTracing_useDistanceFilter << lo.consensus_takeEachRange << lo.consensus_pow << lo.OWA_weights
      << lo.scanLikelihoodOnGridView << gridViewOptions.gridView_minZ << gridViewOptions.gridView_maxZ;
  out << matchingOptions.matching2D_minZ << matchingOptions.matching2D_maxZ;
  out << io.rangeNoiseStd << io.rangeNoiseStdPerMeter << io.rangeNoiseCutoff;
  out << io.poseUncertainty;
  out << frame3d_.defined;
  if (frame3d_.defined)
    out << frame3d_.x_min << frame3d_.y_min << frame3d_.z_min << frame3d_.resolution << frame3d_.size_x
        << frame3d_.size_y << frame3d_.size_z;
  out << static_cast<int32_t>(io.rangeNoiseSharedBand);
  // The map's bytes, preceded by their count, go straight into the archive (a copy in memory
  // would hold up to three times the map while an app saves it, when it holds the most).
  const std::uint64_t bytes = map_.writtenSize();
  out.WriteAs<uint64_t>(bytes);
  detail::SinkBuf sink([&out](const char* p, std::size_t n) { out.WriteBuffer(p, n); });
  std::ostream os(&sink);
  map_.write(os);
  os.flush();
  // The stream catches what the archive throws (a full disk) and fails: said here, not dropped.
  if (!os) throw std::runtime_error("rtog::CRTreeOccupancyGridMap: the archive refused the map's bytes");
  if (sink.bytes() != bytes)
    throw std::logic_error("rtog::CRTreeOccupancyGridMap: the map wrote " + std::to_string(sink.bytes()) +
                           " bytes, not the " + std::to_string(bytes) + " it said");
}

// Everything is read into locals, checked as an .ini's values are (the same validate()s), and
// only then assigned: a stream that fails leaves the map as it was. Lengths are checked before
// anything is allocated (archive_read.hpp).
void CRTreeOccupancyGridMap::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version) {
  constexpr const char* kWho = "rtog::CRTreeOccupancyGridMap";
  if (version > 6) MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
  mrpt::maps::TMapGenericParams generic;
  archive::readGenericParams(in, generic);
  TInsertionOptions io;
  io.sensorModel = archive::readString(in, archive::kMaxName, kWho, "sensorModel");
  int32_t threads = 1;
  in >> io.maxOccupancyUpdateCertainty >> io.maxFreenessUpdateCertainty >> io.clampingMin >> io.clampingMax >>
      io.occupiedThreshold >> io.maxDistanceInsertion >> io.decimation >> io.decimation_3d_range;
  io.mergePolicy = archive::readString(in, archive::kMaxName, kWho, "mergePolicy");
  in >> archive::Flag{io.discretize, "discretize"} >> threads >> io.rotatingScan_minElevation_deg >> io.rotatingScan_maxElevation_deg;
  io.threads = threads;
  // Before version 2 the elevations were always stored, -15/15 being the defaults that stood
  // for "no calibration known": unset, so that the calibration now decides.
  if (version < 2 && io.rotatingScan_minElevation_deg == -15.0f && io.rotatingScan_maxElevation_deg == 15.0f)
    io.rotatingScan_minElevation_deg = io.rotatingScan_maxElevation_deg = std::numeric_limits<float>::quiet_NaN();
  io.planarCache = true;
  if (version >= 1) in >> archive::Flag{io.planarCache, "planarCache"};
  TGridFrame2D frame;
  if (version >= 2) {
    io.sensorModelPreset = archive::readString(in, archive::kMaxName, kWho, "sensorModelPreset");
    in >> io.maxFreenessInvalidRanges >> archive::Flag{io.considerInvalidRangesAsFreeSpace, "considerInvalidRangesAsFreeSpace"} >> io.horizontalTolerance >>
        archive::Flag{io.useMapAltitude, "useMapAltitude"} >> io.mapAltitude >> archive::Flag{io.wideningBeamsWithDistance, "wideningBeamsWithDistance"};
    in >> frame.x_min >> frame.x_max >> frame.y_min >> frame.y_max >> frame.resolution >> frame.size_x >>
        frame.size_y >> archive::Flag{frame.has_layer, "has_layer"} >> frame.layer;
  } else {
    io.sensorModelPreset = "octomap";
  }
  TLikelihoodOptions lo;
  TGridViewOptions gv;
  int32_t method = 0;
  in >> method >> lo.LF_stdHit >> lo.LF_zHit >> lo.LF_zRandom >> lo.LF_maxRange >> lo.LF_decimation >>
      lo.LF_maxCorrsDistance >> archive::Flag{lo.LF_useSquareDist, "LF_useSquareDist"} >> archive::Flag{lo.enableLikelihoodCache, "enableLikelihoodCache"} >> lo.rayTracing_decimation >>
      lo.rayTracing_stdHit;
  if (version < 2) {  // 0/1: the likelihood field / ray tracing, as COccupancyGridMap3D
    if (method != 0 && method != 1) throw std::runtime_error(std::string(kWho) + ": corrupt stream (likelihood method)");
    method = method == 0 ? lmLikelihoodField_Thrun : lmRayTracing;  // the others stay defaults
  } else {
    in >> archive::Flag{lo.LF_alternateAverageMethod, "LF_alternateAverageMethod"} >> lo.MI_exponent >> lo.MI_skip_rays >> lo.MI_ratio_max_distance >>
        archive::Flag{lo.rayTracing_useDistanceFilter, "rayTracing_useDistanceFilter"} >> lo.consensus_takeEachRange >> lo.consensus_pow;
    lo.OWA_weights = archive::readFloats(in, archive::kMaxWeights, kWho, "OWA_weights");
    in >> archive::Flag{lo.scanLikelihoodOnGridView, "scanLikelihoodOnGridView"} >> gv.gridView_minZ >> gv.gridView_maxZ;
  }
  if (method < lmMeanInformation || method > lmConsensusOWA)
    throw std::runtime_error(std::string(kWho) + ": corrupt stream (likelihood method)");
  lo.likelihoodMethod = static_cast<TLikelihoodMethod>(method);
  TMatchingOptions mo;
  if (version >= 2) in >> mo.matching2D_minZ >> mo.matching2D_maxZ;
  if (version >= 3) in >> io.rangeNoiseStd >> io.rangeNoiseStdPerMeter >> io.rangeNoiseCutoff;
  if (version >= 4) in >> archive::Flag{io.poseUncertainty, "poseUncertainty"};
  TGridFrame3D frame3d;
  if (version >= 5) {
    in >> archive::Flag{frame3d.defined, "frame3d.defined"};
    if (frame3d.defined)
      in >> frame3d.x_min >> frame3d.y_min >> frame3d.z_min >> frame3d.resolution >> frame3d.size_x >>
          frame3d.size_y >> frame3d.size_z;
  }
  io.rangeNoiseSharedBand = version >= 6 ? in.ReadAs<int32_t>() : 0;
  try {
    io.validate();
    lo.validate();
    gv.validate();
    mo.validate();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string(kWho) + ": the stored options are invalid: " + e.what());
  }
  // Parsed as it arrives: the block's magic and counts are checked before the rest is read.
  const uint64_t n = in.ReadAs<uint64_t>();
  OccupancyMap map;
  archive::parseBlock(in, n, kWho, "map block", [&](std::istream& is) { map = OccupancyMap::read(is); });
  if (version >= 2) mrpt_grid::checkFrame(frame, map.resolution());
  if (frame3d.defined) mrpt_grid3d::checkFrame(frame3d, map.resolution());

  genericMapParams = generic;
  insertionOptions = io;
  likelihoodOptions = lo;
  gridViewOptions = gv;
  matchingOptions = mo;
  map_ = std::move(map);
  frame_ = frame;
  frame3d_ = frame3d;
  prior_.reset();  // a loaded map clears to empty, as the stock grid does
  lastInsertStats = totalInsertStats = InsertStats{};
  invalidRangesSkipped = 0;
  notifyMapChanged();
}

void CRTreeOccupancyGridMap::saveToFile(const std::string& file) const {
  mrpt::io::CFileGZOutputStream f;
  if (!f.open(file)) throw std::runtime_error("rtog::CRTreeOccupancyGridMap: cannot write '" + file + "'");
  auto ar = mrpt::serialization::archiveFrom(f);
  ar << *this;
}

std::shared_ptr<CRTreeOccupancyGridMap> CRTreeOccupancyGridMap::loadFromFile(const std::string& file) {
  const std::string who = "rtog::CRTreeOccupancyGridMap: '" + file + "': ";
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0) throw std::runtime_error(who + "cannot read (" + std::strerror(errno) + ")");
  if (S_ISDIR(st.st_mode)) throw std::runtime_error(who + "cannot read (it is a directory)");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(who + "cannot read (" + std::strerror(errno) + ")");
  try {
    return readMapStream(in);
  } catch (const std::exception& e) {
    throw std::runtime_error(who + e.what());
  }
}

std::shared_ptr<CRTreeOccupancyGridMap> CRTreeOccupancyGridMap::loadFromStream(std::istream& in) {
  return readMapStream(in);
}

// <prefix>.rtog (gzip CArchive), <prefix>.3Dscene (SceneViewer3D) and <prefix>_slice.png (the
// horizontal layer through the middle of the map's height range, as a picture to look at). One
// at a time: apps save when they hold the most (rbpf-slam, every particle's map).
void CRTreeOccupancyGridMap::saveMetricMapRepresentationToFile(const std::string& prefix) const {
  saveToFile(prefix + ".rtog");
  saveCuboidScene(*this, prefix + ".3Dscene");
  if (!isEmpty()) {
    const Box b = map_.keyBounds();
    const double z = (0.5 * (double(b.min.z) + double(b.max.z)) + 0.5) * map_.resolution();
    try {
      image::writeSlicePicture(map_, z, false, prefix + "_slice.png");
    } catch (const std::exception&) {
      // A slice too large for an image is not an error of the map file itself.
    }
  }
}

}  // namespace rtog
