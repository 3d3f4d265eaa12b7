#include "integrate/graded_scan.hpp"

#include <algorithm>
#include <cmath>

#include "integrate/beams.hpp"
#include "rtog/core/ray_traversal.hpp"
#include "storage/brick.hpp"

namespace rtog {
namespace {

// Where the line origin + t * dir (lattice units, |dir| = 1, `inv` its inverse per axis, 0 where
// the axis is not crossed) is inside cell k: [t_in, t_out].
void cellInterval(const Eigen::Vector3d& origin, const Eigen::Vector3d& inv, const Key& k, double& t_in, double& t_out) {
  t_in = 0.0;
  t_out = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (inv[a] == 0.0) continue;
    const double t1 = (double(k[a]) - origin[a]) * inv[a], t2 = t1 + inv[a];
    t_in = std::max(t_in, std::min(t1, t2));
    t_out = std::min(t_out, std::max(t1, t2));
  }
  t_out = std::max(t_out, t_in);  // a cell the walk only grazes (rounding): a point
}

}  // namespace

void GradedScan::clear() {
  miss_.clear();
  for (std::size_t i = 0; i < slot_bricks_.size(); ++i) marks_[i].clear();
  slot_bricks_.clear();
  slots_.clear();
  last_slot_ = kNoSlot;
  bricks_.clear();
  codes_.clear();
  cells_.clear();
  banded_.clear();
}

void GradedScan::enterBrick(const Key& brick) {
  const auto next = static_cast<std::uint32_t>(slot_bricks_.size());
  last_slot_ = slots_.findOrInsert(packKey(brick), next);
  last_brick_ = brick;
  if (last_slot_ != next) return;
  slot_bricks_.push_back(brick);
  if (marks_.size() < slot_bricks_.size()) marks_.emplace_back();
}

std::size_t GradedScan::memoryBytes() const {
  std::size_t marks = marks_.capacity() * sizeof(marks_[0]);
  for (const auto& m : marks_) marks += m.capacity() * sizeof(Mark);
  return miss_.memoryBytes() + slots_.memoryBytes() + banded_.capacity() + own_ends_.memoryBytes() + marks +
         slot_bricks_.capacity() * sizeof(Key) + value_.capacity() * sizeof(float) +
         order_.capacity() * sizeof(order_[0]) + bricks_.capacity() * sizeof(BrickEntry) +
         codes_.capacity() * sizeof(std::uint64_t) + cells_.capacity() * sizeof(GradedCell);
}

void GradedScan::finalize() {
  miss_.finalize();
  last_slot_ = kNoSlot;
  order_.clear();
  for (std::uint32_t s = 0; s < slot_bricks_.size(); ++s) order_.emplace_back(mortonCode(slot_bricks_[s]), s);
  std::sort(order_.begin(), order_.end());
  // The graded bricks (first), with their codes, each brick's cells by local index...
  std::vector<BrickEntry> graded;
  codes_.clear();
  cells_.clear();
  value_.resize(kBrickCells);
  BrickMask seen{};
  for (const auto& [code, slot] : order_) {
    for (const Mark& m : marks_[slot]) {
      std::uint64_t& word = seen[m.local >> 6];
      const std::uint64_t bit = std::uint64_t{1} << (m.local & 63);
      float& v = value_[m.local];
      if (!(word & bit)) {
        word |= bit;
        v = m.delta;
      } else if (m.delta > v) {
        v = m.delta;
      }
    }
    const auto first = static_cast<std::uint32_t>(cells_.size());
    for (std::size_t w = 0; w < seen.size(); ++w)
      for (std::uint64_t bits = seen[w]; bits != 0; bits &= bits - 1) {
        const auto i = static_cast<std::uint16_t>(w * 64 + static_cast<std::size_t>(__builtin_ctzll(bits)));
        cells_.push_back(GradedCell{i, value_[i]});
      }
    seen = BrickMask{};
    graded.push_back(BrickEntry{slot_bricks_[slot], code, nullptr, first, static_cast<std::uint32_t>(cells_.size()) - first});
    codes_.push_back(code);
  }
  // ...merged with the miss batch's bricks, both in Morton order.
  bricks_.clear();
  const auto& miss_codes = miss_.brickCodes();
  for (std::size_t g = 0, m = 0; g < graded.size() || m < miss_codes.size();) {
    const bool take_g = m == miss_codes.size() || (g < graded.size() && codes_[g] <= miss_codes[m]);
    const bool take_m = g == graded.size() || (m < miss_codes.size() && miss_codes[m] <= codes_[g]);
    BrickEntry e = take_g ? graded[g] : BrickEntry{miss_.brickKeys()[m], miss_codes[m], nullptr, 0, 0};
    if (take_m) e.miss = &miss_.bricks()[m]->free;
    bricks_.push_back(e);
    g += take_g;
    m += take_m;
  }
}

void SharedEnds::count(const Lattice& lattice, const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                       std::size_t n, const InsertParams& ip, const std::uint8_t* is_hit) {
  index_.clear();
  ends_.clear();
  beams_.clear();
  group_of_.clear();
  min_beams_ = ip.range_noise_shared_band;
  if (min_beams_ == 0) return;
  group_of_.resize(n, kNone);
  const BeamRules rules(lattice, ip);
  Eigen::Vector3d end;
  Key end_key;
  std::uint32_t last = kNone;
  for (std::size_t i = 0; i < n; ++i) {
    if (rules.classify(origin, points[i].cast<double>(), is_hit == nullptr || is_hit[i] != 0, end, end_key) !=
        BeamEnd::Hit)
      continue;
    // Neighbouring beams (a depth image's row) mostly end in the same cell: no lookup then.
    std::uint32_t g = last;
    if (g == kNone || ends_[g] != end_key) {
      const auto next = static_cast<std::uint32_t>(ends_.size());
      g = index_.findOrInsert(packKey(end_key), next);
      if (g == next) {
        ends_.push_back(end_key);
        beams_.push_back(0);
      }
      last = g;
    }
    ++beams_[g];
    group_of_[i] = g;
  }
}

void GradedScan::traceRangeNoise(const Lattice& lattice, const LogOddsModel& model, const Eigen::Vector3d& origin,
                                 const Eigen::Vector3f* points, std::size_t count, const InsertParams& ip,
                                 const std::uint8_t* is_hit, const SharedEnds* shared_ends, std::size_t first,
                                 InsertStats& stats) {
  const Key origin_key = lattice.key(origin);  // throws for a bad origin
  const Eigen::Vector3d origin_l = lattice.toLattice(origin);
  const BeamRules rules(lattice, ip);
  const RangeNoiseRule noise(model, ip);
  const double res = lattice.resolution();
  if (shared_ends == nullptr) {
    own_ends_.count(lattice, origin, points, count, ip, is_hit);
    shared_ends = &own_ends_;
    first = 0;
  }
  // A returned beam to `end` (lattice `end_l`, cell `end_key`, range r): the cells before its band take the
  // miss change by the fast walk (if `free`), the band's cells their own (if `band`).
  const auto traceHit = [&](const Eigen::Vector3d& end, const Eigen::Vector3d& end_l, const Key& end_key, double r,
                            bool free, bool band) {
    const double sigma = noise.sigma(r);
    const Eigen::Vector3d dir = (end - origin) / r;
    // Cells before the band's start take exactly the miss change: the fast walk up to the start's
    // cell (up to the end cell if the band starts within it), the graded walk from there.
    Eigen::Vector3d from_l = origin_l;
    Key from_key = origin_key;
    const double band_start = r - noise.reach(sigma);
    Key start_key;
    if (band_start > res && lattice.tryKey(origin + dir * band_start, start_key)) {
      from_l = lattice.toLattice(origin + dir * band_start);
      from_key = start_key;
      if (free) miss_.queueRayFree(origin_l, start_key == end_key ? end_l : from_l, origin_key, start_key);
    } else if (free && !band) {  // a band back to the origin: the shared band grades the end cell
      miss_.queueRayFree(origin_l, end_l, origin_key, end_key);
    }
    if (!band) return;
    // The walk goes on to the far edge of the band, unless that has no key or is too long.
    const Eigen::Vector3d far = origin + dir * (r + noise.reach(sigma));
    Key far_key;
    Eigen::Vector3d far_l = end_l;
    if (lattice.tryKey(far, far_key) &&
        (ip.max_ray_cells == 0 || (far - origin).norm() <= double(ip.max_ray_cells) * res)) {
      far_l = lattice.toLattice(far);
    } else {
      far_key = end_key;
    }
    if (far_key == end_key) far_l = end_l;  // the beam model's walk, exactly
    const Eigen::Vector3d dir_l = (far_l - origin_l).normalized();
    const Eigen::Vector3d inv_l(dir_l.x() != 0.0 ? 1.0 / dir_l.x() : 0.0, dir_l.y() != 0.0 ? 1.0 / dir_l.y() : 0.0,
                                dir_l.z() != 0.0 ? 1.0 / dir_l.z() : 0.0);
    // Cells before the end cell end before the reading, the end cell holds it, later cells
    // start after it, whatever the rounding of their intervals.
    bool past_end = false;
    const auto visit = [&](const Key& k) {
      double t_in, t_out;
      cellInterval(origin_l, inv_l, k, t_in, t_out);
      t_in *= res;
      t_out *= res;
      if (k == end_key) {
        past_end = true;
        t_in = std::min(t_in, r);
        t_out = std::max(t_out, r);
      } else if (!past_end) {
        t_out = std::min(t_out, r);
        t_in = std::min(t_in, t_out);
      } else {
        t_in = std::max(t_in, r);
        t_out = std::max(t_out, t_in);
      }
      float delta;
      if (noise.cellDelta(t_in, t_out, r, sigma, delta)) mark(k, delta);
    };
    traverseRay(from_l, far_l, from_key, far_key, visit);
    visit(far_key);
    // A walk that stepped around the end cell (rounding on a cell corner) still marks it.
    if (!past_end) visit(end_key);
  };
  if (banded_.size() != shared_ends->groups()) banded_.assign(shared_ends->groups(), 0);
  Eigen::Vector3d end;
  Key end_key;
  for (std::size_t i = 0; i < count; ++i) {
    // A returned beam's end cell and group were found when the scan was counted.
    const std::uint32_t g = shared_ends->group(first + i);
    BeamEnd kind = BeamEnd::Hit;
    if (g != SharedEnds::kNone) {
      end = points[i].cast<double>();
      end_key = shared_ends->end(g);
      ++stats.rays_hit;
    } else {
      kind = rules.classify(origin, points[i].cast<double>(), is_hit == nullptr || is_hit[i] != 0, end, end_key);
      if (!BeamRules::count(kind, stats)) continue;
    }
    const Eigen::Vector3d end_l = rules.walkEnd(end, end_key);
    const double r = (end - origin).norm();
    if (kind != BeamEnd::Hit || noise.sigma(r) == 0.0) {  // the beam model's marks (sigma -> 0)
      if (kind == BeamEnd::Hit) mark(end_key, model.hitDelta());
      miss_.queueRayFree(origin_l, end_l, origin_key, end_key);
      continue;
    }
    if (g == SharedEnds::kNone || !shared_ends->shared(g)) {
      traceHit(end, end_l, end_key, r, true, true);
      continue;
    }
    traceHit(end, end_l, end_key, r, true, false);
    // The shared band, once per thread: the same cells and values whichever thread traces it.
    if (banded_[g] != 0) continue;
    banded_[g] = 1;
    const Eigen::Vector3d centre = lattice.cellCenter(end_key);
    traceHit(centre, lattice.toLattice(centre), end_key, (centre - origin).norm(), false, true);
  }
}

}  // namespace rtog
