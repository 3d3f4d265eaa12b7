// Pose uncertainty blurred into one scan's update: the scan is traced from each pose of a
// weighted sample set by the sensor model's own rules, each cell's probabilities are mixed, and
// the mixture is entered once as a graded change (doc/pose-uncertainty.md).
#include <algorithm>
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

Key cellOf(const Key& brick_origin, int local) {
  const Key l = localKey(local);
  return Key{brick_origin.x + l.x, brick_origin.y + l.y, brick_origin.z + l.z};
}

/// Per cell, the weighted sum of (P_i - P0) over the sample set: cells a pose's scan did not
/// touch add nothing, which is their prior.
class Mixture {
 public:
  explicit Mixture(const LogOddsModel& model) : l0_(model.prior()), p0_(sigmoid(model.prior())) {}

  void add(const Key& k, double weight, float delta) {
    const auto fresh = static_cast<std::uint32_t>(keys_.size());
    const std::uint32_t at = index_.findOrInsert(packKey(k), fresh);
    if (at == fresh) {
      keys_.push_back(k);
      sums_.push_back(0.0);
    }
    sums_[at] += weight * (sigmoid(static_cast<double>(l0_) + delta) - p0_);
  }
  /// Adds the cells of a finalized batch: occupied cells take the hit change, free ones the miss.
  void addBatch(const UpdateBatch& batch, double weight, const LogOddsModel& model) {
    for (std::size_t b = 0; b < batch.bricks().size(); ++b) {
      const auto& upd = *batch.bricks()[b];
      addMask(upd.brick, upd.occupied, weight, model.hitDelta());
      addMask(upd.brick, upd.free, weight, model.missDelta());
    }
  }
  /// Adds the cells of a finalized graded scan (a cell in both its miss mask and its own cells
  /// takes the larger change, as applyGraded() does).
  void addGraded(const GradedScan& scan, double weight, const LogOddsModel& model) {
    for (std::size_t b = 0; b < scan.brickCount(); ++b) {
      const BrickMask* miss = scan.missMask(b);
      BrickMask own{};
      const GradedCell* cells = scan.cells(b);
      const Key origin = brickOrigin(scan.brick(b));
      for (std::size_t c = 0; c < scan.cellCount(b); ++c) {
        const int i = cells[c].local;
        const std::uint64_t bit = std::uint64_t{1} << (i & 63);
        own[static_cast<std::size_t>(i >> 6)] |= bit;
        float delta = cells[c].delta;
        if (miss && ((*miss)[static_cast<std::size_t>(i >> 6)] & bit)) delta = std::max(delta, model.missDelta());
        add(cellOf(origin, i), weight, delta);
      }
      if (!miss) continue;
      BrickMask rest;
      for (int w = 0; w < kBrickWords; ++w) rest[w] = (*miss)[w] & ~own[w];
      addMask(scan.brick(b), rest, weight, model.missDelta());
    }
  }
  /// Marks each cell's mixture as its change logit(P) - l0 in `out`.
  void emit(GradedScan& out) const {
    for (std::size_t i = 0; i < keys_.size(); ++i) {
      // P lies between the smallest and the largest P_i, all in (0, 1); the clamp only guards
      // against rounding at the ends.
      const double p = std::clamp(p0_ + sums_[i], 1e-12, 1.0 - 1e-12);
      out.mark(keys_[i], static_cast<float>(std::log(p / (1.0 - p)) - static_cast<double>(l0_)));
    }
  }

 private:
  void addMask(const Key& brick, const BrickMask& mask, double weight, float delta) {
    const Key origin = brickOrigin(brick);
    for (int w = 0; w < kBrickWords; ++w)
      for (std::uint64_t bits = mask[w]; bits != 0; bits &= bits - 1)
        add(cellOf(origin, w * 64 + __builtin_ctzll(bits)), weight, delta);
  }

  float l0_;
  double p0_;
  detail::FlatHashMap64 index_;
  std::vector<Key> keys_;
  std::vector<double> sums_;
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
  parallel::run(threads, [&](std::size_t t) {
    for (std::size_t i; (i = claims.next(t)) != parallel::ChunkClaims::kNone;) {
      const WeightedScan& s = scans[i];
      if (graded) {
        GradedScan& g = scratch.graded[i];
        g.clear();
        g.traceRangeNoise(store_.lattice, store_.model, s.origin, s.points, s.count, ip, s.is_hit, part[i]);
        g.finalize();
      } else {
        UpdateBatch& b = scratch.batches[i];
        b.clear();
        traceBeams(store_.lattice, s.origin, s.points, s.count, ip, s.is_hit, b, part[i]);
        b.finalize();
      }
    }
  });
  Mixture mix(store_.model);
  for (std::size_t i = 0; i < n; ++i) {
    const double w = scans[i].weight / total;
    if (graded) {
      mix.addGraded(scratch.graded[i], w, store_.model);
    } else {
      mix.addBatch(scratch.batches[i], w, store_.model);
    }
  }
  GradedScan& out = scratch.graded[graded ? n : 0];
  out.clear();
  mix.emit(out);
  out.finalize();
  // The beams are those of one scan: counted once, as the first pose's trace counts them.
  InsertStats stats = part[0];
  stats.cells_free = stats.cells_occupied = stats.cells_unchanged = 0;
  applyGraded(store_, {&out}, stats, ip.threads, scratch.apply_ctx);
  return stats;
}

}  // namespace rtog
