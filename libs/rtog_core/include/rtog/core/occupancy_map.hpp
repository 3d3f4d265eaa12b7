// The R-tree occupancy grid: a probabilistic occupancy map whose leaves are disjoint
// axis-aligned cuboids of lattice cells, each with one log-odds value. Cells exist only
// where a sensor observed; unknown space has no leaf.
#pragma once

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rtog/core/cone.hpp"
#include "rtog/core/key.hpp"
#include "rtog/core/log_odds.hpp"
#include "rtog/core/params.hpp"
#include "rtog/core/point_source.hpp"
#include "rtog/core/pose_blur.hpp"
#include "rtog/core/stats.hpp"

namespace rtog {

class MapEngine;  // the implementation (src/map/map_engine.hpp)

class OccupancyMap {
 public:
  explicit OccupancyMap(const MapParams& params = {});
  // Copies and moves cover the source's planar cache first and leave scratch behind; a
  // moved-from map is empty and keeps its parameters.
  OccupancyMap(const OccupancyMap& other);
  OccupancyMap(OccupancyMap&& other);
  OccupancyMap& operator=(const OccupancyMap& other);
  OccupancyMap& operator=(OccupancyMap&& other);
  ~OccupancyMap();

  const MapParams& params() const;
  const Lattice& lattice() const;
  const LogOddsModel& logOddsModel() const;
  double resolution() const { return lattice().resolution(); }

  /// Removes every leaf; parameters stay.
  void clear();

  /// Restricts the map to the cells of `region` (inclusive keys, whole bricks: its faces on
  /// multiples of 2^kBrickBits = 16 cells), for a map split by space (a tile of a larger map). Every
  /// later insertion, fusion and assignment changes those cells only, each exactly as it changes
  /// them in a map without the restriction: the same updates in the same order (a cell depends
  /// on its own updates only, and leaves never cross a brick border), so the maps of the tiles of
  /// a partition of space together hold, leaf for leaf, the one map built from the same scans.
  /// The insertion figures count the region's cells (and every beam). Box::empty() lifts the
  /// restriction. Not written to map files. Throws std::invalid_argument for a region not on brick
  /// borders or beyond the key range, std::logic_error if the map holds cells outside it.
  void setRegion(const Box& region);
  /// The region set by setRegion(); Box::empty() if the map is not restricted.
  Box region() const;

  /// Covers the cells held in the planar cache (see InsertParams::planar_cache) with leaves and
  /// returns the leaf figures of that. Every reading call does this first by itself (safely from
  /// concurrent readers); calling it moves the cost to a time of your choosing.
  InsertStats flush();
  /// True while scans wait in the planar cache.
  bool hasPendingCover() const;

  // ---- insertion --------------------------------------------------------------------
  /// Integrates one scan: beams from `origin` to each point (map frame, metres). `is_hit`
  /// (optional, one byte per point) flags beams that returned; a zero marks a no-return
  /// beam, which clears space up to the point but marks nothing occupied.
  InsertStats insertPointCloud(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                               const InsertParams& ip = {}, const std::uint8_t* is_hit = nullptr);
  InsertStats insertPointCloud(const Eigen::Vector3d& origin, const std::vector<Eigen::Vector3f>& points,
                               const InsertParams& ip = {}) {
    return insertPointCloud(origin, points.data(), points.size(), ip);
  }

  /// Integrates one scan read piece by piece (PointSource) by the insertion threads, with the
  /// same result as the points given whole: a scan in the sensor's frame is moved into the map
  /// frame a few thousand points at a time, never copied whole. Every beam returned.
  InsertStats insertPointSource(const Eigen::Vector3d& origin, const PointSource& source, const InsertParams& ip = {});

  /// Integrates one scan taken from an uncertain pose, given as the scan seen from each pose of
  /// a weighted sample set (e.g. sigmaPoints() of the pose covariance): every cell takes, once,
  /// the change logit(P) - l0 of P = sum_i w_i P_i, where P_i is the probability the sensor model
  /// (ip.model) gives the cell from pose i and the prior for a cell the scan from pose i did not
  /// touch (weights are normalized). One scan gives insertPointCloud()'s update bit for bit. Throws
  /// std::invalid_argument for a weight that is not positive and finite, std::out_of_range for an
  /// origin without a key, changing nothing.
  InsertStats insertBlurred(const WeightedScan* scans, std::size_t n, const InsertParams& ip = {});
  InsertStats insertBlurred(const std::vector<WeightedScan>& scans, const InsertParams& ip = {}) {
    return insertBlurred(scans.data(), scans.size(), ip);
  }
  /// The same blur of a scan given once, as seen from the mean pose (map frame, as
  /// insertPointCloud() takes it), with each pose of the set as a rigid move of it (PoseMove). The
  /// scan is traced once; pose i's probability of a cell is the one the mean trace gives the
  /// point move_i^-1 (cell centre), which is the traced pose's up to the raster (cells of a beam
  /// moved, not the moved beam's cells: equal for moves by whole cells). The mixture is then the
  /// same. A cell no move reaches takes no change. Throws as insertBlurred(scans) does, and
  /// std::invalid_argument for a move that is not finite.
  InsertStats insertBlurred(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                            const PoseMove* moves, std::size_t n, const InsertParams& ip = {},
                            const std::uint8_t* is_hit = nullptr);
  InsertStats insertBlurred(const Eigen::Vector3d& origin, const std::vector<Eigen::Vector3f>& points,
                            const std::vector<PoseMove>& moves, const InsertParams& ip = {}) {
    return insertBlurred(origin, points.data(), points.size(), moves.data(), moves.size(), ip);
  }

  /// Integrates readings of range sensors with a wide beam (sonar, IR; rtog/core/cone.hpp), in
  /// order, each one measurement: the cells of its cone (coneCells) take weight * the hit change
  /// (arc) or weight * the miss change (inside), once. The axis is a beam of `ip`: cut at
  /// ip.max_range (no echo then), skipped and counted as a beam is. ip.model and ip.discretize
  /// do not apply. A reading of non-finite range or yaw is skipped and counted in
  /// skipped_non_finite, one of range <= 0 in skipped_zero_length. Throws, changing nothing,
  /// std::invalid_argument for a non-finite origin or an aperture outside [0, pi] and
  /// std::out_of_range for an origin without a key.
  InsertStats insertCones(const ConeReading* readings, std::size_t n, ConeWeighting w = ConeWeighting::Elfes,
                          const InsertParams& ip = {});

  using StepRun = rtog::StepRun;
  static constexpr int kRunFracBits = kStepRunFracBits;
  /// Calls fn(x, y, kind) for every cell of a run, in its order.
  template <class Fn>
  static void forEachRunCell(const StepRun& r, Fn&& fn) {
    rtog::forEachRunCell(r, std::forward<Fn>(fn));
  }
  /// Applies the runs' steps in their order to cells of z-layer `z`, each one StepRule::apply: a
  /// cell crossed by five beams takes five steps, as in a grid that updates beam by beam, where
  /// insertPointCloud() updates each cell once a scan. Unknown cells start at the prior; the cells
  /// go through the planar cache, as planar scans do. `after`, if given, receives the value of
  /// each step's cell after that step, in forEachRunCell's order. The stats count steps:
  /// cells_free and cells_occupied by kind, cells_unchanged those (of either) where the value stayed. Throws
  /// std::out_of_range, changing nothing, if a cell has no key.
  InsertStats applyStepRuns(std::int32_t z, const StepRun* runs, std::size_t n, const StepRule& rule,
                            std::vector<float>* after = nullptr);

  /// Fuses `other` (another robot's, sensor's or day's map) into this one by the independent
  /// opinion pool: each cell becomes l1 + l2 - l0, clamped (l0: `other`'s prior, counted once), a
  /// cell known in one map only keeps its value (exactly so when l0 is 0, the default). `other` is
  /// placed by the rigid `pose` (its frame in this map's) and resampled into this lattice so that
  /// its evidence is conserved: each cell receives, from each cuboid of `other`, (l2 - l0) times
  /// the volume of the placed cuboid inside the cell over one cell of `other` (a coarser lattice
  /// sums, a finer one divides, a turn spreads by the exact overlap). Cell for cell when the pose
  /// is a shift by whole cells or a quarter turn of an equal lattice. Cells beyond the key range
  /// (a far pose) are left out, each cuboid that has some counted in skipped_out_of_range.
  /// Without clamping, maps built from two halves of a log fuse into the
  /// map of the whole log, up to float rounding of the sums. Throws std::invalid_argument, changing
  /// nothing, for a pose that is not rigid, threads < 1, or `other` being this map.
  InsertStats fuse(const OccupancyMap& other, const Eigen::Isometry3d& pose = Eigen::Isometry3d::Identity(),
                   int threads = defaultThreadCount());
  /// One pose of an uncertain placement (e.g. the sigma points of a registration's covariance).
  struct WeightedPose {
    Eigen::Isometry3d pose;
    double weight;
  };
  /// fuse() with `other` placed by a pose that is uncertain (the seed's "additional covariance for
  /// registration uncertainty"): each cell takes the change of the mixture over `poses` of the
  /// other map's P(occupied) there, P_i = P(l0 + the evidence fuse(other, pose_i) resamples into
  /// the cell), a pose that puts the cell outside the other map's known cells adding the prior. Its blurring is the pose-uncertainty insertion's. One pose of weight 1 is
  /// fuse(other, pose). Throws std::invalid_argument, changing nothing, for a pose that is not
  /// rigid, weights that are not positive or do not sum to 1, threads < 1, or `other` being this map.
  InsertStats fuse(const OccupancyMap& other, const std::vector<WeightedPose>& poses, int threads = defaultThreadCount());

  /// Sets cells to absolute log-odds values (a prior, an imported grid): the cells of boxes[i]
  /// take values[i], whatever they held; other cells keep theirs. A map without leaves takes the
  /// boxes as its leaves, cut at brick borders (cell by cell where the merge policy keeps the value
  /// apart); elsewhere each touched brick is covered anew, as insertion covers it. Counts each cell
  /// in cells_occupied (a value above the prior) or cells_free. Throws std::invalid_argument,
  /// changing nothing, for an empty box, one beyond the key range, boxes that overlap, boxes
  /// spanning more than 2^26 bricks, or a value that is not finite or lies outside the clamping
  /// bounds.
  InsertStats assignCells(const Box* boxes, const float* values, std::size_t n);

  /// Insertion works in buffers that all maps of the process share through a pool: an idle one
  /// keeps the size of the largest insertion it served, and up to four are kept (one for each
  /// map inserting at the same time). This frees the idle ones.
  static void releaseInsertBuffers();

  // ---- queries ----------------------------------------------------------------------
  std::optional<float> logOdds(const Key& k) const;
  /// P(occupied); the prior for unknown cells.
  double occupancy(const Key& k) const;
  CellState state(const Key& k) const;
  /// State at a metric point; Unknown for points without a key.
  CellState stateAt(const Eigen::Vector3d& p) const;
  BoxSummary summarize(const Box& b) const;

  struct RayHit {
    bool hit = false;
    Key cell;              ///< first occupied cell along the ray
    double distance = 0;   ///< metres from the origin to where the ray enters it
  };
  /// First occupied leaf along a ray (direction need not be normalized).
  RayHit castRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double max_range) const;

  struct NearestHit {
    bool found = false;
    Box leaf;
    double distance = 0;   ///< metres from p to the closest point of the leaf
  };
  /// Nearest occupied leaf within max_distance metres.
  NearestHit nearestOccupied(const Eigen::Vector3d& p, double max_distance) const;

  /// Calls fn(box, log_odds) for every leaf.
  template <class Fn>
  void forEachLeaf(Fn&& fn) const {
    visitLeaves(nullptr, erase(fn), &callLeafVisitor<std::remove_reference_t<Fn>>);
  }
  /// Calls fn(box, log_odds) for every leaf that intersects `region`, through the R-tree: the
  /// cost follows the region, not the map.
  template <class Fn>
  void forEachLeafIn(const Box& region, Fn&& fn) const {
    visitLeaves(&region, erase(fn), &callLeafVisitor<std::remove_reference_t<Fn>>);
  }

  std::size_t leafCount() const;
  /// Cells covered by leaves (a merged cuboid counts all its cells).
  std::int64_t cellCount() const;
  /// Smallest box containing every leaf (Box::empty() if none).
  Box keyBounds() const;
  std::size_t memoryBytes() const;
  MapStatistics statistics() const;
  /// Covers the known cells again with brick-bounded cuboids, greedily as insertion does, but
  /// joining cells of one class whatever their log-odds; emit(box, state), if given, gets each
  /// cuboid. How far a map that kept only classes would shrink (greedy: not a proven minimum).
  ClassCover classCover(const std::function<void(const Box&, CellState)>& emit = {}) const;

  /// Empty if the R-tree (upper levels, leaf nodes, entries) and the brick index are sound
  /// and agree; else the first problem found.
  std::string checkInvariants() const;

  // ---- serialization (binary, little-endian, versioned; see doc/format.md) -------------
  void write(std::ostream& os) const;
  /// The bytes write() produces.
  std::uint64_t writtenSize() const;
  /// Throws std::runtime_error on a corrupt or truncated stream.
  static OccupancyMap read(std::istream& is);

 private:
  friend struct MapEngineAccess;  // the core's own code and tests (src/map/engine_access.hpp)
  using LeafVisitor = void (*)(void* fn, const Box& box, float log_odds);
  template <class Fn>
  static void callLeafVisitor(void* fn, const Box& box, float log_odds) {
    (*static_cast<Fn*>(fn))(box, log_odds);
  }
  template <class Fn>
  static void* erase(Fn& fn) {
    return const_cast<void*>(static_cast<const void*>(&fn));
  }
  /// Calls visit(fn, box, log_odds) for every leaf, or for those meeting *region.
  void visitLeaves(const Box* region, void* fn, LeafVisitor visit) const;

  std::unique_ptr<MapEngine> engine_;
};

}  // namespace rtog
