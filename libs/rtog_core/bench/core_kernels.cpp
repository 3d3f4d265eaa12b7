// Micro-benchmarks of the core's inner loops (Google Benchmark): the exact walkers, the
// planar batch's runs, the AVX2 and AVX-512 lanes (random rays and a depth image's), the box
// cover and the layer-update kernels. Not a test: run `build/libs/rtog_core/rtog-core-micro` on
// a quiet machine to compare two builds.
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "integrate/planar/planar_batch.hpp"
#include "integrate/update_batch.hpp"
#include "kernels/layer_update.hpp"
#include "rtog/core/ray_traversal.hpp"
#include "storage/box_cover.hpp"

using namespace rtog;

namespace {

struct Ray {
  Eigen::Vector3d from, to;
  Key from_key, to_key;
};

Key floorKey(const Eigen::Vector3d& p) {
  return Key{static_cast<std::int32_t>(std::floor(p.x())), static_cast<std::int32_t>(std::floor(p.y())),
             static_cast<std::int32_t>(std::floor(p.z()))};
}

// Rays of a depth camera's reach at 5 cm: up to `reach` cells, from one origin; planar ones
// keep z.
std::vector<Ray> makeRays(std::size_t n, double reach, bool planar, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Vector3d o(0.37, 0.61, planar ? 0.5 : 0.29);
  std::vector<Ray> rays;
  while (rays.size() < n) {
    Eigen::Vector3d d(u(rng), u(rng), planar ? 0.0 : u(rng) * 0.5);
    if (d.norm() < 1e-3) continue;
    const Eigen::Vector3d e = o + d.normalized() * reach * (0.3 + 0.35 * (u(rng) + 1.0));
    rays.push_back(Ray{o, e, floorKey(o), floorKey(e)});
  }
  return rays;
}

// The rays of one depth image (640 x 480, 525 px focal length) in a room of 5 x 6 x 2.5 m, in
// cells of `cell` metres, pixel by pixel as an observation gives them: neighbouring rays have
// about the same length and pass through the same cells near the camera.
std::vector<Ray> makeDepthFrameRays(double cell) {
  const Eigen::Vector3d o = Eigen::Vector3d(0.37, 0.61, 0.29) * cell;
  std::vector<Ray> rays;
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u) {
      const Eigen::Vector3d d(1.0, -(u - 319.5) / 525.0, -(v - 239.5) / 525.0);
      double t = 5.0 + 0.3 * std::sin(0.05 * u) * std::cos(0.07 * v);  // the far wall, not flat
      if (d.y() != 0.0) t = std::min(t, (d.y() > 0 ? 3.0 : -3.0) / d.y());
      if (d.z() != 0.0) t = std::min(t, (d.z() > 0 ? 1.7 : -0.8) / d.z());
      const Eigen::Vector3d from = o / cell, to = (o + t * d) / cell;
      rays.push_back(Ray{from, to, floorKey(from), floorKey(to)});
    }
  return rays;
}

void BM_WalkRay3D(benchmark::State& state) {
  const auto rays = makeRays(4096, 80.0, false, 1);
  std::int64_t cells = 0;
  for (auto _ : state) {
    for (const Ray& r : rays) cells += traverseRay(r.from, r.to, r.from_key, r.to_key, [](const Key& k) { benchmark::DoNotOptimize(k); });
  }
  state.counters["cells/s"] = benchmark::Counter(static_cast<double>(cells), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_WalkRay3D);

// The rays queued into an update batch with `kernel` (detail::LaneKernel: 0 none, 1 AVX2,
// 2 AVX-512), walked and finalized.
void queueAndWalk(benchmark::State& state, const std::vector<Ray>& rays, std::int64_t kernel) {
  UpdateBatch batch;
  if (!batch.useLaneKernel(static_cast<detail::LaneKernel>(kernel))) {
    state.SkipWithError("this CPU does not run that lane kernel");
    return;
  }
  for (auto _ : state) {
    batch.clear();
    for (const Ray& r : rays) batch.queueRayFree(r.from, r.to, r.from_key, r.to_key);
    batch.finalize();
    benchmark::DoNotOptimize(batch.bricks().size());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(rays.size()));
}

// Argument: the lane kernel.
void BM_UpdateBatchQueuedRays(benchmark::State& state) {
  queueAndWalk(state, makeRays(4096, 80.0, false, 2), state.range(0));
}
BENCHMARK(BM_UpdateBatchQueuedRays)->Arg(0)->Arg(1)->Arg(2);

// Arguments: the lane kernel; the cell size in millimetres.
void BM_UpdateBatchDepthFrame(benchmark::State& state) {
  queueAndWalk(state, makeDepthFrameRays(static_cast<double>(state.range(1)) / 1000.0), state.range(0));
}
BENCHMARK(BM_UpdateBatchDepthFrame)->ArgsProduct({{0, 1, 2}, {50, 100}})->Unit(benchmark::kMillisecond);

void BM_PlanarBatchRuns(benchmark::State& state) {
  const auto rays = makeRays(4096, 300.0, true, 3);
  Key lo = rays[0].from_key, hi = lo;
  for (const Ray& r : rays)
    for (int a = 0; a < 2; ++a) lo[a] = std::min(lo[a], r.to_key[a]), hi[a] = std::max(hi[a], r.to_key[a]);
  std::vector<PlanarSegment> segs;
  for (const Ray& r : rays) segs.push_back(planarSegment(r.from, r.to, r.from_key, r.to_key));
  PlanarBatch batch;
  for (auto _ : state) {
    batch.reset(lo, hi);
    for (const PlanarSegment& s : segs) batch.markRayFree(s, rays[0].from_key, 0);
    batch.finalize();
    benchmark::DoNotOptimize(batch.tiles().data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(rays.size()));
}
BENCHMARK(BM_PlanarBatchRuns);

void BM_CoverGreedily(benchmark::State& state) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  BrickMask mask{};
  for (int c = 0; c < kBrickCells; ++c)  // a surface-like mask: a few thick z-layers
    if (localKey(c).z < 5 && u(rng) < 0.9) mask[static_cast<std::size_t>(c >> 6)] |= std::uint64_t{1} << (c & 63);
  std::size_t boxes = 0;
  for (auto _ : state)
    detail::coverGreedily(mask, [&](const std::uint8_t*, const std::uint8_t*, int) { ++boxes; });
  benchmark::DoNotOptimize(boxes);
}
BENCHMARK(BM_CoverGreedily);

void layerUpdate(benchmark::State& state, int which) {
  const auto kernels = detail::layerUpdateKernels();
  const detail::UpdateLayerFn kernel = kernels[static_cast<std::size_t>(which)];
  if (!kernel) {
    state.SkipWithError("this CPU lacks the kernel's instructions");
    return;
  }
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::array<float, kLayerCells> values{};
  LayerMask known{}, occupied{}, free{};
  for (int c = 0; c < kLayerCells; ++c) {
    const auto w = static_cast<std::size_t>(c >> 6);
    const std::uint64_t bit = std::uint64_t{1} << (c & 63);
    if (u(rng) < 0.05) occupied[w] |= bit;
    if (u(rng) < 0.6) free[w] |= bit;
  }
  const float deltas[4] = {0.85f, -0.4f, -2.0f, 3.5f};
  detail::LayerCounts counts;
  for (auto _ : state) {
    kernel(values.data(), known.data(), occupied.data(), free.data(), deltas, counts);
    benchmark::DoNotOptimize(values.data());
  }
  benchmark::DoNotOptimize(counts.free);
}
void BM_LayerUpdatePortable(benchmark::State& state) { layerUpdate(state, 0); }
void BM_LayerUpdateAvx2(benchmark::State& state) { layerUpdate(state, 1); }
BENCHMARK(BM_LayerUpdatePortable);
BENCHMARK(BM_LayerUpdateAvx2);

}  // namespace

BENCHMARK_MAIN();
