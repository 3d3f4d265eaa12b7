// Pose blur by moving one trace (OccupancyMap::insertBlurred with pose moves): the scan is traced
// once, from the mean pose, by the sensor model's own rules: the seed's local view V_R. Each pose
// of the sample set is a rigid move of that view, and pose i's change of a cell is the view's
// change at the cell's centre moved back by move i (the view's cell that holds that point). The
// cells are then mixed by the same rule as scans traced from each pose (mixture.hpp).
//
// Tracing costs a step per cell a beam crosses, and a dense sensor's beams cross the same cells
// many times; moving the view costs a lookup per cell and pose. The cells a move can reach are
// found forward (each view cell's centre moved, and the cells whose centres the moved cell can
// hold), then each is read backward, so a cell's value never depends on which view cell reached it.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "integrate/beam_integrator.hpp"
#include "integrate/insert_scratch.hpp"
#include "integrate/pose_blur.hpp"
#include "parallel/parallel.hpp"
#include "rtog/core/mixture.hpp"
#include "storage/brick.hpp"
#include "storage/map_store.hpp"
#include "util/chunked_vector.hpp"
#include "util/flat_hash_map.hpp"

namespace rtog {
namespace {

/// The mean trace per brick, each changed cell as its mixture term P - P0 (weight 1).
class MeanView {
 public:
  struct Brick {
    Key key;
    BrickMask graded;  // beam model: occupied cells; range noise: cells of their own change
    BrickMask miss;    // cells of exactly the miss change (not in `graded`)
    std::uint32_t first = 0;                     // graded: the brick's first term in terms_
    std::array<std::uint16_t, kBrickWords> rank{};  // graded: the brick's graded cells before each word
  };

  void fromBatch(const UpdateBatch& batch, double q_hit, double q_miss) {
    clear();
    q_hit_ = q_hit, q_miss_ = q_miss, graded_terms_ = false;
    for (const UpdateBatch::BrickUpdates* b : batch.bricks()) {
      Brick& v = add(b->brick);
      v.graded = b->occupied;
      v.miss = b->free;  // finalize() dropped the free marks of occupied cells
    }
  }
  void fromGraded(const GradedScan& scan, const ProbabilityMixture& rule, float miss_delta) {
    clear();
    q_miss_ = rule.term(1.0, miss_delta), graded_terms_ = true;
    for (std::size_t b = 0; b < scan.brickCount(); ++b) {
      Brick& v = add(scan.brick(b));
      v.first = static_cast<std::uint32_t>(terms_.size());
      const BrickMask* miss = scan.missMask(b);
      const GradedCell* cells = scan.cells(b);
      for (std::size_t c = 0; c < scan.cellCount(b); ++c) {
        const int i = cells[c].local;
        const std::uint64_t bit = std::uint64_t{1} << (i & 63);
        const auto word = static_cast<std::size_t>(i >> 6);
        v.graded[word] |= bit;
        // A cell in both takes the larger change, as the graded applier does.
        float delta = cells[c].delta;
        if (miss && ((*miss)[word] & bit)) delta = std::max(delta, miss_delta);
        terms_.push_back(rule.term(1.0, delta));
      }
      std::uint16_t before = 0;
      for (std::size_t w = 0; w < kBrickWords; ++w) {
        v.rank[w] = before;
        before = static_cast<std::uint16_t>(before + __builtin_popcountll(v.graded[w]));
        if (miss) v.miss[w] = (*miss)[w] & ~v.graded[w];
      }
    }
  }

  const std::vector<Brick>& bricks() const { return bricks_; }

  /// The term of a cell, with the last brick read kept.
  class Reader {
   public:
    explicit Reader(const MeanView& view) : view_(view) {}
    /// False if the trace did not change the cell.
    bool term(const Key& cell, double& q) {
      const Key b = brickOf(cell);
      if (brick_ == nullptr || b != brick_->key) {
        const std::uint32_t at = view_.index_.find(packKey(b));
        if (at == detail::FlatHashMap64::kAbsent) return false;
        brick_ = &view_.bricks_[at];
      }
      const int i = localIndex(cell);
      const auto word = static_cast<std::size_t>(i >> 6);
      const std::uint64_t bit = std::uint64_t{1} << (i & 63);
      if (brick_->graded[word] & bit) {
        if (!view_.graded_terms_) {
          q = view_.q_hit_;
        } else {
          const std::uint64_t below = brick_->graded[word] & (bit - 1);
          q = view_.terms_[brick_->first + brick_->rank[word] + static_cast<std::uint32_t>(__builtin_popcountll(below))];
        }
        return true;
      }
      q = view_.q_miss_;
      return (brick_->miss[word] & bit) != 0;
    }

   private:
    const MeanView& view_;
    const Brick* brick_ = nullptr;
  };

 private:
  void clear() {
    bricks_.clear();
    index_.clear();
    terms_.clear();
  }
  Brick& add(const Key& key) {
    index_.findOrInsert(packKey(key), static_cast<std::uint32_t>(bricks_.size()));
    bricks_.emplace_back();
    bricks_.back().key = key;
    return bricks_.back();
  }

  std::vector<Brick> bricks_;
  detail::FlatHashMap64 index_;  // packed brick key -> position in bricks_
  std::vector<double> terms_;
  double q_hit_ = 0.0, q_miss_ = 0.0;
  bool graded_terms_ = false;
};

/// A pose's move in lattice coordinates (a cell is a unit cube): u' = r u + t, and back.
struct LatticeMove {
  Eigen::Matrix3d r, back;
  Eigen::Vector3d t, back_t;
  double reach;  // how far past half a cell a moved cell's centre-to-face distance reaches
  double weight;
  LatticeMove(const PoseMove& m, const Lattice& lattice, double weight) : weight(weight) {
    r = m.move.linear();
    for (int a = 0; a < 3; ++a) t[a] = lattice.toLattice(m.move.translation()[a]);
    back = r.transpose();
    back_t = -(back * t);
    // A centre q is in the moved cell of centre p iff |back (q - p)|_inf < 1/2; back (q - p) differs
    // from q - p by at most |back - I|_inf |q - p|_inf, and the candidates lie within 3/2.
    reach = 1.5 * (back - Eigen::Matrix3d::Identity()).cwiseAbs().rowwise().sum().maxCoeff() + 1e-9;
  }
};

/// The cells some move can reach, per output brick: found forward from the view's cells.
class Reach {
 public:
  struct Brick {
    Key key;
    std::uint64_t code;
    BrickMask cells;
  };
  void clear() {
    bricks_.clear();
    index_.clear();
    last_ = nullptr;
  }
  /// Marks the cells whose centres the moved view cell (centre p) may hold; false if some lie
  /// beyond the key range (not marked).
  bool mark(const Eigen::Vector3d& p, double reach) {
    std::int32_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      if (!(p[a] - reach >= double(kKeyMin) && p[a] + reach < double(kKeyMax) + 1.0)) return false;
      lo[a] = floorToInt(p[a] - reach);
      hi[a] = floorToInt(p[a] + reach);
    }
    for (std::int32_t z = lo[2]; z <= hi[2]; ++z)
      for (std::int32_t y = lo[1]; y <= hi[1]; ++y)
        for (std::int32_t x = lo[0]; x <= hi[0]; ++x) {
          const Key k{x, y, z};
          const int i = localIndex(k);
          brickFor(k).cells[static_cast<std::size_t>(i >> 6)] |= std::uint64_t{1} << (i & 63);
        }
    return true;
  }
  /// The bricks in Morton order.
  std::vector<const Brick*> sorted() const {
    std::vector<const Brick*> out;
    out.reserve(bricks_.size());
    for (std::size_t i = 0; i < bricks_.size(); ++i) out.push_back(&bricks_[i]);
    std::sort(out.begin(), out.end(), [](const Brick* a, const Brick* b) { return a->code < b->code; });
    return out;
  }

 private:
  Brick& brickFor(const Key& cell) {
    const Key b = brickOf(cell);
    if (last_ == nullptr || last_->key != b) {
      const auto at = index_.findOrInsert(packKey(b), static_cast<std::uint32_t>(bricks_.size()));
      if (at == bricks_.size()) {
        Brick& fresh = bricks_.emplaceBack();
        fresh.key = b, fresh.code = mortonCode(b);
      }
      last_ = &bricks_[at];
    }
    return *last_;
  }
  detail::ChunkedVector<Brick, 256> bricks_;  // stable addresses for last_
  detail::FlatHashMap64 index_;
  Brick* last_ = nullptr;
};

/// Whether moving the mean's trace surely costs less than tracing each pose: the beams cross
/// (DDA steps) kMoveRatio times as many cells as the scan's bounding box holds, or more, so at
/// least that many times the cells the trace touches. Known before any trace; a dense scan with
/// far-flung points is traced (the exact way, not the fast one).
bool surelyDense(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count, const InsertParams& ip,
                 const Lattice& lattice) {
  double crossed = 0.0;
  Eigen::Vector3d lo = origin, hi = origin;
  for (std::size_t k = 0; k < count; ++k) {
    const Eigen::Vector3d d = points[k].cast<double>() - origin;
    if (!d.allFinite()) continue;
    const double len = d.norm();
    const double cut = ip.max_range > 0.0 && len > ip.max_range ? ip.max_range / len : 1.0;
    crossed += lattice.toLattice(d.lpNorm<1>() * cut);
    lo = lo.cwiseMin(origin + d * cut), hi = hi.cwiseMax(origin + d * cut);
  }
  double box = 1.0;
  for (int a = 0; a < 3; ++a) box *= lattice.toLattice(hi[a] - lo[a]) + 1.0;
  return crossed >= PoseBlurIntegrator::kMoveRatio * box;
}

}  // namespace

UpdateSet PoseBlurIntegrator::traceMoved(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                                         const std::uint8_t* is_hit, const PoseMove* moves, std::size_t n,
                                         const InsertParams& ip) {
  std::vector<std::vector<Eigen::Vector3f>>& moved = ctx_.scratch.moved_points;
  if (moved.size() < n) moved.resize(n);
  std::vector<WeightedScan> scans(n);
  for (std::size_t i = 0; i < n; ++i) {
    moved[i].resize(count);
    for (std::size_t k = 0; k < count; ++k) moved[i][k] = (moves[i].move * points[k].cast<double>()).cast<float>();
    scans[i] = WeightedScan{moves[i].weight, moves[i].move * origin, moved[i].data(), count, is_hit};
  }
  return trace(scans.data(), n, ip);
}

UpdateSet PoseBlurIntegrator::resample(const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                                       std::size_t count, const std::uint8_t* is_hit, const PoseMove* moves,
                                       std::size_t n, const InsertParams& ip) {
  ip.validate();
  const MapStore& store = ctx_.store;
  if (n == 0) return UpdateSet::nothing(UpdateSet::Kind::Graded, {});
  const double total = weightSum(n, [&](std::size_t i) { return moves[i].weight; });
  for (std::size_t i = 0; i < n; ++i)
    if (!moves[i].move.matrix().allFinite())
      throw std::invalid_argument("insertBlurred: move " + std::to_string(i) + " is not finite");
  // Throws before any change for an origin some pose carries beyond the keys.
  (void)store.lattice.key(origin);
  for (std::size_t i = 0; i < n; ++i) (void)store.lattice.key(moves[i].move * origin);
  // One pose: the plain update from it, bit for bit.
  if (n == 1 && moves[0].move.matrix().isIdentity(0.0)) return integrateScan(ctx_, origin, points, count, ip, is_hit);
  if (n == 1 || ip.blur_method == BlurMethod::Trace ||
      (ip.blur_method == BlurMethod::Auto && !surelyDense(origin, points, count, ip, store.lattice)))
    return traceMoved(origin, points, count, is_hit, moves, n, ip);
  InsertScratch& scratch = ctx_.scratch;
  const ProbabilityMixture rule(store.model.prior());
  const bool graded = ip.model == SensorModel::RangeNoise;
  const std::size_t threads = std::max<std::size_t>(1, static_cast<std::size_t>(ip.threads));
  if (scratch.batches.empty()) scratch.batches.resize(1);
  if (scratch.graded.size() < threads + 1) scratch.graded.resize(threads + 1);
  InsertStats stats;
  // The view: the mean's trace, as one thread traces a pose of the traced blur.
  auto view = std::make_unique<MeanView>();
  if (graded) {
    GradedScan& g = scratch.graded[threads];
    g.clear();
    g.traceRangeNoise(store.lattice, store.model, origin, points, count, ip, is_hit, nullptr, 0, stats);
    g.finalize();
    view->fromGraded(g, rule, store.model.missDelta());
  } else {
    UpdateBatch& b = scratch.batches[0];
    b.clear();
    const std::size_t max_bricks = maxScanBricks(ip);
    if (!BeamIntegrator::traceBeams(store.lattice, origin, points, count, ip, is_hit, b, stats, max_bricks) ||
        (b.finalize(), max_bricks > 0 && b.brickCodes().size() > max_bricks)) {
      b.clear();
      InsertStats skipped;
      skipped.skipped_over_budget = count;
      return UpdateSet::nothing(UpdateSet::Kind::Graded, skipped);
    }
    view->fromBatch(b, rule.term(1.0, store.model.hitDelta()), rule.term(1.0, store.model.missDelta()));
  }
  std::vector<LatticeMove> lattice_moves;
  for (std::size_t i = 0; i < n; ++i)
    lattice_moves.emplace_back(moves[i], store.lattice, moves[i].weight / total);

  // Forward: the cells each move can reach.
  Reach reach;
  std::size_t beyond = 0;
  for (const MeanView::Brick& b : view->bricks()) {
    const Eigen::Vector3d corner(double(b.key.x) * kBrickSize + 0.5, double(b.key.y) * kBrickSize + 0.5,
                                 double(b.key.z) * kBrickSize + 0.5);
    for (const LatticeMove& m : lattice_moves) {
      const Eigen::Vector3d base = m.r * corner + m.t;
      for (std::size_t w = 0; w < kBrickWords; ++w) {
        for (std::uint64_t bits = b.graded[w] | b.miss[w]; bits != 0; bits &= bits - 1) {
          const Key l = localKey(static_cast<int>(w * 64) + __builtin_ctzll(bits));
          if (!reach.mark(base + m.r * Eigen::Vector3d(l.x, l.y, l.z), m.reach)) ++beyond;
        }
      }
    }
  }
  stats.skipped_out_of_range += beyond;

  // Backward: each reachable cell reads the view under each move, in brick ranges per thread.
  const std::vector<const Reach::Brick*> out = reach.sorted();
  const std::size_t parts = std::min(threads, std::max<std::size_t>(1, out.size() / 16));
  parallel::run(parts, [&](std::size_t part) {
    GradedScan& g = scratch.graded[part];
    g.clear();
    MeanView::Reader reader(*view);
    std::vector<GradedCell> cells;
    for (std::size_t at = out.size() * part / parts; at < out.size() * (part + 1) / parts; ++at) {
      const Reach::Brick& b = *out[at];
      cells.clear();
      for (std::size_t w = 0; w < kBrickWords; ++w) {
        for (std::uint64_t bits = b.cells[w]; bits != 0; bits &= bits - 1) {
          const int i = static_cast<int>(w * 64) + __builtin_ctzll(bits);
          const Key l = localKey(i);
          const Eigen::Vector3d centre(double(b.key.x) * kBrickSize + l.x + 0.5,
                                       double(b.key.y) * kBrickSize + l.y + 0.5,
                                       double(b.key.z) * kBrickSize + l.z + 0.5);
          double sum = 0.0;
          bool said = false;
          for (const LatticeMove& m : lattice_moves) {
            const Eigen::Vector3d s = m.back * centre + m.back_t;
            // Beyond the keys (a move of thousands of kilometres) the view has nothing.
            if (!(s.cwiseAbs().maxCoeff() < double(kKeyMax))) continue;
            double q;
            if (reader.term(Key{floorToInt(s.x()), floorToInt(s.y()), floorToInt(s.z())}, q)) sum += m.weight * q, said = true;
          }
          if (said) cells.push_back(GradedCell{static_cast<std::uint16_t>(i), ip.graded(rule.change(sum))});
        }
      }
      if (!cells.empty()) g.appendBrick(b.key, b.code, cells.data(), cells.size());
    }
  });
  UpdateSet set = UpdateSet::nothing(UpdateSet::Kind::Graded, stats);
  set.stats.cells_free = set.stats.cells_occupied = set.stats.cells_unchanged = 0;
  for (std::size_t part = 0; part < parts; ++part) set.graded.push_back(&scratch.graded[part]);
  set.planar_ok = ip.planar_cache;
  set.threads = static_cast<int>(parts);
  return set;
}

}  // namespace rtog
