// A scan in one z-layer: its beams in exact planar form, marked into planar batches.
#include "integrate/planar/planar_beams.hpp"

#include <algorithm>

#include "integrate/beam_integrator.hpp"
#include "integrate/beams.hpp"
#include "integrate/insert_scratch.hpp"
#include "integrate/planar/fan_skip.hpp"
#include "parallel/parallel.hpp"
#include "storage/map_store.hpp"

namespace rtog {

bool mayBePlanar(const Lattice& lattice, const Eigen::Vector3d& origin, const PointSource& source,
                 const InsertParams& ip) {
  Key origin_key;
  if (!lattice.tryKey(origin, origin_key)) return true;  // the whole scan's path reports it
  // A volumetric scan leaves the origin's z-layer within its first beams.
  Eigen::Vector3f piece[kSourcePiece];
  const std::size_t kept = source.read(0, std::min(kSourcePiece, source.count), piece);
  const BeamRules rules(lattice, ip);
  Eigen::Vector3d end;
  Key end_key;
  for (std::size_t i = 0; i < kept; ++i) {
    const BeamEnd kind = rules.classify(origin, piece[i].cast<double>(), true, end, end_key);
    if ((kind == BeamEnd::Hit || kind == BeamEnd::Truncated) && end_key.z != origin_key.z) return false;
  }
  return true;
}

UpdateSet markPlanarBeams(const IntegrationContext& ctx, const Eigen::Vector3d& origin, std::size_t count,
                          const InsertParams& ip, const Key& lo, const Key& hi, InsertStats stats) {
  InsertScratch& scratch = ctx.scratch;
  const std::size_t threads = traceThreads(count, ip);
  if (scratch.planar_batches.size() < threads) scratch.planar_batches.resize(threads);
  std::vector<InsertStats> part(threads);
  const Key origin_key = ctx.store.lattice.key(origin);
  const BeamRules rules(ctx.store.lattice, ip);
  parallel::traceChunks(
      count, traceChunk(count, threads, ip), part, [&](std::size_t t) { scratch.planar_batches[t].reset(lo, hi); },
      [&](std::size_t t, std::size_t first, std::size_t n, InsertStats&) {
        PlanarBatch& batch = scratch.planar_batches[t];
        for (std::size_t i = first; i < first + n; ++i) {
          const PlanarBeam& beam = scratch.planar_beams[i];
          if (!beam.traced) continue;
          rules.mark(beam.hit, beam.end, batch, [&] { batch.markRayFree(beam.seg, origin_key, beam.skip_runs); });
        }
        return true;
      },
      [&](std::size_t t) { scratch.planar_batches[t].finalize(); });
  for (std::size_t t = 0; t < threads; ++t) stats += part[t];
  UpdateSet set = UpdateSet::nothing(UpdateSet::Kind::Planar, stats);
  set.planar = &scratch.planar_batches;
  set.planar_count = threads;
  set.z = lo.z;
  return set;
}

bool preparePlanarBeams(const Lattice& lattice, const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                        std::size_t count, const InsertParams& ip, const std::uint8_t* is_hit,
                        std::vector<PlanarBeam>& beams, Key& lo, Key& hi, InsertStats& stats) {
  // A planar batch of more than this many bricks (16 MiB: a scan 400 m wide at 5 cm) takes
  // the general path instead.
  constexpr std::size_t kMaxPlanarTiles = std::size_t{1} << 18;
  Key origin_key;
  if (!lattice.tryKey(origin, origin_key)) return false;
  const Eigen::Vector3d origin_l = lattice.toLattice(origin);
  lo = hi = origin_key;
  // Grown beam by beam: a volumetric scan usually leaves the layer within its first beams, and
  // sizing for all of them (a depth image: 307,200) cost more than its whole planar test.
  beams.clear();
  InsertStats counts;  // into `stats` only if the scan is planar: else the general path counts
  const BeamRules rules(lattice, ip);
  Eigen::Vector3d end;
  for (std::size_t i = 0; i < count; ++i) {
    PlanarBeam& beam = beams.emplace_back();
    const BeamEnd kind =
        rules.classify(origin, points[i].cast<double>(), is_hit == nullptr || is_hit[i] != 0, end, beam.end);
    beam.traced = false;
    beam.skip_runs = 0;
    if (kind != BeamEnd::Hit && kind != BeamEnd::Truncated) {
      BeamRules::count(kind, counts);
      continue;
    }
    if (beam.end.z != origin_key.z) return false;
    lo = Key{std::min(lo.x, beam.end.x), std::min(lo.y, beam.end.y), lo.z};
    hi = Key{std::max(hi.x, beam.end.x), std::max(hi.y, beam.end.y), hi.z};
    beam.traced = true;
    beam.hit = kind == BeamEnd::Hit;
    BeamRules::count(kind, counts);
    beam.seg = planarSegment(origin_l, rules.walkEnd(end, beam.end), origin_key, beam.end);
  }
  if (PlanarBatch::tilesFor(lo, hi) > kMaxPlanarTiles) return false;
  // A budget smaller than the batch's box: the general path counts the bricks touched.
  const std::uint64_t box_cells = std::uint64_t(PlanarBatch::tilesFor(lo, hi)) * kBrickSize * kBrickSize;
  if (ip.max_scan_cells > 0 && box_cells > ip.max_scan_cells) return false;
  // Discretized beams are traced once per end cell, which a skip could not rely on.
  if (rules.tracesFree() && !rules.discretize()) fanSkipRuns(beams.data(), count);
  stats += counts;
  return true;
}

}  // namespace rtog
