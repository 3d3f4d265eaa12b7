// rtog::CRTreeBackedGridMap2D: a COccupancyGridMap2D view of an R-tree map.
#include "rtog/mrpt/CRTreeBackedGridMap2D.h"

#include "CRTreeOccupancyGridMap_grid2d.hpp"
#include "finite_pose.hpp"
#include "grid_consensus.hpp"
#include "likelihood_field_2d.hpp"
#include "rtog/core/band.hpp"
#include "mrpt_grid.hpp"
#include "options_check.hpp"

#include <cmath>
#include <limits>
#include <sstream>

#include <mrpt/obs/CObservationRange.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/serialization/CArchive.h>

using namespace mrpt::maps;

IMPLEMENTS_SERIALIZABLE(CRTreeBackedGridMap2D, COccupancyGridMap2D, rtog)

MAP_DEFINITION_REGISTER("rtog::CRTreeBackedGridMap2D,rtreeGridMap2D", rtog::CRTreeBackedGridMap2D)

// Registered for CArchive right after its runtimeClassId is initialized (why not with
// MRPT_INITIALIZER: CRTreeOccupancyGridMap.cpp).
namespace {
[[maybe_unused]] const bool registered_at_load =
    (mrpt::rtti::registerClass(CLASS_ID(rtog::CRTreeBackedGridMap2D)), true);
}  // namespace

namespace rtog {

CRTreeBackedGridMap2D::TMapDefinition::TMapDefinition() = default;

void CRTreeBackedGridMap2D::TMapDefinition::loadFromConfigFile_map_specific(
    const mrpt::config::CConfigFileBase& source, const std::string& prefix) {
  loadError.clear();
  try {
    const std::string sec = prefix + "_creationOpts";
    resolution = readDouble(source, sec, "resolution", resolution);
    if (!(std::isfinite(resolution) && resolution >= 1e-3 && resolution <= 1e2))
      throw std::invalid_argument("rtog::CRTreeBackedGridMap2D: invalid option [" + sec +
                                  "] resolution: must lie in [1e-3, 1e2] m, got " + std::to_string(resolution));
    readGridExtent(source, sec, min_x, max_x, min_y, max_y);
    readGenericMapParams(source, sec, "rtog::CRTreeBackedGridMap2D", genericMapParams);
    reportUnknownKeys(source, sec,
                      {"resolution", "min_x", "max_x", "min_y", "max_y", "gridView_minZ", "gridView_maxZ",
                       "disableSaveAs3DObject", "enableSaveAs3DObject", "enableObservationLikelihood",
                       "enableObservationInsertion"});
    CRTreeOccupancyGridMap::TGridViewOptions band;  // the same keys and check as the R-tree map's
    band.gridView_minZ = gridView_minZ, band.gridView_maxZ = gridView_maxZ;
    band.loadFromConfigFile(source, sec);
    gridView_minZ = band.gridView_minZ, gridView_maxZ = band.gridView_maxZ;
    insertionOpts.loadFromConfigFile(source, prefix + "_insertOpts");
    // The grid's own struct, read by MRPT, which checks none of its values: their syntax first
    // (MRPT's read_bool takes "on" as false, read_float "0.1abc" as 0.1), then their values.
    using V = IniValue;
    checkIniValues(source, prefix + "_likelihoodOpts", "rtog::CRTreeBackedGridMap2D",
                   {{"LF_stdHit", V::Real}, {"LF_zHit", V::Real}, {"LF_zRandom", V::Real}, {"LF_maxRange", V::Real},
                    {"LF_decimation", V::Count}, {"LF_maxCorrsDistance", V::Real}, {"LF_useSquareDist", V::Bool},
                    {"LF_alternateAverageMethod", V::Bool}, {"MI_exponent", V::Real}, {"MI_skip_rays", V::Count},
                    {"MI_ratio_max_distance", V::Real}, {"rayTracing_useDistanceFilter", V::Bool},
                    {"rayTracing_stdHit", V::Real}, {"consensus_takeEachRange", V::Count}, {"consensus_pow", V::Real},
                    {"enableLikelihoodCache", V::Bool}});
    likelihoodOpts.loadFromConfigFile(source, prefix + "_likelihoodOpts");
    // MRPT's read_bool took "on" as false: the booleans read again as everywhere in rtog.
    for (auto [key, flag] : {std::pair{"LF_useSquareDist", &likelihoodOpts.LF_useSquareDist},
                             std::pair{"LF_alternateAverageMethod", &likelihoodOpts.LF_alternateAverageMethod},
                             std::pair{"rayTracing_useDistanceFilter", &likelihoodOpts.rayTracing_useDistanceFilter},
                             std::pair{"enableLikelihoodCache", &likelihoodOpts.enableLikelihoodCache}})
      *flag = readBool(source, prefix + "_likelihoodOpts", key, *flag);
    checkLikelihoodValues(likelihoodOpts, "rtog::CRTreeBackedGridMap2D", prefix + "_likelihoodOpts");
  } catch (const std::exception& e) {
    loadError = e.what();  // raised in internal_CreateFromMapDefinition
  }
}

void CRTreeBackedGridMap2D::TMapDefinition::dumpToTextStream_map_specific(std::ostream& out) const {
  out << "resolution = " << resolution << "\ngridView_minZ = " << gridView_minZ
      << "\ngridView_maxZ = " << gridView_maxZ << "\n";
  insertionOpts.dumpToTextStream(out);
  likelihoodOpts.dumpToTextStream(out);
}

mrpt::maps::CMetricMap* CRTreeBackedGridMap2D::internal_CreateFromMapDefinition(
    const mrpt::maps::TMetricMapInitializer& def) {
  const auto& d = dynamic_cast<const CRTreeBackedGridMap2D::TMapDefinition&>(def);
  if (!d.loadError.empty()) throw std::invalid_argument(d.loadError);
  auto* m = new CRTreeBackedGridMap2D(d.resolution);
  m->rtree_ = CRTreeOccupancyGridMap(d.resolution, d.insertionOpts);
  m->setExtent(d.min_x, d.max_x, d.min_y, d.max_y);
  // The grid's own insertion options, for code that reads them off a COccupancyGridMap2D.
  auto& gio = m->insertionOptions;
  const auto& io = d.insertionOpts;
  gio.mapAltitude = io.mapAltitude;
  gio.useMapAltitude = io.useMapAltitude;
  gio.maxDistanceInsertion = io.maxDistanceInsertion;
  gio.maxOccupancyUpdateCertainty = io.maxOccupancyUpdateCertainty;
  gio.maxFreenessUpdateCertainty = io.maxFreenessUpdateCertainty;
  gio.maxFreenessInvalidRanges = io.maxFreenessInvalidRanges;
  gio.considerInvalidRangesAsFreeSpace = io.considerInvalidRangesAsFreeSpace;
  gio.decimation = io.decimation;
  gio.horizontalTolerance = io.horizontalTolerance;
  gio.wideningBeamsWithDistance = io.wideningBeamsWithDistance;
  m->likelihoodOptions = d.likelihoodOpts;
  m->gridView_minZ = d.gridView_minZ;
  m->gridView_maxZ = d.gridView_maxZ;
  m->genericMapParams = d.genericMapParams;
  return m;
}

CRTreeBackedGridMap2D::CRTreeBackedGridMap2D(double resolution)
    : COccupancyGridMap2D(-10.0f, 10.0f, -10.0f, 10.0f, static_cast<float>(resolution)), rtree_(resolution) {}

void CRTreeBackedGridMap2D::internal_clear() {
  COccupancyGridMap2D::internal_clear();
  rtree_.clear();
}

void CRTreeBackedGridMap2D::setExtent(float x_min, float x_max, float y_min, float y_max) {
  setSize(x_min, x_max, y_min, y_max, getResolution(), 0.5f);
  rtree_.setGridFrame(x_min, x_max, y_min, y_max);
}

bool CRTreeBackedGridMap2D::insertGridScan(const mrpt::obs::CObservation2DRangeScan& scan,
                                           const mrpt::poses::CPose3D& pose) {
  thread_local CRTreeOccupancyGridMap::GridScanUpdate upd;
  if (!rtree_.insertGridScan(scan, pose, &upd)) return false;
  // MRPT's own growth of this grid, from the same request: it must land on the geometry the
  // R-tree map's mirror computed, or the cells below would not be the grid's.
  resizeGrid(upd.grow[0], upd.grow[1], upd.grow[2], upd.grow[3], 0.5f);
  const TGridFrame2D& f = rtree_.gridFrame();
  TGridFrame2D mine = f;
  mine.x_min = getXMin(), mine.x_max = getXMax(), mine.y_min = getYMin(), mine.y_max = getYMax();
  mine.size_x = getSizeX(), mine.size_y = getSizeY();
  if (!mine.sameGeometry(f)) throw std::logic_error("rtog::CRTreeBackedGridMap2D: the grid grew unlike its mirror");
  const std::int32_t ox = mrpt_grid::keyOffsetX(f), oy = mrpt_grid::keyOffsetY(f);
  // MRPT drops every kept likelihood-field value after an insertion (a pass over the whole grid,
  // then every term computed again): only the values the changed cells can reach are dropped
  // here, unless the grid grew (resizeGrid dropped them all, as MRPT does) or none are kept.
  const bool keep = !m_likelihoodCacheOutDated && likelihoodOptions.enableLikelihoodCache &&
                    m_precomputedLikelihood.size() == m_map.size();
  constexpr int kBlock = 16;
  const std::size_t bx = m_size_x / kBlock + 1, by = m_size_y / kBlock + 1;
  std::vector<std::uint8_t> touched(keep ? bx * by : 0, 0);
  const float* value = upd.after.data();
  for (const auto& run : upd.runs)
    rtog::OccupancyMap::forEachRunCell(run, [&](std::int32_t x, std::int32_t y, rtog::StepKind) {
      const auto cx = static_cast<std::size_t>(x - ox), cy = static_cast<std::size_t>(y - oy);
      const auto c = static_cast<cellType>(mrpt_grid::cellOfValue(*value++));
      cellType& cell = m_map[cx + cy * m_size_x];
      if (keep && cell != c) touched[cy / kBlock * bx + cx / kBlock] = 1;
      cell = c;
    });
  if (keep)
    forgetKeptFieldNear(touched, bx, kBlock);
  else
    m_likelihoodCacheOutDated = true;
  m_is_empty = false;
  return true;
}

void CRTreeBackedGridMap2D::forgetKeptFieldNear(const std::vector<std::uint8_t>& touched, std::size_t bx, int block) {
  // A cell's term reads the cells within K of it (COccupancyGridMap2D's likelihood field): the
  // terms within K of a changed block are dropped, as MRPT marks a term not computed.
  const int k = FieldConstants(likelihoodOptions, m_resolution).window;
  const int sx = static_cast<int>(m_size_x), sy = static_cast<int>(m_size_y);
  for (std::size_t b = 0; b < touched.size(); ++b) {
    if (!touched[b]) continue;
    const int x0 = std::max(0, static_cast<int>(b % bx) * block - k), x1 = std::min(sx - 1, static_cast<int>(b % bx) * block + block - 1 + k);
    const int y0 = std::max(0, static_cast<int>(b / bx) * block - k), y1 = std::min(sy - 1, static_cast<int>(b / bx) * block + block - 1 + k);
    for (int y = y0; y <= y1; ++y)
      std::fill(m_precomputedLikelihood.begin() + (static_cast<std::ptrdiff_t>(y) * sx + x0),
                m_precomputedLikelihood.begin() + (static_cast<std::ptrdiff_t>(y) * sx + x1 + 1), kTermNotComputed);
  }
}

double CRTreeBackedGridMap2D::internal_computeObservationLikelihood(const mrpt::obs::CObservation& obs,
                                                                   const mrpt::poses::CPose3D& takenFrom) const {
  // Before the stock grid: its mean-information method inserts the scan into a copy of this map
  // (which refuses a non-finite pose by an exception), the others read NaN cells.
  if (!detail::finitePoses(obs, takenFrom)) return detail::kImpossibleLogLik;
  // Else as COccupancyGridMap2D's own (private, so not callable): non-planar scans and scans off
  // the map's altitude score -10, the rest by the selected method on the 2D pose.
  if (const auto* scan = dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(&obs)) {
    if (!scan->isPlanarScan(insertionOptions.horizontalTolerance)) return -10;
    if (insertionOptions.useMapAltitude && std::fabs(insertionOptions.mapAltitude - scan->sensorPose.z()) > 0.01)
      return -10;
  }
  const mrpt::poses::CPose2D pose(takenFrom);
  switch (likelihoodOptions.likelihoodMethod) {
    case lmMeanInformation: return computeObservationLikelihood_MI(obs, pose);
    case lmConsensus: {
      // MRPT's reads the cells of end points beyond the grid unchecked (SIGSEGV): bounded, the
      // same double wherever MRPT's reads the grid's cells.
      const std::optional<double> l = boundedConsensusLikelihood(*this, obs, pose);
      return l ? *l : computeObservationLikelihood_Consensus(obs, pose);
    }
    case lmCellsDifference: return computeObservationLikelihood_CellsDifference(obs, pose);
    case lmLikelihoodField_Thrun:
      // The stock method's value on the grid's own kept terms, one sine and cosine per pose.
      if (const auto* scan = dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(&obs))
        return keptFieldScanLogLikelihood(*this, m_precomputedLikelihood, m_likelihoodCacheOutDated, *scan, takenFrom);
      return computeObservationLikelihood_likelihoodField_Thrun(obs, pose);
    case lmLikelihoodField_II: return computeObservationLikelihood_likelihoodField_II(obs, pose);
    case lmConsensusOWA: return computeObservationLikelihood_ConsensusOWA(obs, pose);
    case lmRayTracing:
    default: return computeObservationLikelihood_rayTracing(obs, pose);
  }
}

bool CRTreeBackedGridMap2D::internal_insertObservation(const mrpt::obs::CObservation& obs,
                                                       const std::optional<const mrpt::poses::CPose3D>& robotPose) {
  if (rtree_.insertionOptions.mrptGrid())
    if (const auto* scan = dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(&obs))
      return insertGridScan(*scan, robotPose ? *robotPose : mrpt::poses::CPose3D());
  const mrpt::poses::CPose3D pose = robotPose ? *robotPose : mrpt::poses::CPose3D();
  if (const auto* range = dynamic_cast<const mrpt::obs::CObservationRange*>(&obs)) {
    // Cones: the region is each reading's disc of its range about its sensor.
    std::size_t invalid = 0;
    const std::vector<ConeReading> cones = rtree_.sonarReadings(*range, pose, invalid);  // throws before any change
    if (!rtree_.insertObservation(obs, robotPose)) return false;
    if (cones.empty()) return true;
    double x0 = cones[0].origin.x(), x1 = x0, y0 = cones[0].origin.y(), y1 = y0;
    for (const ConeReading& c : cones) {
      x0 = std::min(x0, c.origin.x() - c.range), x1 = std::max(x1, c.origin.x() + c.range);
      y0 = std::min(y0, c.origin.y() - c.range), y1 = std::max(y1, c.origin.y() + c.range);
    }
    const double pad = 2.0 * rtree_.resolution();
    refreshRegion(x0 - pad, y0 - pad, x1 + pad, y1 + pad);
    return true;
  }
  ObservationBeams beams;
  if (!rtree_.extractBeams(obs, pose, beams, true)) return false;
  if (!rtree_.insertObservation(obs, robotPose)) return false;
  // The region the beams can have changed: their bounding box, beams cut at maxDistanceInsertion.
  // End points the R-tree map skipped (non-finite, or without a key) changed nothing: left out,
  // or one infinite coordinate (cut to NaN) would make the grid's resize assert.
  const Lattice& lat = rtree_.map().lattice();
  Key unused;
  if (!lat.tryKey(beams.origin, unused)) return true;
  double x0 = beams.origin.x(), x1 = x0, y0 = beams.origin.y(), y1 = y0;
  const double maxd = rtree_.insertionOptions.maxDistanceInsertion;
  for (const auto& p : beams.points) {
    Eigen::Vector3d q = p.cast<double>();
    if (!q.allFinite()) continue;
    const Eigen::Vector3d d = q - beams.origin;
    if (maxd > 0 && d.norm() > maxd) q = beams.origin + d * (maxd / d.norm());
    if (!lat.tryKey(q, unused)) continue;
    x0 = std::min(x0, q.x()), x1 = std::max(x1, q.x());
    y0 = std::min(y0, q.y()), y1 = std::max(y1, q.y());
  }
  const double pad = 2.0 * rtree_.resolution();
  refreshRegion(x0 - pad, y0 - pad, x1 + pad, y1 + pad);
  return true;
}

void CRTreeBackedGridMap2D::refreshRegion(double x0, double y0, double x1, double y1) {
  const OccupancyMap& m = rtree_.map();
  const Box kb = m.keyBounds();
  if (kb.isEmpty()) return;
  resizeGrid(static_cast<float>(x0), static_cast<float>(x1), static_cast<float>(y0), static_cast<float>(y1), 0.5f,
             true);
  const Lattice& lat = m.lattice();
  Key k0, k1, z0, z1;
  if (!lat.tryKey(Eigen::Vector3d(x0, y0, 0), k0) || !lat.tryKey(Eigen::Vector3d(x1, y1, 0), k1)) return;
  const double zlo = std::max<double>(gridView_minZ, lat.boxMin(kb).z());
  const double zhi = std::min<double>(gridView_maxZ, lat.boxMax(kb).z() - 0.5 * lat.resolution());
  if (!(zlo <= zhi) || !lat.tryKey(Eigen::Vector3d(0, 0, zlo), z0) || !lat.tryKey(Eigen::Vector3d(0, 0, zhi), z1))
    return;
  const Box region{Key{k0.x, k0.y, z0.z}, Key{k1.x, k1.y, z1.z}};
  // Sample the band at each 2D cell centre (the grid's cells need not align with the lattice):
  // the cells whose centre's column lies in a run. The others hold no known cell: left as they
  // are (unknown: cells leave the R-tree map only through clear() or a load, which refreshGrid).
  const int cx0 = std::max(0, x2idx(x0)), cx1 = std::min<int>(static_cast<int>(getSizeX()) - 1, x2idx(x1));
  const int cy0 = std::max(0, y2idx(y0)), cy1 = std::min<int>(static_cast<int>(getSizeY()) - 1, y2idx(y1));
  forEachBandRun(m, region, [&](std::int32_t ky, std::int32_t kx0, std::int32_t kx1, const float* best) {
    const Box run{Key{kx0, ky, 0}, Key{kx1, ky, 0}};
    const Eigen::Vector3d lo = lat.boxMin(run), hi = lat.boxMax(run);
    const int tx0 = std::max(cx0, x2idx(lo.x()) - 1), tx1 = std::min(cx1, x2idx(hi.x()) + 1);
    const int ty0 = std::max(cy0, y2idx(lo.y()) - 1), ty1 = std::min(cy1, y2idx(hi.y()) + 1);
    for (int cy = ty0; cy <= ty1; ++cy)
      for (int cx = tx0; cx <= tx1; ++cx) {
        Key k;
        if (!lat.tryKey(Eigen::Vector3d(idx2x(cx), idx2y(cy), 0), k)) continue;
        if (k.y != ky || k.x < kx0 || k.x > kx1) continue;
        const float v = best[k.x - kx0];
        // MRPT grid cells hold P(free): 0 is occupied (black), 1 free (white).
        setCell(cx, cy, std::isnan(v) ? 0.5f : static_cast<float>(1.0 - probability(v)));
      }
  });
}

void CRTreeBackedGridMap2D::refreshGrid() {
  const OccupancyMap& m = rtree_.map();
  const Box kb = m.keyBounds();
  if (kb.isEmpty()) {
    COccupancyGridMap2D::internal_clear();
    return;
  }
  const Eigen::Vector3d lo = m.lattice().boxMin(kb), hi = m.lattice().boxMax(kb);
  setSize(static_cast<float>(lo.x()), static_cast<float>(hi.x()), static_cast<float>(lo.y()),
          static_cast<float>(hi.y()), static_cast<float>(m.resolution()), 0.5f);
  refreshRegion(lo.x(), lo.y(), hi.x(), hi.y());
  m_is_empty = false;
}

// What the stock grid writes, and the map itself: the R-tree map's scene and slice picture would
// draw again what the grid's picture shows, at the cost of the save (apps save last, holding the
// most). `rtog export --scene` draws the cuboids from the .rtog.
void CRTreeBackedGridMap2D::saveMetricMapRepresentationToFile(const std::string& prefix) const {
  COccupancyGridMap2D::saveMetricMapRepresentationToFile(prefix);
  rtree_.saveToFile(prefix + ".rtog");
}

std::string CRTreeBackedGridMap2D::asString() const {
  std::ostringstream os;
  os << "rtog::CRTreeBackedGridMap2D: " << getSizeX() << "x" << getSizeY() << " 2D view of " << rtree_.asString();
  return os.str();
}

}  // namespace rtog
