// Writes the seed corpora of the fuzz targets from the repository's real data, so that fuzzing
// starts from valid files and mutates them instead of discovering the formats byte by byte:
//   core_map/     .rtog files of one TUM depth frame (share/rtog/data), each merge policy
//   mrpt_archive/ CArchive streams (saveToFile's content without gzip) of both plugin classes
//                 after a few scans of Debian's SENA rawlog, in both update presets
// Usage: rtog_fuzz_seeds TUM_DIR SENA_RAWLOG OUT_DIR
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/serialization/CArchive.h>

#include "rtog/image/tum_dataset.hpp"
#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "rtog/mrpt/register_classes.h"

namespace fs = std::filesystem;

namespace {

void writeCore(const std::string& tum_dir, const fs::path& out) {
  fs::create_directories(out);
  const auto seq = rtog::image::readTumSequence(tum_dir);
  if (seq.frames.empty()) throw std::runtime_error("no frames in " + tum_dir);
  // A coarse stride and resolution keep the seeds a few kB: small inputs fuzz faster.
  const auto scan = rtog::image::loadDepthScan(seq.frames.front(), seq.intrinsics, 24);
  const rtog::MergePolicy merges[] = {rtog::MergePolicy::Off, rtog::MergePolicy::Clamped, rtog::MergePolicy::Equal};
  for (const auto merge : merges) {
    rtog::MapParams mp;
    mp.resolution = 0.2;
    mp.merge = merge;
    rtog::OccupancyMap map(mp);
    rtog::InsertParams ip;
    ip.max_range = 4.0;
    map.insertPointCloud(scan.origin, scan.points, ip);
    std::ofstream f(out / (std::string("tum_") + rtog::toString(merge) + ".rtog"), std::ios::binary);
    map.write(f);
  }
  std::ofstream empty(out / "empty.rtog", std::ios::binary);
  rtog::OccupancyMap().write(empty);
}

template <class Map>
void writeArchive(const Map& m, const fs::path& file) {
  mrpt::io::CFileOutputStream f(file.string());
  auto ar = mrpt::serialization::archiveFrom(f);
  ar << m;
}

void writeArchives(const std::string& rawlog, const fs::path& out) {
  fs::create_directories(out);
  mrpt::obs::CRawlog rl;
  if (!rl.loadFromRawLogFile(rawlog)) throw std::runtime_error("cannot load " + rawlog);
  for (const char* preset : {"mrpt_grid", "octomap"}) {
    rtog::CRTreeOccupancyGridMap::TInsertionOptions io;
    io.sensorModelPreset = preset;
    io.maxDistanceInsertion = 4.0f;
    rtog::CRTreeOccupancyGridMap map(0.25, io);
    rtog::CRTreeBackedGridMap2D grid(0.25);
    grid.rtreeMap() = rtog::CRTreeOccupancyGridMap(0.25, io);
    mrpt::poses::CPose2D pose;
    int frames = 0;
    for (std::size_t i = 0; i < rl.size() && frames < 3; ++i) {
      if (rl.getType(i) == mrpt::obs::CRawlog::etActionCollection) {
        mrpt::poses::CPose3D inc;
        if (rl.getAsAction(i)->getFirstMovementEstimationMean(inc)) pose = pose + mrpt::poses::CPose2D(inc);
      } else if (rl.getType(i) == mrpt::obs::CRawlog::etSensoryFrame) {
        const auto sf = rl.getAsObservations(i);
        sf->insertObservationsInto(map, mrpt::poses::CPose3D(pose));
        sf->insertObservationsInto(grid, mrpt::poses::CPose3D(pose));
        ++frames;
      }
    }
    writeArchive(map, out / (std::string("sena_") + preset + ".bin"));
    writeArchive(grid, out / (std::string("sena_grid2d_") + preset + ".bin"));
  }
  writeArchive(rtog::CRTreeOccupancyGridMap(0.1), out / "empty.bin");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s TUM_DIR SENA_RAWLOG OUT_DIR\n", argv[0]);
    return 2;
  }
  try {
    rtog::registerMrptClasses();
    writeCore(argv[1], fs::path(argv[3]) / "core_map");
    writeArchives(argv[2], fs::path(argv[3]) / "mrpt_archive");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rtog_fuzz_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
