// rtog::CRTreeOccupancyGridMap: the 2D view (a COccupancyGridMap2D of a height band), the
// mrpt_grid preset's grid geometry and 2D scans (grid_graded.hpp: the grid's steps, with range
// noise or from an uncertain pose), and the grid queries MRPT users call on a 2D grid. (The
// likelihood of planar scans on the view is in CRTreeOccupancyGridMap_likelihood.cpp.)
#include "CRTreeOccupancyGridMap_grid2d.hpp"
#include "rtog/core/band.hpp"
#include "grid_graded.hpp"
#include "grid_tiles.hpp"
#include "mrpt_grid.hpp"
#include "pose_sigma.hpp"
#include "options_check.hpp"
#include "CRTreeOccupancyGridMap_caches.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <mrpt/config/CConfigFileBase.h>

namespace rtog {

using Grid2D = mrpt::maps::COccupancyGridMap2D;
using mrpt::poses::CPose3D;

// Our enumerators must be MRPT's numbers: configs and serialized maps carry them.
static_assert(int(CRTreeOccupancyGridMap::lmMeanInformation) == int(Grid2D::lmMeanInformation));
static_assert(int(CRTreeOccupancyGridMap::lmRayTracing) == int(Grid2D::lmRayTracing));
static_assert(int(CRTreeOccupancyGridMap::lmConsensus) == int(Grid2D::lmConsensus));
static_assert(int(CRTreeOccupancyGridMap::lmCellsDifference) == int(Grid2D::lmCellsDifference));
static_assert(int(CRTreeOccupancyGridMap::lmLikelihoodField_Thrun) == int(Grid2D::lmLikelihoodField_Thrun));
static_assert(int(CRTreeOccupancyGridMap::lmLikelihoodField_II) == int(Grid2D::lmLikelihoodField_II));
static_assert(int(CRTreeOccupancyGridMap::lmConsensusOWA) == int(Grid2D::lmConsensusOWA));

namespace {
constexpr const char* kNames[] = {"lmMeanInformation",       "lmRayTracing",         "lmConsensus",
                                  "lmCellsDifference",       "lmLikelihoodField_Thrun",
                                  "lmLikelihoodField_II",    "lmConsensusOWA"};
constexpr int kMethods = int(sizeof(kNames) / sizeof(kNames[0]));
}  // namespace

const char* const kLikelihoodMethodNames =
    "lmMeanInformation (0), lmRayTracing (1), lmConsensus (2), lmCellsDifference (3), lmLikelihoodField_Thrun (4), "
    "lmLikelihoodField_II (5), lmConsensusOWA (6)";

const char* likelihoodMethodName(CRTreeOccupancyGridMap::TLikelihoodMethod m) {
  const int i = static_cast<int>(m);
  return i >= 0 && i < kMethods ? kNames[i] : nullptr;
}

bool likelihoodMethodFromString(const std::string& s, CRTreeOccupancyGridMap::TLikelihoodMethod& out) {
  for (int i = 0; i < kMethods; ++i)
    if (s == kNames[i] || s == std::to_string(i)) {
      out = static_cast<CRTreeOccupancyGridMap::TLikelihoodMethod>(i);
      return true;
    }
  return false;
}

void loadGridLikelihoodKeys(CRTreeOccupancyGridMap::TLikelihoodOptions& o, const mrpt::config::CConfigFileBase& s,
                            const std::string& sec) {
  o.LF_alternateAverageMethod = readBool(s, sec, "LF_alternateAverageMethod", o.LF_alternateAverageMethod);
  o.MI_exponent = readFloat(s, sec, "MI_exponent", o.MI_exponent);
  const int skip = readInt(s, sec, "MI_skip_rays", static_cast<int>(o.MI_skip_rays));  // unsigned: -1 would wrap
  if (skip < 1) throw std::invalid_argument("rtog: invalid option [" + sec + "] MI_skip_rays: must be >= 1, got " + std::to_string(skip));
  o.MI_skip_rays = static_cast<uint32_t>(skip);
  o.MI_ratio_max_distance = readFloat(s, sec, "MI_ratio_max_distance", o.MI_ratio_max_distance);
  o.rayTracing_useDistanceFilter = readBool(s, sec, "rayTracing_useDistanceFilter", o.rayTracing_useDistanceFilter);
  o.consensus_takeEachRange = readInt(s, sec, "consensus_takeEachRange", o.consensus_takeEachRange);
  o.consensus_pow = readFloat(s, sec, "consensus_pow", o.consensus_pow);
  s.read_vector(sec, "OWA_weights", std::vector<float>(o.OWA_weights), o.OWA_weights);
  o.scanLikelihoodOnGridView = readBool(s, sec, "scanLikelihoodOnGridView", o.scanLikelihoodOnGridView);
}

void saveGridLikelihoodKeys(const CRTreeOccupancyGridMap::TLikelihoodOptions& o, mrpt::config::CConfigFileBase& c,
                            const std::string& sec) {
  c.write(sec, "LF_alternateAverageMethod", o.LF_alternateAverageMethod);
  c.write(sec, "MI_exponent", o.MI_exponent);
  c.write(sec, "MI_skip_rays", static_cast<int>(o.MI_skip_rays));
  c.write(sec, "MI_ratio_max_distance", o.MI_ratio_max_distance);
  c.write(sec, "rayTracing_useDistanceFilter", o.rayTracing_useDistanceFilter);
  c.write(sec, "consensus_takeEachRange", o.consensus_takeEachRange);
  c.write(sec, "consensus_pow", o.consensus_pow);
  c.write(sec, "OWA_weights", o.OWA_weights);
  c.write(sec, "scanLikelihoodOnGridView", o.scanLikelihoodOnGridView);
}

void CRTreeOccupancyGridMap::TGridViewOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& s,
                                                                 const std::string& sec) {
  gridView_minZ = readFloat(s, sec, "gridView_minZ", gridView_minZ);
  gridView_maxZ = readFloat(s, sec, "gridView_maxZ", gridView_maxZ);
  try {
    validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(e.what()) + " (section [" + sec + "])");
  }
}

void CRTreeOccupancyGridMap::TGridViewOptions::validate() const {
  if (!(gridView_minZ <= gridView_maxZ))  // also rejects NaN
    throw std::invalid_argument(
        "rtog::CRTreeOccupancyGridMap: invalid option [creationOpts] gridView_minZ/gridView_maxZ: need "
        "gridView_minZ <= gridView_maxZ");
}

void CRTreeOccupancyGridMap::TGridViewOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c,
                                                               const std::string& sec) const {
  c.write(sec, "gridView_minZ", gridView_minZ);
  c.write(sec, "gridView_maxZ", gridView_maxZ);
}

int8_t toMrptCell(float v) {
  // Scaling by a power of two is exact: a stored -l/16 gives back l bit for bit.
  const float t = -16.0f * v;
  if (t == std::nearbyint(t) && t >= -128.0f && t <= 127.0f) return static_cast<int8_t>(t);
  return Grid2D::p2l(static_cast<float>(1.0 - probability(v)));
}

// ---- the view ----------------------------------------------------------------------------

namespace {
/// The most cells a 2D view holds (one byte each): 1 GiB.
constexpr double kMaxViewCells = double(std::uint64_t{1} << 30);
}  // namespace

CRTreeOccupancyGridMap::GridView::GridView(const OccupancyMap& m, float lo, float hi, const std::optional<Rect>& ex,
                                           const TGridFrame2D* frame)
    : minZ(lo), maxZ(hi), extra(ex) {
  const double res = m.resolution();
  const auto fres = static_cast<float>(res);
  const Box kb = m.keyBounds();
  if (frame) {
    // The geometry of the grid the scans were stepped in, so that the view is that grid: MRPT's
    // methods then read the same cells at the same indices, margins included.
    const double fx0 = mrpt_grid::keyOffsetX(*frame), fy0 = mrpt_grid::keyOffsetY(*frame);
    const bool holds = kb.isEmpty() || (kb.min.x >= fx0 && kb.min.y >= fy0 && kb.max.x < fx0 + frame->size_x &&
                                        kb.max.y < fy0 + frame->size_y);
    const bool reaches = !extra || ((*extra)[0] >= frame->x_min && (*extra)[1] >= frame->y_min &&
                                    (*extra)[2] <= frame->x_max && (*extra)[3] <= frame->y_max);
    if (!(holds && reaches)) frame = nullptr;
  }
  if (frame && double(frame->size_x) * double(frame->size_y) > double(kMaxViewCells)) frame = nullptr;
  if (frame) {
    grid.setGeometry(*frame);
    fillCells(m, kb, mrpt_grid::keyOffsetX(*frame), mrpt_grid::keyOffsetY(*frame));
    return;
  }
  // The grid's lattice cells: the known cells' columns and `extra`, at least one cell.
  double gx0 = 0, gy0 = 0, gx1 = 0, gy1 = 0;  // inclusive cell keys
  if (!kb.isEmpty()) gx0 = kb.min.x, gy0 = kb.min.y, gx1 = kb.max.x, gy1 = kb.max.y;
  if (extra) {
    const auto key = [&](double v) { return std::floor(std::min(std::max(v / res, double(kKeyMin)), double(kKeyMax))); };
    const bool any = !kb.isEmpty();
    gx0 = any ? std::min(gx0, key((*extra)[0])) : key((*extra)[0]);
    gy0 = any ? std::min(gy0, key((*extra)[1])) : key((*extra)[1]);
    gx1 = std::max(any ? gx1 : gx0, key((*extra)[2]));
    gy1 = std::max(any ? gy1 : gy0, key((*extra)[3]));
  }
  // MRPT sizes its cell array with 32-bit arithmetic: a view of 2^32 cells or more gets none
  // (a scan whose end points lie a million cells away asks for one). Refused with the reason.
  const double cells = (gx1 - gx0 + 1) * (gy1 - gy0 + 1);
  if (cells > double(kMaxViewCells))
    throw std::length_error("rtog::CRTreeOccupancyGridMap: the 2D view of the map and the observation would have " +
                            std::to_string(cells) + " cells (more than " + std::to_string(kMaxViewCells) +
                            "): the observation reaches too far from the map's cells");
  // Cell k of the lattice is cell k - g*0 of the grid: setSize keeps multiples of res.
  grid.setSize(static_cast<float>(gx0 * res), static_cast<float>((gx1 + 1) * res), static_cast<float>(gy0 * res),
               static_cast<float>((gy1 + 1) * res), fres, 0.5f);
  fillCells(m, kb, gx0, gy0);
}

void CRTreeOccupancyGridMap::GridView::fillCells(const OccupancyMap& m, const Box& kb, double gx0, double gy0) {
  if (kb.isEmpty()) return;
  grid.setNonEmpty();
  const auto sx = static_cast<std::int64_t>(grid.getSizeX()), sy = static_cast<std::int64_t>(grid.getSizeY());
  const Box region = bandRegion(m, kb, minZ, maxZ);
  if (region.isEmpty()) return;  // band outside the map: all unknown
  auto& cells = grid.cells();
  // Known cells outside the view's frame (a grid frame that 2D scans grew, cells that other
  // observations put beyond it) are not drawn: clipped on every side.
  forEachBandRun(m, region, [&](std::int32_t ky, std::int32_t kx0, std::int32_t kx1, const float* best) {
    const auto y = static_cast<std::int64_t>(ky - gy0);
    if (y < 0 || y >= sy) return;
    const auto x0 = static_cast<std::int64_t>(kx0 - gx0);
    for (std::int64_t x = std::max<std::int64_t>(0, x0); x <= x0 + (kx1 - kx0) && x < sx; ++x) {
      const float v = best[x - x0];
      if (!std::isnan(v)) cells[static_cast<std::size_t>(y * sx + x)] = toMrptCell(v);
    }
  });
}

bool toGridLikelihoodOptions(const CRTreeOccupancyGridMap::TLikelihoodOptions& o, Grid2D::TLikelihoodOptions& g) {
  // MRPT keeps its per-cell likelihood-field values until the cells change, whatever the options.
  const bool lfChanged = g.LF_stdHit != o.LF_stdHit || g.LF_zHit != o.LF_zHit || g.LF_zRandom != o.LF_zRandom ||
                         g.LF_maxRange != o.LF_maxRange || g.LF_maxCorrsDistance != o.LF_maxCorrsDistance ||
                         g.LF_useSquareDist != o.LF_useSquareDist;
  g.likelihoodMethod = static_cast<Grid2D::TLikelihoodMethod>(o.likelihoodMethod);
  g.LF_stdHit = o.LF_stdHit;
  g.LF_zHit = o.LF_zHit;
  g.LF_zRandom = o.LF_zRandom;
  g.LF_maxRange = o.LF_maxRange;
  g.LF_decimation = o.LF_decimation;
  g.LF_maxCorrsDistance = o.LF_maxCorrsDistance;
  g.LF_useSquareDist = o.LF_useSquareDist;
  g.LF_alternateAverageMethod = o.LF_alternateAverageMethod;
  g.MI_exponent = o.MI_exponent;
  g.MI_skip_rays = o.MI_skip_rays;
  g.MI_ratio_max_distance = o.MI_ratio_max_distance;
  g.rayTracing_useDistanceFilter = o.rayTracing_useDistanceFilter;
  g.rayTracing_decimation = o.rayTracing_decimation;
  g.rayTracing_stdHit = o.rayTracing_stdHit;
  g.consensus_takeEachRange = o.consensus_takeEachRange;
  g.consensus_pow = o.consensus_pow;
  // Only lmConsensusOWA reads the weights (a hundred by default): not compared per call otherwise.
  if (o.likelihoodMethod == CRTreeOccupancyGridMap::lmConsensusOWA && g.OWA_weights != o.OWA_weights)
    g.OWA_weights = o.OWA_weights;
  g.enableLikelihoodCache = o.enableLikelihoodCache;
  return lfChanged;
}

void CRTreeOccupancyGridMap::GridView::setOptions(const TLikelihoodOptions& o, const TInsertionOptions& io) {
  const bool lfChanged = toGridLikelihoodOptions(o, grid.likelihoodOptions);
  // MI and ray tracing read the grid's insertion range.
  grid.insertionOptions.maxDistanceInsertion = io.maxDistanceInsertion;
  if (lfChanged) {
    grid.invalidateLikelihoodCache();
    field.clear();
  }
}

std::shared_ptr<CRTreeOccupancyGridMap::GridView> CRTreeOccupancyGridMap::gridViewShared(const double* need) const {
  const float lo = gridViewOptions.gridView_minZ, hi = gridViewOptions.gridView_maxZ;
  if (!(lo <= hi)) throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: need gridView_minZ <= gridView_maxZ");
  std::lock_guard<std::mutex> lk(caches_->mutex);
  auto& v = caches_->grid_view;
  const bool same = v && v->minZ == lo && v->maxZ == hi;
  if (same && (!need || v->covers({need[0], need[1], need[2], need[3]}))) return v;
  // In the mrpt_grid preset the view is the grid the scans were stepped in, which is what the
  // stock grid would hold, as long as what is asked lies within it; else grown beyond it.
  const bool on_frame = insertionOptions.mrptGrid() && frame_.has_layer &&
                        (!need || (need[0] >= frame_.x_min && need[1] >= frame_.y_min && need[2] <= frame_.x_max &&
                                   need[3] <= frame_.y_max));
  std::optional<GridView::Rect> extra;
  if (need && !on_frame) {
    // Grown with a margin, so that particles wandering out of it rebuild it rarely.
    constexpr double kMargin = 5.0;
    extra = GridView::Rect{need[0] - kMargin, need[1] - kMargin, need[2] + kMargin, need[3] + kMargin};
    if (same && v->extra)
      for (int i = 0; i < 4; ++i) (*extra)[i] = i < 2 ? std::min((*extra)[i], (*v->extra)[i]) : std::max((*extra)[i], (*v->extra)[i]);
  } else if (same && !on_frame) {
    extra = v->extra;
  }
  v = std::make_shared<GridView>(map_, lo, hi, extra, on_frame ? &frame_ : nullptr);
  return v;
}

std::shared_ptr<const Grid2D> CRTreeOccupancyGridMap::gridView() const {
  auto v = gridViewShared();
  return std::shared_ptr<const Grid2D>(v, &v->grid);  // keeps the view alive, not the map's cache
}

void CRTreeOccupancyGridMap::setGridFrame(float x_min, float x_max, float y_min, float y_max) {
  if (!isEmpty()) throw std::logic_error("rtog::CRTreeOccupancyGridMap::setGridFrame: the map holds cells");
  TGridFrame2D f;
  mrpt_grid::setSize(f, x_min, x_max, y_min, y_max, static_cast<float>(map_.resolution()));
  frame_ = f;
}

// ---- grid queries on the view --------------------------------------------------------------

void CRTreeOccupancyGridMap::computeEntropy(Grid2D::TEntropyInfo& info) const {
  const auto v = gridViewShared();
  std::lock_guard<std::mutex> lk(v->mutex);
  v->grid.computeEntropy(info);
}

void CRTreeOccupancyGridMap::getAsImage(mrpt::img::CImage& img, bool verticalFlip, bool forceRGB,
                                        bool tricolor) const {
  const auto v = gridViewShared();
  std::lock_guard<std::mutex> lk(v->mutex);
  v->grid.getAsImage(img, verticalFlip, forceRGB, tricolor);
}

bool CRTreeOccupancyGridMap::saveAsBitmapFile(const std::string& file) const {
  const auto v = gridViewShared();
  std::lock_guard<std::mutex> lk(v->mutex);
  return v->grid.saveAsBitmapFile(file);
}

float CRTreeOccupancyGridMap::computeClearance(float x, float y, float maxSearchDistance) const {
  const auto v = gridViewShared();
  std::lock_guard<std::mutex> lk(v->mutex);
  return v->grid.computeClearance(x, y, maxSearchDistance);
}

double CRTreeOccupancyGridMap::getArea() const { return gridViewShared()->grid.getArea(); }

CRTreeOccupancyGridMap::TCellCounts CRTreeOccupancyGridMap::gridViewCellCounts() const {
  const auto v = gridViewShared();
  TCellCounts n;
  for (const auto l : v->grid.getRawMap()) (l > 0 ? n.free : l < 0 ? n.occupied : n.unknown)++;
  return n;
}

// ---- 2D scans in the mrpt_grid preset ----------------------------------------

bool CRTreeOccupancyGridMap::insertGridScan(const mrpt::obs::CObservation2DRangeScan& scan, const CPose3D& robotPose,
                                            GridScanUpdate* update) {
  // The grid's steps are the graded path's with one pose and no band (grid_graded.hpp).
  return insertGradedScan(scan, {pose_sigma::SigmaPose{1.0, robotPose}}, update);
}

bool CRTreeOccupancyGridMap::followsGridScans() const {
  std::lock_guard<std::mutex> lk(caches_->mutex);
  return caches_->tiles != nullptr;
}

bool CRTreeOccupancyGridMap::insertGradedScan(const mrpt::obs::CObservation2DRangeScan& scan,
                                              const std::vector<pose_sigma::SigmaPose>& poses, GridScanUpdate* update) {
  syncParams();
  InsertStats stats;
  std::size_t invalid = 0;
  const bool follow = followsGridScans();
  GridScanUpdate own;
  GridScanUpdate* upd = update ? update : follow ? &own : nullptr;
  // With the view's tiles kept, the scan's steps are what they follow.
  if (!mrpt_grid::insertGradedScan(map_, frame_, scan, poses, insertionOptions, upd, stats, invalid)) return false;
  invalidRangesSkipped += invalid;
  lastInsertStats = stats;
  totalInsertStats += stats;
  if (follow)
    followGridScan(*upd);
  else
    notifyMapChanged();
  return true;
}

// The 2D view's tiles (grid_tiles.hpp) follow the scan's steps: see tilesLikelihood() for when
// they stand for the view.
void CRTreeOccupancyGridMap::followGridScan(const GridScanUpdate& upd) {
  std::lock_guard<std::mutex> lk(caches_->mutex);
  caches_->dropCellData();
  GridTiles* tiles = caches_->tiles.get();
  if (!tiles) return;
  if (!mrpt_grid::layerInBand(frame_, map_.resolution(), gridViewOptions.gridView_minZ, gridViewOptions.gridView_maxZ)) {
    caches_->tiles.reset();  // the first scan's layer is not in the view: made again when needed
    return;
  }
  if (!tiles->frame().sameGeometry(frame_)) tiles->setFrame(frame_);
  const float* after = upd.after.data();
  for (const auto& run : upd.runs)
    OccupancyMap::forEachRunCell(run, [&](std::int32_t x, std::int32_t y, StepKind) {
      const float v = *after++;
      if (!std::isnan(v)) tiles->setCell(x, y, toMrptCell(v));  // NaN: a cell outside the map's region
    });
  const FieldConstants f(caches_->tiles_likelihood, frame_.resolution);
  tiles->dropStaleTerms(f.window);
}

}  // namespace rtog
