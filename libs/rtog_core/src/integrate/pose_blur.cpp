// Pose uncertainty blurred into one scan's update: the scan is traced from each pose of a
// weighted sample set by the sensor model's own rules, each cell's probabilities are mixed, and
// the mixture is entered once as a graded change (doc/pose-uncertainty.md).
#include <algorithm>
#include <array>
#include <atomic>
#include <memory>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

#include "integrate/batch_apply.hpp"
#include "integrate/scan_integrator.hpp"
#include "parallel/parallel.hpp"
#include "rtog/core/pose_blur.hpp"
#include "storage/brick.hpp"
#include "util/flat_hash_map.hpp"

namespace rtog {
namespace {

double sigmoid(double l) { return 1.0 / (1.0 + std::exp(-l)); }


/// One pose's updates of one brick: a finalized batch's brick or a graded scan's.
struct BrickSource {
  std::uint64_t code;  // the brick's Morton code
  std::uint32_t pose;
  std::uint32_t index;  // brick index in that pose's batch / graded scan
};

/// The mixture, brick by brick: per cell the weighted sum over the poses of (P_i - P0), in pose
/// order (so the sums do not depend on the thread count), in a dense brick array; cells a pose's
/// scan did not touch add nothing, which is their prior. Each touched cell is then appended to `out`
/// with its change logit(P0 + sum) - l0, bricks in Morton order as finalize() leaves them.
class Mixture {
 public:
  Mixture(const LogOddsModel& model, const std::vector<double>& weights)
      : model_(model), weights_(weights), p0_(sigmoid(model.prior())),
        hit_(sigmoid(double(model.prior()) + model.hitDelta()) - p0_),
        miss_(sigmoid(double(model.prior()) + model.missDelta()) - p0_) {}

  void mixBatches(const std::vector<UpdateBatch>& batches, GradedScan& out) {
    std::vector<BrickSource> sources;
    for (std::uint32_t i = 0; i < weights_.size(); ++i)
      for (std::uint32_t b = 0; b < batches[i].brickCodes().size(); ++b)
        sources.push_back(BrickSource{batches[i].brickCodes()[b], i, b});
    forEachBrick(sources, out, [&](const BrickSource& s) {
      const auto& upd = *batches[s.pose].bricks()[s.index];
      const double w = weights_[s.pose];
      addMask(upd.occupied, w * hit_);
      addMask(upd.free, w * miss_);  // finalize() dropped the free marks of occupied cells
      return upd.brick;
    });
  }

  void mixGraded(const std::vector<GradedScan>& scans, GradedScan& out) {
    std::vector<BrickSource> sources;
    for (std::uint32_t i = 0; i < weights_.size(); ++i)
      for (std::uint32_t b = 0; b < scans[i].brickCount(); ++b) sources.push_back(BrickSource{scans[i].brickCode(b), i, b});
    forEachBrick(sources, out, [&](const BrickSource& s) {
      const GradedScan& scan = scans[s.pose];
      const double w = weights_[s.pose];
      // A cell in both the miss mask and the graded cells takes the larger change, as applyGraded() does.
      const BrickMask* miss = scan.missMask(s.index);
      BrickMask own{};
      const GradedCell* cells = scan.cells(s.index);
      for (std::size_t c = 0; c < scan.cellCount(s.index); ++c) {
        const int i = cells[c].local;
        const std::uint64_t bit = std::uint64_t{1} << (i & 63);
        const auto word = static_cast<std::size_t>(i >> 6);
        own[word] |= bit;
        float delta = cells[c].delta;
        if (miss && ((*miss)[word] & bit)) delta = std::max(delta, model_.missDelta());
        sum_[static_cast<std::size_t>(i)] += w * (sigmoid(double(model_.prior()) + delta) - p0_);
        touched_[word] |= bit;
      }
      if (miss) {
        BrickMask rest;
        for (std::size_t k = 0; k < rest.size(); ++k) rest[k] = (*miss)[k] & ~own[k];
        addMask(rest, w * miss_);
      }
      return scan.brick(s.index);
    });
  }

 private:
  void addMask(const BrickMask& mask, double v) {
    for (std::size_t w = 0; w < mask.size(); ++w) {
      touched_[w] |= mask[w];
      for (std::uint64_t bits = mask[w]; bits != 0; bits &= bits - 1)
        sum_[w * 64 + static_cast<std::size_t>(__builtin_ctzll(bits))] += v;
    }
  }
  /// Groups `sources` by brick (Morton order, poses in order within one), has add(source) sum each
  /// into the dense brick (it returns the brick's key), then marks the brick's cells in `out`.
  template <class Add>
  void forEachBrick(std::vector<BrickSource>& sources, GradedScan& out, Add&& add) {
    std::sort(sources.begin(), sources.end(), [](const BrickSource& a, const BrickSource& b) {
      return a.code != b.code ? a.code < b.code : a.pose < b.pose;
    });
    for (std::size_t first = 0; first < sources.size();) {
      std::size_t last = first;
      Key brick{};
      for (; last < sources.size() && sources[last].code == sources[first].code; ++last) brick = add(sources[last]);
      cells_.clear();
      for (std::size_t w = 0; w < touched_.size(); ++w) {
        for (std::uint64_t bits = touched_[w]; bits != 0; bits &= bits - 1) {
          const auto i = w * 64 + static_cast<std::size_t>(__builtin_ctzll(bits));
          // P lies between the smallest and the largest P_i, all in (0, 1); the clamp only guards
          // against rounding at the ends.
          const double p = std::clamp(p0_ + sum_[i], 1e-12, 1.0 - 1e-12);
          cells_.push_back(GradedCell{static_cast<std::uint16_t>(i),
                                      static_cast<float>(std::log(p / (1.0 - p)) - double(model_.prior()))});
          sum_[i] = 0.0;
        }
        touched_[w] = 0;
      }
      out.appendBrick(brick, sources[first].code, cells_.data(), cells_.size());
      first = last;
    }
  }

  const LogOddsModel& model_;
  const std::vector<double>& weights_;
  double p0_, hit_, miss_;
  std::array<double, kBrickCells> sum_{};
  BrickMask touched_{};
  std::vector<GradedCell> cells_;  // one brick's, for out.appendBrick()
};

}  // namespace

std::vector<SigmaPoint> sigmaPoints(const Eigen::MatrixXd& cov) {
  if (cov.rows() != cov.cols() || cov.rows() == 0) throw std::invalid_argument("sigmaPoints: the covariance is not square");
  if (!cov.allFinite()) throw std::invalid_argument("sigmaPoints: the covariance is not finite");
  const double scale = std::max(1.0, cov.cwiseAbs().maxCoeff());
  if (!cov.isApprox(cov.transpose(), 1e-9) && (cov - cov.transpose()).cwiseAbs().maxCoeff() > 1e-12 * scale)
    throw std::invalid_argument("sigmaPoints: the covariance is not symmetric");
  const std::size_t n = static_cast<std::size_t>(cov.rows());
  if (cov.isZero(0.0)) return {SigmaPoint{Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n)), 1.0}};
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cov);
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  const double largest = lambda.maxCoeff();
  // Eigenvalues this far below the largest are rounding of a rank-deficient matrix (a planar
  // pose's covariance padded to six dimensions), not variance.
  const double tiny = 1e-12 * std::max(largest, 0.0);
  if (lambda.minCoeff() < -1e-9 * scale) throw std::invalid_argument("sigmaPoints: the covariance is not positive semi-definite");
  std::vector<Eigen::Index> dirs;
  for (Eigen::Index j = 0; j < lambda.size(); ++j)
    if (lambda[j] > tiny) dirs.push_back(j);
  if (dirs.empty()) return {SigmaPoint{Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n)), 1.0}};
  const double m = static_cast<double>(dirs.size());
  std::vector<SigmaPoint> out;
  for (const Eigen::Index j : dirs) {
    const Eigen::VectorXd step = std::sqrt(m * lambda[j]) * eig.eigenvectors().col(j);
    out.push_back(SigmaPoint{step, 1.0 / (2.0 * m)});
    out.push_back(SigmaPoint{-step, 1.0 / (2.0 * m)});
  }
  return out;
}

InsertStats ScanIntegrator::insertBlurred(const WeightedScan* scans, std::size_t n, const InsertParams& ip,
                                          const std::function<void()>& flush_pending) {
  ip.validate();
  if (n == 0) return {};
  double total = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!(std::isfinite(scans[i].weight) && scans[i].weight > 0.0))
      throw std::invalid_argument("insertBlurred: weight " + std::to_string(i) + " is not positive and finite");
    total += scans[i].weight;
  }
  if (!std::isfinite(total)) throw std::invalid_argument("insertBlurred: the weights' sum is not finite");
  if (n == 1) return insert(scans[0].origin, scans[0].points, scans[0].count, ip, scans[0].is_hit, flush_pending);
  for (std::size_t i = 0; i < n; ++i) (void)store_.lattice.key(scans[i].origin);  // throws before any change
  flush_pending();
  InsertScratch& scratch = scratch_;
  const bool graded = ip.model == SensorModel::RangeNoise;
  // One batch per pose (one more graded scan holds the mixture), traced on the insertion's
  // threads; they are mixed in pose order, so the map does not depend on the thread count.
  if (graded) {
    if (scratch.graded.size() < n + 1) scratch.graded.resize(n + 1);
  } else if (scratch.batches.size() < n) {
    scratch.batches.resize(n);
  }
  if (scratch.graded.empty()) scratch.graded.resize(1);
  std::vector<InsertStats> part(n);
  const std::size_t threads = std::min<std::size_t>(static_cast<std::size_t>(ip.threads), n);
  parallel::ChunkClaims claims(n, threads);
  // InsertParams::max_scan_cells bounds each pose's batch (each a copy of the one scan): a pose
  // over it skips the scan, whatever the thread count (each pose is traced by one thread).
  const std::size_t max_bricks =
      ip.max_scan_cells == 0 ? 0 : static_cast<std::size_t>(std::max<std::uint64_t>(1, ip.max_scan_cells / kBrickCells));
  std::atomic<bool> over{false};
  parallel::run(threads, [&](std::size_t t) {
    for (std::size_t i; (i = claims.next(t)) != parallel::ChunkClaims::kNone;) {
      if (over.load(std::memory_order_relaxed)) break;
      const WeightedScan& s = scans[i];
      if (graded) {
        GradedScan& g = scratch.graded[i];
        g.clear();
        g.traceRangeNoise(store_.lattice, store_.model, s.origin, s.points, s.count, ip, s.is_hit, part[i]);
        g.finalize();
      } else {
        UpdateBatch& b = scratch.batches[i];
        b.clear();
        if (!traceBeams(store_.lattice, s.origin, s.points, s.count, ip, s.is_hit, b, part[i], max_bricks)) {
          over.store(true, std::memory_order_relaxed);
          break;
        }
        b.finalize();
        if (max_bricks > 0 && b.brickCodes().size() > max_bricks) over.store(true, std::memory_order_relaxed);
      }
    }
  });
  if (over.load()) {
    for (std::size_t i = 0; i < n; ++i) scratch.batches[i].clear();
    InsertStats skipped;
    skipped.skipped_over_budget = scans[0].count;
    return skipped;
  }
  std::vector<double> weights(n);
  for (std::size_t i = 0; i < n; ++i) weights[i] = scans[i].weight / total;
  GradedScan& out = scratch.graded[graded ? n : 0];
  out.clear();
  auto mix = std::make_unique<Mixture>(store_.model, weights);  // 36 KB of dense brick sums
  if (graded) {
    mix->mixGraded(scratch.graded, out);
  } else {
    mix->mixBatches(scratch.batches, out);
  }
  // The beams are those of one scan: counted once, as the first pose's trace counts them.
  InsertStats stats = part[0];
  stats.cells_free = stats.cells_occupied = stats.cells_unchanged = 0;
  applyGraded(store_, {&out}, stats, ip.threads, scratch.apply_ctx);
  return stats;
}

}  // namespace rtog
