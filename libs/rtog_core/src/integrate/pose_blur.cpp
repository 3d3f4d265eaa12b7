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

#include "integrate/pose_blur.hpp"

#include "integrate/beam_integrator.hpp"
#include "integrate/insert_scratch.hpp"
#include "rtog/core/mixture.hpp"
#include "parallel/parallel.hpp"
#include "storage/brick.hpp"
#include "storage/map_store.hpp"

namespace rtog {
namespace {

/// One pose's updates of one brick: a finalized batch's brick or a graded scan's.
struct BrickSource {
  std::uint64_t code;  // the brick's Morton code
  std::uint32_t pose;
  std::uint32_t index;  // brick index in that pose's batch / graded scan
};

/// The mixture (ProbabilityMixture), brick by brick: per cell the sum of the poses' terms, in pose
/// order (so the sums do not depend on the thread count), in a dense brick array; cells a pose's
/// scan did not touch add nothing, which is their prior. Each touched cell is then appended to `out`
/// with its change logit(P0 + sum) - l0, bricks in Morton order as finalize() leaves them.
class Mixture {
 public:
  Mixture(const LogOddsModel& model, const std::vector<double>& weights, const InsertParams& ip)
      : model_(model), weights_(weights), ip_(ip), rule_(model.prior()) {}

  void mixBatches(const std::vector<UpdateBatch>& batches, GradedScan& out) {
    std::vector<BrickSource> sources;
    for (std::uint32_t i = 0; i < weights_.size(); ++i)
      for (std::uint32_t b = 0; b < batches[i].brickCodes().size(); ++b)
        sources.push_back(BrickSource{batches[i].brickCodes()[b], i, b});
    forEachBrick(sources, out, [&](const BrickSource& s) {
      const auto& upd = *batches[s.pose].bricks()[s.index];
      const double w = weights_[s.pose];
      addMask(upd.occupied, rule_.term(w, model_.hitDelta()));
      addMask(upd.free, rule_.term(w, model_.missDelta()));  // finalize() dropped the free marks of occupied cells
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
      // A cell in both the miss mask and the graded cells takes the larger change, as the graded applier does.
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
        sum_[static_cast<std::size_t>(i)] += rule_.term(w, delta);
        touched_[word] |= bit;
      }
      if (miss) {
        BrickMask rest;
        for (std::size_t k = 0; k < rest.size(); ++k) rest[k] = (*miss)[k] & ~own[k];
        addMask(rest, rule_.term(w, model_.missDelta()));
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
          cells_.push_back(GradedCell{static_cast<std::uint16_t>(i), ip_.graded(rule_.change(sum_[i]))});
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
  const InsertParams& ip_;  // its graded_unit
  ProbabilityMixture rule_;
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

UpdateSet PoseBlurIntegrator::trace(const WeightedScan* scans, std::size_t n, const InsertParams& ip) {
  ip.validate();
  const MapStore& store = ctx_.store;
  if (n == 0) return UpdateSet::nothing(UpdateSet::Kind::Graded, {});
  const double total = weightSum(n, [&](std::size_t i) { return scans[i].weight; });
  if (n == 1) return integrateScan(ctx_, scans[0].origin, scans[0].points, scans[0].count, ip, scans[0].is_hit);
  for (std::size_t i = 0; i < n; ++i) (void)store.lattice.key(scans[i].origin);  // throws before any change
  InsertScratch& scratch = ctx_.scratch;
  const bool graded = ip.model == SensorModel::RangeNoise;
  // One batch per pose (one more graded scan holds the mixture), traced on the insertion's
  // threads; they are mixed in pose order, so the map does not depend on the thread count.
  if (graded) {
    if (scratch.graded.size() < n + 1) scratch.graded.resize(n + 1);
  } else if (scratch.batches.size() < n) {
    scratch.batches.resize(n);
  }
  if (scratch.graded.empty()) scratch.graded.resize(1);
  std::vector<InsertStats> part(n), unused(std::min<std::size_t>(static_cast<std::size_t>(ip.threads), n));
  // InsertParams::max_scan_cells bounds each pose's batch (each a copy of the one scan): a pose
  // over it skips the scan, whatever the thread count (each pose is traced by one thread).
  const std::size_t max_bricks = maxScanBricks(ip);
  const bool traced = parallel::traceChunks(
      n, 1, unused, [](std::size_t) {},
      [&](std::size_t, std::size_t i, std::size_t, InsertStats&) {
        const WeightedScan& s = scans[i];
        if (graded) {
          GradedScan& g = scratch.graded[i];
          g.clear();
          g.traceRangeNoise(store.lattice, store.model, s.origin, s.points, s.count, ip, s.is_hit, nullptr, 0, part[i]);
          g.finalize();
          return true;
        }
        UpdateBatch& b = scratch.batches[i];
        b.clear();
        if (!BeamIntegrator::traceBeams(store.lattice, s.origin, s.points, s.count, ip, s.is_hit, b, part[i], max_bricks))
          return false;
        b.finalize();
        return !(max_bricks > 0 && b.brickCodes().size() > max_bricks);
      },
      [](std::size_t) {});
  if (!traced) {
    for (std::size_t i = 0; i < n; ++i) scratch.batches[i].clear();
    InsertStats skipped;
    skipped.skipped_over_budget = scans[0].count;
    return UpdateSet::nothing(UpdateSet::Kind::Graded, skipped);
  }
  std::vector<double> weights(n);
  for (std::size_t i = 0; i < n; ++i) weights[i] = scans[i].weight / total;
  GradedScan& out = scratch.graded[graded ? n : 0];
  out.clear();
  auto mix = std::make_unique<Mixture>(store.model, weights, ip);  // 36 KB of dense brick sums
  if (graded) {
    mix->mixGraded(scratch.graded, out);
  } else {
    mix->mixBatches(scratch.batches, out);
  }
  // The beams are those of one scan: counted once, as the first pose's trace counts them.
  UpdateSet set = UpdateSet::nothing(UpdateSet::Kind::Graded, part[0]);
  set.stats.cells_free = set.stats.cells_occupied = set.stats.cells_unchanged = 0;
  set.graded.push_back(&out);
  set.planar_ok = ip.planar_cache;
  set.threads = ip.threads;
  return set;
}

}  // namespace rtog
