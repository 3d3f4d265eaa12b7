#include "grid_graded.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <utility>

namespace rtog::mrpt_grid {
namespace {

/// Cell i of the 2D grid's raster `r` (past its end cell for i > count), false outside the grid.
bool rasterCell(const OccupancyMap::StepRun& r, std::uint32_t i, const TGridFrame2D& f, Key& k) {
  constexpr int F = OccupancyMap::kRunFracBits;
  k = Key{static_cast<std::int32_t>((std::int64_t{r.x} * (1 << F) + std::int64_t{i} * r.dx) >> F),
          static_cast<std::int32_t>((std::int64_t{r.y} * (1 << F) + std::int64_t{i} * r.dy) >> F), f.layer};
  return static_cast<std::uint32_t>(k.x - keyOffsetX(f)) < f.size_x && static_cast<std::uint32_t>(k.y - keyOffsetY(f)) < f.size_y;
}

/// One pose's beams as steps to out.push_back(CellStep), beam by beam in the grid's order: each
/// run's cells, then its end cell; a hit beam with range noise by gradeBeam().
template <class Out>
void poseSteps(const std::vector<OccupancyMap::StepRun>& runs, const std::vector<float>& ranges,
               const RangeNoiseRule* noise, const Steps& whole, const TGridFrame2D& f, Out& out) {
  const std::int32_t z = f.layer;
  for (std::size_t j = 0; j < runs.size(); ++j) {
    const OccupancyMap::StepRun& r = runs[j];
    const double R = ranges[j];
    const double sigma = noise && r.end && r.count > 0 ? noise->sigma(R) : 0.0;
    if (!(sigma > 0.0)) {
      OccupancyMap::forEachRunCell(r, [&](std::int32_t x, std::int32_t y, StepKind k) {
        const int size = k == StepKind::Occupied ? whole.occupied : k == StepKind::Free ? whole.free : whole.noecho;
        out.push_back(CellStep{Key{x, y, z}, k, static_cast<std::uint8_t>(size)});
      });
      continue;
    }
    const Key end{r.end_x, r.end_y, z};
    gradeBeam(*noise, R, sigma, r.count, &end, whole, [&](std::uint32_t i, Key& k) { return rasterCell(r, i, f, k); }, out);
  }
}

/// `plain` (the grid's runs, in order) with the grid's rule, then `band` (single cells' graded
/// steps) grouped by kind and size, a pass each, through the planar cache; `update`, if given,
/// receives every run applied and the value after each step, in that order.
InsertStats applyGrouped(OccupancyMap& map, std::int32_t layer, const std::vector<OccupancyMap::StepRun>& plain,
                         std::vector<CellStep> band, const Steps& whole, CRTreeOccupancyGridMap::GridScanUpdate* update) {
  std::vector<float> after;
  const auto apply = [&](const std::vector<OccupancyMap::StepRun>& runs, const StepRule& rule) {
    const InsertStats s = map.applyStepRuns(layer, runs.data(), runs.size(), rule, update ? &after : nullptr);
    if (update) {
      update->runs.insert(update->runs.end(), runs.begin(), runs.end());
      update->after.insert(update->after.end(), after.begin(), after.end());
    }
    return s;
  };
  if (update) update->runs.clear(), update->after.clear();
  const StepRule grid_rule = stepRule(whole);
  InsertStats stats = apply(plain, grid_rule);
  // By kind and size, each group in its order (a counting sort: sizes are bytes).
  {
    const auto slot = [](const CellStep& c) { return static_cast<std::size_t>(c.kind) * 256 + c.size; };
    std::vector<std::uint32_t> start(3 * 256 + 1, 0);
    for (const CellStep& c : band) ++start[slot(c) + 1];
    for (std::size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
    std::vector<CellStep> sorted(band.size());
    for (const CellStep& c : band) sorted[start[slot(c)]++] = c;
    band.swap(sorted);
  }
  std::vector<OccupancyMap::StepRun> group;
  for (std::size_t first = 0; first < band.size();) {
    std::size_t last = first;
    group.clear();
    for (; last < band.size() && band[last].kind == band[first].kind && band[last].size == band[first].size; ++last) {
      OccupancyMap::StepRun s{};
      s.x = band[last].key.x, s.y = band[last].key.y;
      s.kind = band[last].kind;
      s.count = s.kind == StepKind::Occupied ? 0 : 1;
      s.end = s.kind == StepKind::Occupied;
      s.end_x = s.x, s.end_y = s.y;
      group.push_back(s);
    }
    StepRule rule = grid_rule;
    const auto i = static_cast<std::size_t>(band[first].kind);
    const int size = band[first].size;
    rule.delta[i] = valueOfCell(band[first].kind == StepKind::Occupied ? -size : size);
    rule.limit[i] = stepLimit(band[first].kind, size, whole);
    stats += apply(group, rule);
    first = last;
  }
  return stats;
}

/// One pose's beams through the planar cache, as the grid's own scans go (OccupancyMap::applyStepRuns):
/// a beam whose steps are all the grid's (no range noise, or a band within its end cell) as the
/// grid's run, in the grid's order; of a beam with graded steps, the free cells before its band
/// with those runs, and its band's cells after them, grouped by kind and size (each group one
/// pass: a cell in several beams' bands takes their graded steps in that order).
InsertStats stepThroughCache(OccupancyMap& map, const std::vector<OccupancyMap::StepRun>& runs,
                             const std::vector<float>& ranges, const RangeNoiseRule* noise, const Steps& whole,
                             const TGridFrame2D& f, CRTreeOccupancyGridMap::GridScanUpdate* update) {
  const std::int32_t z = f.layer;
  std::vector<OccupancyMap::StepRun> plain;
  std::vector<CellStep> tail, band;
  plain.reserve(runs.size());
  for (std::size_t j = 0; j < runs.size(); ++j) {
    const OccupancyMap::StepRun& r = runs[j];
    const double R = ranges[j];
    const double sigma = noise && r.end && r.count > 0 ? noise->sigma(R) : 0.0;
    if (!(sigma > 0.0)) {
      plain.push_back(r);
      continue;
    }
    const std::uint32_t prefix = bandStart(*noise, R, sigma, r.count);
    const Key end{r.end_x, r.end_y, z};
    tail.clear();
    gradeBeam(*noise, R, sigma, r.count, &end, whole, [&](std::uint32_t i, Key& k) { return rasterCell(r, i, f, k); },
              tail, prefix);
    // The grid's own run: the rest of its free cells and its end cell, each with its whole step.
    std::size_t whole_free = 0;
    while (whole_free < tail.size() && tail[whole_free].kind == StepKind::Free && tail[whole_free].size == whole.free)
      ++whole_free;
    const bool grids = whole_free == r.count - prefix && tail.size() == whole_free + 1 &&
                       tail.back().kind == StepKind::Occupied && tail.back().size == whole.occupied;
    if (grids) {
      plain.push_back(r);
      continue;
    }
    if (prefix + whole_free > 0) {
      OccupancyMap::StepRun head = r;
      head.count = prefix + static_cast<std::uint32_t>(std::min<std::size_t>(whole_free, r.count - prefix));
      head.end = false;
      plain.push_back(head);
    }
    band.insert(band.end(), tail.begin() + static_cast<std::ptrdiff_t>(std::min<std::size_t>(whole_free, r.count - prefix)),
                tail.end());
  }
  return applyGrouped(map, f.layer, plain, std::move(band), whole, update);
}

}  // namespace

PoseMixture::PoseMixture(float prior, const Box* box)
    : mix_(prior), unit_term_(2 * kUnits + 1, std::numeric_limits<double>::quiet_NaN()) {
  // No cell lies within a block of this one's (keys are within kKeyMin..kKeyMax).
  none_.first = Key{std::numeric_limits<std::int32_t>::min() / 2, std::numeric_limits<std::int32_t>::min() / 2,
                    std::numeric_limits<std::int32_t>::min() / 2};
  if (box && !box->isEmpty()) {
    const auto block = [](const Key& k) {
      return Key{static_cast<std::int32_t>(static_cast<std::uint32_t>(k.x - kKeyMin) >> 4),
                 static_cast<std::int32_t>(static_cast<std::uint32_t>(k.y - kKeyMin) >> 4), k.z - kKeyMin};
    };
    const Key lo = block(box->min), hi = block(box->max);
    const auto w = static_cast<std::uint64_t>(hi.x - lo.x + 1), h = static_cast<std::uint64_t>(hi.y - lo.y + 1),
               d = static_cast<std::uint64_t>(hi.z - lo.z + 1);
    if (w * h * d <= kTableBlocks) {
      table_.assign(static_cast<std::size_t>(w * h * d), 0);
      table_lo_ = lo;
      table_w_ = static_cast<std::uint32_t>(w), table_h_ = static_cast<std::uint32_t>(h),
      table_d_ = static_cast<std::uint32_t>(d);
    }
  }
}

PoseMixture::~PoseMixture() {
  // Back to the pool as a new block: sums 0, no bits, no stamp (`now` is reset by `mine` on use).
  std::vector<std::unique_ptr<Block>>& spare = pool();
  for (std::unique_ptr<Block>& b : blocks_) {
    if (spare.size() >= kPoolBlocks) break;
    for (std::size_t w = 0; w < b->touched.size(); ++w)
      for (std::uint64_t bits = b->touched[w]; bits != 0; bits &= bits - 1)
        b->sum[w * 64 + static_cast<std::size_t>(__builtin_ctzll(bits))] = 0.0;
    b->touched = {}, b->mine = {}, b->stamp = 0;
    spare.push_back(std::move(b));
  }
}

std::vector<std::unique_ptr<PoseMixture::Block>>& PoseMixture::pool() {
  thread_local std::vector<std::unique_ptr<Block>> spare;
  return spare;
}

double PoseMixture::fillTerm(std::size_t i) {
  return unit_term_[i] = mix_.term(1.0, valueOfCell(static_cast<int>(i) - kUnits));
}

void PoseMixture::enter(const Key& k) {
  const auto bx = static_cast<std::uint32_t>(k.x - kKeyMin) >> 4, by = static_cast<std::uint32_t>(k.y - kKeyMin) >> 4,
             bz = static_cast<std::uint32_t>(k.z - kKeyMin);
  const auto next = static_cast<std::uint32_t>(blocks_.size());
  std::uint32_t at;
  const auto tx = bx - static_cast<std::uint32_t>(table_lo_.x), ty = by - static_cast<std::uint32_t>(table_lo_.y),
             tz = bz - static_cast<std::uint32_t>(table_lo_.z);
  if (tx < table_w_ && ty < table_h_ && tz < table_d_) {
    std::uint32_t& slot = table_[(std::size_t{tz} * table_h_ + ty) * table_w_ + tx];
    if (slot == 0) slot = next + 1;
    at = slot - 1;
  } else {
    at = index_.findOrInsert(std::uint64_t{bx} | std::uint64_t{by} << 21 | std::uint64_t{bz} << 42, next);
  }
  if (at == next) {
    std::vector<std::unique_ptr<Block>>& spare = pool();
    if (spare.empty()) {
      blocks_.push_back(std::make_unique<Block>());
    } else {
      blocks_.push_back(std::move(spare.back()));
      spare.pop_back();
    }
    blocks_.back()->first = Key{static_cast<std::int32_t>(bx << 4) + kKeyMin, static_cast<std::int32_t>(by << 4) + kKeyMin,
                                static_cast<std::int32_t>(bz) + kKeyMin};
  }
  at_ = blocks_[at].get();
  if (at_->stamp != stamp_) at_->stamp = stamp_, pose_blocks_.push_back(at);
}

void PoseMixture::beginPose() {
  ++stamp_;
  pose_blocks_.clear();
  at_ = &none_;
}

void PoseMixture::endPose(double weight) {
  for (const std::uint32_t at : pose_blocks_) {
    Block& b = *blocks_[at];
    for (std::size_t w = 0; w < b.mine.size(); ++w) {
      for (std::uint64_t bits = b.mine[w]; bits != 0; bits &= bits - 1) {
        const std::size_t c = w * 64 + static_cast<std::size_t>(__builtin_ctzll(bits));
        b.sum[c] += weight * unitTerm(b.now[c]);
      }
      b.touched[w] |= b.mine[w];
      b.mine[w] = 0;
    }
  }
  at_ = &none_;
}

void PoseMixture::steps(std::vector<CellStep>& out) const {
  for (const std::unique_ptr<Block>& block : blocks_) {
    const Block& b = *block;
    for (std::size_t w = 0; w < b.touched.size(); ++w)
      for (std::uint64_t bits = b.touched[w]; bits != 0; bits &= bits - 1) {
        const auto c = static_cast<int>(w * 64) + __builtin_ctzll(bits);
        const auto [kind, size] = gradedStep(mix_.change(b.sum[static_cast<std::size_t>(c)]));
        if (size > 0)
          out.push_back(CellStep{Key{b.first.x + (c & 15), b.first.y + (c >> 4), b.first.z}, kind,
                                 static_cast<std::uint8_t>(std::min(size, 254))});
      }
  }
}

void applyInOrder(ScanCells& cells, const Key& offset, const std::vector<CellStep>& steps, const Steps& whole) {
  for (const CellStep& c : steps) {
    std::int8_t& v = cells.at(c.key.x - offset.x, c.key.y - offset.y, c.key.z - offset.z);
    v = stepCell(v, c.kind, c.size, whole);
  }
}

bool insertGradedScan(OccupancyMap& map, TGridFrame2D& frame, const mrpt::obs::CObservation2DRangeScan& scan,
                      const std::vector<pose_sigma::SigmaPose>& poses, const CRTreeOccupancyGridMap::TInsertionOptions& io,
                      CRTreeOccupancyGridMap::GridScanUpdate* update, InsertStats& stats, std::size_t& invalid) {
  std::optional<RangeNoiseRule> noise;
  if (sensorModelFromString(io.sensorModel) == SensorModel::RangeNoise) noise.emplace(map.logOddsModel(), io.toInsertParams());
  const RangeNoiseRule* rule = noise ? &*noise : nullptr;
  // Every pose planned on the grid as it grows (a throw leaves map and geometry as they were),
  // then traced on the grown grid.
  TGridFrame2D grown = frame;
  std::vector<std::optional<ScanPlan>> plans(poses.size());
  double mean_z = 0.0, min_z = std::numeric_limits<double>::infinity(), max_z = -min_z;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    ScanPlan plan;
    if (!planScan(scan, poses[i].pose, io, grown, plan)) continue;  // this pose says nothing of any cell
    resize(grown, plan.grow[0], plan.grow[1], plan.grow[2], plan.grow[3]);
    plans[i] = std::move(plan);
    const double z = (poses[i].pose + scan.sensorPose).z();
    mean_z += poses[i].weight * z;
    min_z = std::min(min_z, z), max_z = std::max(max_z, z);
  }
  if (std::none_of(plans.begin(), plans.end(), [](const auto& p) { return p.has_value(); })) return false;
  if (!grown.has_layer) {
    Key k;
    // Poses at one height (a planar covariance) take that height itself: the weighted sum of equal
    // heights may round to the layer below when the sensor sits on a cell face, and the plain
    // scan's layer is the height's.
    const double z = min_z == max_z ? min_z : mean_z;
    if (!map.lattice().tryKey(Eigen::Vector3d(0, 0, z), k))
      throw std::out_of_range("rtog::CRTreeOccupancyGridMap: a 2D scan's height has no key");
    grown.has_layer = true;
    grown.layer = k.z;
  }
  const Steps whole = stepsOf(io);
  stats = InsertStats{};
  if (poses.size() == 1) {  // the grid's own store: its planar cache
    std::vector<OccupancyMap::StepRun> runs;
    std::vector<float> ranges;
    traceScan(scan, *plans[0], io, grown, runs, stats, &ranges, map.region());
    stats += stepThroughCache(map, runs, ranges, rule, whole, grown, update);
    if (update) std::copy(std::begin(plans[0]->grow), std::end(plans[0]->grow), update->grow);
  } else {  // several poses: their mixture, each cell one graded step
    bool counted = false;
    std::vector<OccupancyMap::StepRun> runs;
    std::vector<float> ranges;
    std::vector<CellStep> steps;
    const Box grid{Key{keyOffsetX(grown), keyOffsetY(grown), grown.layer},
                   Key{keyOffsetX(grown) + static_cast<std::int32_t>(grown.size_x) - 1,
                       keyOffsetY(grown) + static_cast<std::int32_t>(grown.size_y) - 1, grown.layer}};
    PoseMixture mixture(map.logOddsModel().prior(), &grid);
    for (std::size_t i = 0; i < poses.size(); ++i) {
      if (!plans[i]) continue;
      InsertStats pose_stats;
      traceScan(scan, *plans[i], io, grown, runs, pose_stats, &ranges, map.region());
      if (!counted) stats = pose_stats, counted = true;
      mixture.add(poses[i].weight, [&](auto& sink) { poseSteps(runs, ranges, rule, whole, grown, sink); });
    }
    steps.clear();
    mixture.steps(steps);
    stats += applyGrouped(map, grown.layer, {}, std::move(steps), whole, update);
    if (update) update->grow[0] = grown.x_min, update->grow[1] = grown.x_max, update->grow[2] = grown.y_min,
                update->grow[3] = grown.y_max;
  }
  frame = grown;
  invalid = invalidNotFree(scan, io);
  return true;
}

}  // namespace rtog::mrpt_grid
