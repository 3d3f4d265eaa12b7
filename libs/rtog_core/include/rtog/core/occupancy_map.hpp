// The R-tree occupancy grid: a probabilistic occupancy map whose leaves are disjoint
// axis-aligned cuboids of lattice cells, each with one log-odds value. Cells exist only
// where a sensor observed; unknown space has no leaf.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rtog/core/detail/chunked_vector.hpp"
#include "rtog/core/detail/flat_hash_map.hpp"
#include "rtog/core/detail/small_vector.hpp"
#include "rtog/core/key.hpp"
#include "rtog/core/log_odds.hpp"
#include "rtog/core/rtree.hpp"
#include "rtog/core/update_batch.hpp"

namespace rtog {

/// Inverse sensor model used to turn a beam into cell updates.
enum class SensorModel {
  BeamBased,     ///< ray traced: free along the beam, occupied at its end
  BeamEndPoint,  ///< end points only
};

/// When adjacent leaves are merged into one cuboid.
enum class MergePolicy {
  Off,      ///< every leaf stays one cell
  Clamped,  ///< cells whose log-odds converged to the same clamping bound (seed §2.5.2)
  Equal,    ///< any cells with bit-identical log-odds (lossless as well; more merging)
};

const char* toString(SensorModel m);
const char* toString(MergePolicy m);
SensorModel sensorModelFromString(const std::string& s);  ///< throws std::invalid_argument
MergePolicy mergePolicyFromString(const std::string& s);  ///< throws std::invalid_argument

struct MapParams {
  double resolution = 0.05;              ///< Cell edge length [m]. (Default: 0.05)
  LogOddsParams log_odds;                ///< Sensor and clamping probabilities. (Default: OctoMap's)
  MergePolicy merge = MergePolicy::Clamped;  ///< Leaf merging. (Default: Clamped)
  RTreeParams rtree;                     ///< Node capacities of the index. (Default: 16/6)

  void validate() const;
};

/// Per-call insertion settings.
struct InsertParams {
  SensorModel model = SensorModel::BeamBased;  ///< (Default: BeamBased)
  /// Beams longer than this are cut here: free up to the cut, nothing occupied. <= 0 means
  /// unlimited. (Default: -1)
  double max_range = -1.0;
  /// Beams longer than this many cells (after the max_range cut) are skipped and counted in
  /// InsertStats::skipped_too_long: a bound on the cost of one beam, so that garbage ranges
  /// (a 100 km reading) cannot make one scan take minutes and millions of leaves. 65,536 cells
  /// are 3.3 km at 5 cm, 655 m at 1 cm. 0: no bound (the caller's call). (Default: 65536)
  std::uint32_t max_ray_cells = std::uint32_t{1} << 16;
  /// Trace each beam to the centre of its end cell and beams ending in the same cell once
  /// (OctoMap's `discretize`): much faster for dense clouds. (Default: false)
  bool discretize = false;
  /// Threads tracing beams; the map is bit-identical for any count. (Default: 1)
  int threads = 1;
  /// Scans whose origin and end cells all lie in one z-layer (2D range scans) update the log-odds
  /// of their bricks' layers in place and are covered with leaves when the map is next read,
  /// instead of reshaping leaves at every scan. The cells are the same either way. (Default: true)
  bool planar_cache = true;
};

/// What one insertion did; every input beam is counted in exactly one of the first six.
struct InsertStats {
  std::size_t rays_hit = 0;              ///< beams that marked an occupied end cell
  std::size_t rays_truncated = 0;        ///< beams cut at max_range or flagged as no-return
  std::size_t skipped_non_finite = 0;    ///< NaN/Inf end points
  std::size_t skipped_zero_length = 0;   ///< end point at the origin (no direction)
  std::size_t skipped_out_of_range = 0;  ///< end point outside the key range
  std::size_t skipped_too_long = 0;      ///< longer than InsertParams::max_ray_cells cells
  std::size_t cells_occupied = 0;        ///< distinct cells updated as occupied
  std::size_t cells_free = 0;            ///< distinct cells updated as free
  std::size_t cells_unchanged = 0;       ///< updates absorbed by clamping
  // The leaf count changes by leaves_created - leaves_merged. A brick rebuilt in one pass (many
  // updates, or the planar cache covered again) counts its new leaves as created and its old ones
  // as merged away. Scans held in the planar cache report their leaves in flush().
  std::size_t leaves_created = 0;
  std::size_t leaves_merged = 0;         ///< merges performed (each removes one leaf)
  std::size_t leaves_split = 0;          ///< merged cuboids split by disagreeing evidence

  std::size_t raysTotal() const {
    return rays_hit + rays_truncated + skipped_non_finite + skipped_zero_length + skipped_out_of_range +
           skipped_too_long;
  }
  InsertStats& operator+=(const InsertStats& o);
  bool operator==(const InsertStats& o) const;
};

/// Whole-map figures (what `rtog info` prints).
struct MapStatistics {
  std::size_t leaves = 0, occupied_leaves = 0, free_leaves = 0;
  std::int64_t cells = 0, occupied_cells = 0, free_cells = 0;
  std::size_t bricks = 0;
  int tree_height = 0;
  std::size_t tree_nodes = 0;
  std::size_t memory_bytes = 0;
  Box bounds = Box::empty();
};

/// Leaves of a cover that keeps only each cell's class (see OccupancyMap::classCover).
struct ClassCover {
  std::size_t occupied = 0, free = 0;
  std::size_t leaves() const { return occupied + free; }
};

/// Counts of cells in a box by state.
struct BoxSummary {
  std::int64_t occupied = 0, free = 0, unknown = 0;
};

class OccupancyMap {
 public:
  explicit OccupancyMap(const MapParams& params = {});
  // Copies and moves cover the source's planar cache first and leave scratch behind.
  OccupancyMap(const OccupancyMap& other);
  OccupancyMap(OccupancyMap&& other);
  OccupancyMap& operator=(const OccupancyMap& other);
  OccupancyMap& operator=(OccupancyMap&& other);
  ~OccupancyMap() = default;

  const MapParams& params() const { return params_; }
  const Lattice& lattice() const { return lattice_; }
  const LogOddsModel& logOddsModel() const { return model_; }
  double resolution() const { return lattice_.resolution(); }

  /// Removes every leaf; parameters stay.
  void clear();

  /// Covers the cells held in the planar cache (see InsertParams::planar_cache) with leaves and
  /// returns the leaf figures of that. Every reading call does this first by itself (safely from
  /// concurrent readers); calling it moves the cost to a time of your choosing.
  InsertStats flush();
  /// True while scans wait in the planar cache.
  bool hasPendingCover() const { return cover_pending_.load(std::memory_order_acquire); }

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

  /// Cells a beam steps in one z-layer, as grids raster beams in fixed point: cell k (k < count)
  /// is (((x << F) + k * dx) >> F, ((y << F) + k * dy) >> F) for F = kRunFracBits, each taking a
  /// `kind` step; then, if `end`, the cell (end_x, end_y) takes an Occupied step.
  struct StepRun {
    std::int32_t x, y, dx, dy;
    std::uint32_t count;
    StepKind kind;
    bool end;
    std::int32_t end_x, end_y;
  };
  static constexpr int kRunFracBits = 9;
  /// Calls fn(x, y, kind) for every cell of a run, in its order.
  template <class Fn>
  static void forEachRunCell(const StepRun& r, Fn&& fn) {
    std::int32_t fx = r.x * (1 << kRunFracBits), fy = r.y * (1 << kRunFracBits);
    for (std::uint32_t k = 0; k < r.count; ++k, fx += r.dx, fy += r.dy) fn(fx >> kRunFracBits, fy >> kRunFracBits, r.kind);
    if (r.end) fn(r.end_x, r.end_y, StepKind::Occupied);
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

  /// Step 1 of an insertion: traces the beams into `batch` (no change to the map). Throws
  /// std::out_of_range if the origin has no key.
  void computeUpdate(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                     const InsertParams& ip, const std::uint8_t* is_hit, UpdateBatch& batch,
                     InsertStats& stats) const;
  /// Step 2: applies a finalized batch to the tree in one sweep over its bricks, split over
  /// `threads` (the result does not depend on it).
  void applyUpdate(const UpdateBatch& batch, InsertStats& stats, int threads = 1);
  /// Step 2 for several finalized batches at once: applies their union (occupied winning over
  /// free across batches too), so that per-thread batches need no serial merge.
  void applyUpdate(const std::vector<const UpdateBatch*>& batches, InsertStats& stats, int threads = 1);
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
    ensureCovered();
    for (const Brick& b : bricks_) {
      const Key o = brickOrigin(b.brick);
      for (const LeafEntry& e : b.leaves) fn(globalBox(o, e), e.value);
    }
  }

  /// Calls fn(box, log_odds) for every leaf that intersects `region`, through the R-tree: the
  /// cost follows the region, not the map.
  template <class Fn>
  void forEachLeafIn(const Box& region, Fn&& fn) const {
    ensureCovered();
    upper_.queryBox(region, [&](Handle h, const Box&) {
      forEachInLeafNode(h, [&](const Box& b, float v) {
        if (b.intersects(region)) fn(b, v);
      });
    });
  }

  std::size_t leafCount() const {
    ensureCovered();
    return leaf_count_;
  }
  /// Cells covered by leaves (a merged cuboid counts all its cells).
  std::int64_t cellCount() const;
  /// Smallest box containing every leaf (Box::empty() if none).
  Box keyBounds() const {
    ensureCovered();
    return upper_.bounds();
  }
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
  /// Throws std::runtime_error on a corrupt or truncated stream.
  static OccupancyMap read(std::istream& is);

 private:
  // The R-tree's leaf level is clustered by brick: a brick's cuboids (in Morton order of their
  // first cell when loaded; later updates append and fill holes from the end) are cut into
  // leaf nodes of at most M consecutive entries. The levels
  // above are a Guttman R-tree over the leaf nodes' boxes. A brick's array is thus the storage
  // of its leaf nodes, and the brick hash finds a cell's leaf without descending the tree.
  struct LeafEntry {
    std::uint8_t lo[3], hi[3];  // brick-local cells, inclusive
    float value;                // log-odds
  };
  struct LeafNodeRef {
    std::uint32_t brick;  // slot in bricks_
    std::uint32_t node;   // leaf node index within the brick
  };
  struct Brick {
    Key brick;
    std::vector<LeafEntry> leaves;
    detail::SmallVector<Handle, 4> nodes;  // upper-tree handle of each leaf node
  };
  static constexpr std::uint8_t kDead = 0xFF;

  static Box globalBox(const Key& brick_origin, const LeafEntry& e) {
    return Box{Key{brick_origin.x + e.lo[0], brick_origin.y + e.lo[1], brick_origin.z + e.lo[2]},
               Key{brick_origin.x + e.hi[0], brick_origin.y + e.hi[1], brick_origin.z + e.hi[2]}};
  }
  std::uint32_t brickSlot(const Key& brick);
  const Brick* findBrick(const Key& brick) const;
  const LeafEntry* findLeaf(const Key& k) const;
  std::size_t leafNodeSize() const { return params_.rtree.max_entries; }
  Box leafNodeBox(const Brick& b, std::size_t node) const;
  /// The union of a leaf node's entries in brick-local cells (value unused).
  LeafEntry localNodeBox(const std::vector<LeafEntry>& leaves, std::size_t node) const;
  bool mergeable(float v) const;
  /// Per-thread state of applyUpdate().
  struct alignas(64) ApplyContext {
    std::vector<std::int32_t> local;  // brick-local cell -> leaf index, -1 when none
    std::vector<std::uint32_t> candidates;
    std::vector<std::uint32_t> reshaped;  // bricks whose leaf nodes changed
    UpdateBatch::BrickUpdates merged;     // union of one brick's updates from several batches
    std::vector<float> values;            // brick-local cell -> log-odds, for rebuildBrick()
    std::vector<LeafEntry> rebuilt;
    // The reshaped bricks' leaf-node boxes (brick-local; value unused), taken while their leaves
    // are in the cache: a rebuild of the upper tree reads them instead of every leaf again.
    std::vector<LeafEntry> node_boxes;
    std::vector<std::uint32_t> reshaped_boxes;  // first of each reshaped brick's boxes
    std::int64_t leaf_delta = 0;
    InsertStats stats;
  };
  /// Buffers of one insertion: per-thread update batches and apply contexts, a planar scan's
  /// beams and batches. A map holds them only while it inserts: they come from a process-wide
  /// pool and go back to it, so maps do not each keep buffers the size of their largest scan
  /// (a particle filter keeps a map per particle; one VLP-16 scan's batch is 20 MB), and a new
  /// map starts with buffers already faulted in.
  struct InsertScratch {
    std::vector<UpdateBatch> batches;  // per thread
    std::vector<ApplyContext> apply_ctx;
    std::vector<PlanarBatch> planar_batches;  // per thread
    std::vector<PlanarBeam> planar_beams;
  };
  struct ScratchPool;
  /// Holds scratch_ for its lifetime, from the pool unless an enclosing scope holds it already.
  class ScratchScope {
   public:
    explicit ScratchScope(OccupancyMap& map);
    ~ScratchScope();
    ScratchScope(const ScratchScope&) = delete;
    ScratchScope& operator=(const ScratchScope&) = delete;

   private:
    OccupancyMap& map_;
    bool owner_;
  };
  void applyBrick(const UpdateBatch::BrickUpdates& upd, std::uint32_t slot, ApplyContext& ctx);
  /// applyBrick()'s way for a brick without leaves under equal-value merging: each class of
  /// fresh cells has one value, so the greedy cover of each class's mask gives the leaves, the
  /// same boxes as rebuildBrick()'s cover (which never joins cells of different values).
  void coverFreshBrick(const UpdateBatch::BrickUpdates& upd, std::uint32_t slot, ApplyContext& ctx);
  /// applyBrick()'s way for a brick with many updates: values into a dense table, updated
  /// there, and the brick covered anew with boxes of equal (mergeable) value. Costs O(4096)
  /// instead of a split and merges per updated cell.
  void rebuildBrick(const UpdateBatch::BrickUpdates& upd, std::uint32_t slot, ApplyContext& ctx);
  std::size_t mergeInBrick(std::vector<LeafEntry>& leaves, std::vector<std::int32_t>& local,
                           const std::vector<std::uint32_t>& candidates) const;
  /// Rewrites a brick's leaves in Morton order of their first cell from the painted scratch
  /// table, dropping leaves merged away.
  void packLeaves(std::uint32_t slot);
  /// Brings the brick's leaf nodes in the upper tree up to date with its leaves.
  void syncLeafNodes(std::uint32_t slot);
  /// Packs every brick's leaf nodes into a fresh upper tree (Morton-order bulk load); the boxes
  /// of bricks the contexts reshaped come from them.
  void rebuildUpperTree(int threads = 1, const ApplyContext* contexts = nullptr, std::size_t context_count = 0);
  /// Brings the upper tree up to date with the leaf nodes of reshaped_bricks_ (sorted).
  void refreshUpperTree(int threads = 1, const ApplyContext* contexts = nullptr, std::size_t context_count = 0);
  /// Records a brick applyBrick() reshaped, with its leaf-node boxes.
  void noteReshaped(std::uint32_t slot, ApplyContext& ctx) const;
  /// The bricks of several finalized batches in groups of one brick, published as they come.
  struct BrickGroups;
  /// Fills `groups` in brick order, each group's brick found or made (its slot), publishing
  /// the groups done every few: appliers take them while the rest are grouped.
  void groupByBrick(const std::vector<const UpdateBatch*>& batches, BrickGroups& groups);
  /// The union of a group's updates (occupied winning), in `scratch` if there are several.
  static const UpdateBatch::BrickUpdates* unionOf(const UpdateBatch::BrickUpdates* const* sources, std::size_t n,
                                                  UpdateBatch::BrickUpdates& scratch);

  // Planar cache: one z-layer of a brick as a dense table of log-odds, updated in place by
  // planar scans, until coverPlanarLayers() turns the brick's layers into leaves again. Costs
  // O(updated cells) per scan instead of O(leaves in the touched bricks).
  struct PlanarLayer {
    std::uint32_t slot;  // brick
    int z;               // brick-local z of the layer
    std::array<std::uint64_t, kLayerWords> known;
    std::array<float, kLayerCells> value;  // the prior where unknown
  };
  /// True if every traced beam of the scan stays in the origin's z-layer and the scan is not too
  /// wide for a planar batch: then the beams in exact planar form, with the runs each can skip
  /// (fanSkipRuns), are in scratch_->planar_beams, [lo, hi] bounds their cells in x and y, and `stats`
  /// counts them.
  bool preparePlanarBeams(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                          const InsertParams& ip, const std::uint8_t* is_hit, Key& lo, Key& hi, InsertStats& stats);
  void traceBeams(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                  const InsertParams& ip, const std::uint8_t* is_hit, UpdateBatch& batch, InsertStats& stats) const;
  /// Applies the union of scratch_->planar_batches[0 .. batches) of a scan in z-layer `z` to the cache.
  void applyPlanar(std::size_t batches, int z, InsertStats& stats);
  /// The index in planar_layers_ of brick `slot`'s layer z, made from its leaves if new.
  std::uint32_t planarLayer(std::uint32_t slot, int z);
  InsertStats coverPlanarLayers();
  /// Readers call this first: covers pending planar layers once, under a lock. Sound on a const
  /// object: layers come only from insertion, and copies and moves are made covered.
  void ensureCovered() const {
    if (cover_pending_.load(std::memory_order_acquire)) const_cast<OccupancyMap*>(this)->flush();
  }
  /// The assignments' common part: `other` covered, its leaves and index copied or moved.
  template <class Other>
  void assignCovered(Other&& other);

  /// Visits the leaf entries of one upper-tree item.
  template <class Fn>
  void forEachInLeafNode(Handle h, Fn&& fn) const {
    const LeafNodeRef r = upper_.payload(h);
    const Brick& b = bricks_[r.brick];
    const Key o = brickOrigin(b.brick);
    const std::size_t first = r.node * leafNodeSize(), last = std::min(b.leaves.size(), first + leafNodeSize());
    for (std::size_t i = first; i < last; ++i) fn(globalBox(o, b.leaves[i]), b.leaves[i].value);
  }

  MapParams params_;
  Lattice lattice_;
  LogOddsModel model_;
  RTree<LeafNodeRef> upper_;
  detail::FlatHashMap64 brick_index_;
  std::vector<Brick> bricks_;
  std::size_t leaf_count_ = 0;
  std::vector<std::int32_t> local_;  // scratch: brick-local cell -> leaf index, -1 when none
  std::vector<LeafEntry> pack_scratch_;
  std::unique_ptr<InsertScratch> scratch_;  // while inserting (ScratchScope)
  std::vector<std::uint32_t> reshaped_bricks_;  // bricks whose leaf nodes changed in this batch
  detail::ChunkedVector<PlanarLayer, 64> planar_layers_;
  detail::FlatHashMap64 planar_index_;  // brick slot * kBrickSize + z -> index in planar_layers_
  detail::RecentLookups<10> recent_layers_;  // packKey(brick x, y, cell z) -> planar_layers_ index
  std::mutex cover_mutex_;
  std::atomic<bool> cover_pending_{false};
};

}  // namespace rtog
