// rtog::CRTreeBackedGridMap2D: versioned CSerializable.
#include <cstring>
#include <stdexcept>

#include <mrpt/serialization/CArchive.h>

#include "archive_read.hpp"
#include "mrpt_grid.hpp"
#include "options_check.hpp"
#include "rtog/mrpt/CRTreeBackedGridMap2D.h"

namespace rtog {

// Version 0: the COccupancyGridMap2D part (grid and its options), the R-tree map, the band.
uint8_t CRTreeBackedGridMap2D::serializeGetVersion() const { return 0; }

void CRTreeBackedGridMap2D::serializeTo(mrpt::serialization::CArchive& out) const {
  COccupancyGridMap2D::serializeTo(out);
  out << rtree_ << gridView_minZ << gridView_maxZ;
}

// The COccupancyGridMap2D part is read here as MRPT 2.5's COccupancyGridMap2D::serializeFrom()
// reads the version serializeTo() writes (6), field for field, but not as it allocates: MRPT
// sizes the grid from the stored extent and zero-fills it before reading a cell, so a flipped
// exponent bit asked for terabytes. Here the size must match the extent and stay within
// archive::kMaxGridCells, the cells are read as they arrive, and everything is assigned only
// once the whole stream was read and checked (the map is unchanged by a stream that fails).
void CRTreeBackedGridMap2D::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version) {
  constexpr const char* kWho = "rtog::CRTreeBackedGridMap2D";
  if (version != 0) MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
  const auto corrupt = [&](const std::string& why) {
    return std::runtime_error(std::string(kWho) + ": corrupt stream (" + why + ")");
  };
  uint8_t bits = 0;
  in >> bits;
  if (bits != 8) throw corrupt("grid cells of " + std::to_string(bits) + " bits, this MRPT stores 8");
  uint32_t size_x = 0, size_y = 0;
  float x_min, x_max, y_min, y_max, res;
  in >> size_x >> size_y >> x_min >> x_max >> y_min >> y_max >> res;
  TGridFrame2D f;
  try {
    mrpt_grid::setSize(f, x_min, x_max, y_min, y_max, res);  // the geometry MRPT's setSize() makes of it
  } catch (const std::invalid_argument& e) {
    throw corrupt(std::string("grid geometry: ") + e.what());
  }
  if (f.size_x != size_x || f.size_y != size_y)
    throw corrupt("a grid of " + std::to_string(size_x) + " x " + std::to_string(size_y) +
                  " cells does not match its extent");
  std::string cells;
  archive::readBytes(in, std::uint64_t{size_x} * size_y, cells, kWho, "grid cells");

  TInsertionOptions io = insertionOptions;  // as MRPT: the fields the stream lacks stay
  TLikelihoodOptions lo = likelihoodOptions;
  in >> io.mapAltitude >> archive::Flag{io.useMapAltitude, "useMapAltitude"} >> io.maxDistanceInsertion >> io.maxOccupancyUpdateCertainty >>
      archive::Flag{io.considerInvalidRangesAsFreeSpace, "considerInvalidRangesAsFreeSpace"} >> io.decimation >> io.horizontalTolerance;
  int32_t method = 0;
  in >> method >> lo.LF_stdHit >> lo.LF_zHit >> lo.LF_zRandom >> lo.LF_maxRange >> lo.LF_decimation >>
      lo.LF_maxCorrsDistance >> archive::Flag{lo.LF_alternateAverageMethod, "LF_alternateAverageMethod"} >> lo.MI_exponent >> lo.MI_skip_rays >>
      lo.MI_ratio_max_distance >> archive::Flag{lo.rayTracing_useDistanceFilter, "rayTracing_useDistanceFilter"} >> lo.rayTracing_decimation >>
      lo.rayTracing_stdHit >> lo.consensus_takeEachRange >> lo.consensus_pow;
  lo.OWA_weights = archive::readFloats(in, archive::kMaxWeights, kWho, "OWA_weights");
  in >> archive::Flag{lo.enableLikelihoodCache, "enableLikelihoodCache"};
  lo.likelihoodMethod = static_cast<TLikelihoodMethod>(method);
  mrpt::maps::TMapGenericParams generic;
  archive::readGenericParams(in, generic);
  in >> io.CFD_features_gaussian_size >> io.CFD_features_median_size >> archive::Flag{io.wideningBeamsWithDistance, "wideningBeamsWithDistance"};

  CRTreeOccupancyGridMap rtree;  // bounded and validated by its own serializeFrom()
  in >> rtree;
  CRTreeOccupancyGridMap::TGridViewOptions band;
  in >> band.gridView_minZ >> band.gridView_maxZ;
  try {
    band.validate();
    checkLikelihoodValues(lo, kWho, "likelihoodOptions");
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string(kWho) + ": the stored options are invalid: " + e.what());
  }

  setSize(x_min, x_max, y_min, y_max, res, 0.5f);
  if (getRawMap().size() != cells.size()) throw std::logic_error(std::string(kWho) + ": the grid is not its mirror");
  std::memcpy(m_map.data(), cells.data(), cells.size());
  m_is_empty = false;
  m_likelihoodCacheOutDated = true;
  insertionOptions = io;
  likelihoodOptions = lo;
  genericMapParams = generic;
  rtree_ = rtree;
  gridView_minZ = band.gridView_minZ;
  gridView_maxZ = band.gridView_maxZ;
}

}  // namespace rtog
