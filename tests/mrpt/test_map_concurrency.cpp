// Const use of one map from several threads while nothing inserts: likelihoods (each method,
// native and on the 2D view, caches cold so that the threads race to fill them) and queries
// give bit for bit what one thread gives. Run under ThreadSanitizer by .ci/tsan.
#include <gtest/gtest.h>

#include <cstring>
#include <thread>
#include <vector>

#include <mrpt/obs/CObservation2DRangeScan.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;

namespace {

constexpr int kThreads = 4;

struct Probe {
  mrpt::obs::CObservation::Ptr obs;
  mrpt::poses::CPose3D pose;
};

std::vector<PosedFrame> frames() { return loadOdometryFrames(dataset(kSena), 30); }

CRTreeOccupancyGridMap build(const std::vector<PosedFrame>& fr) {
  CRTreeOccupancyGridMap m(0.1);
  for (const auto& f : fr) f.sf->insertObservationsInto(m, f.pose);
  return m;
}

std::vector<Probe> probes(const std::vector<PosedFrame>& fr) {
  std::vector<Probe> out;
  for (std::size_t i = 0; i < fr.size(); i += 3)
    for (const double dx : {-0.2, 0.0, 0.15})
      out.push_back({fr[i].sf->getObservationByIndex(0), fr[i].pose + mrpt::poses::CPose3D(dx, 0.05, 0, 0.02, 0, 0)});
  return out;
}

/// Everything one thread reads, as raw bits, so that equality is bit for bit.
std::vector<std::uint64_t> readAll(const CRTreeOccupancyGridMap& m, const std::vector<Probe>& ps, std::size_t start) {
  std::vector<std::uint64_t> bits(ps.size() * 4);
  auto put = [&](std::size_t slot, double v) { std::memcpy(&bits[slot], &v, sizeof(v)); };
  for (std::size_t k = 0; k < ps.size(); ++k) {
    const std::size_t i = (start + k) % ps.size();  // each thread in its own order
    const auto& p = ps[i];
    put(4 * i, m.computeObservationLikelihood(*p.obs, p.pose));
    const auto ray = m.castRay({p.pose.x(), p.pose.y(), 0.05}, {1.0, 0.3, 0.0}, 20.0);
    put(4 * i + 1, ray ? *ray : -1.0);
    const auto near = m.nearestObstacleDistance({p.pose.x(), p.pose.y(), 0.05}, 3.0);
    put(4 * i + 2, near ? *near : -1.0);
    const float x = static_cast<float>(p.pose.x()), y = static_cast<float>(p.pose.y());
    put(4 * i + 3, m.squareDistanceToClosestCorrespondence(x, y));
  }
  return bits;
}

void expectThreadsAgree(CRTreeOccupancyGridMap& serial, CRTreeOccupancyGridMap& shared, const std::vector<Probe>& ps,
                        const char* what) {
  const auto want = readAll(serial, ps, 0);
  std::vector<std::vector<std::uint64_t>> got(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] { got[t] = readAll(shared, ps, static_cast<std::size_t>(t) * ps.size() / kThreads); });
  for (auto& th : threads) th.join();
  for (int t = 0; t < kThreads; ++t) EXPECT_TRUE(got[t] == want) << what << ", thread " << t;
}

}  // namespace

TEST(MapConcurrency, ConstQueriesAndLikelihoodsFromSeveralThreadsAgreeWithOne) {
  const auto fr = frames();
  const auto ps = probes(fr);
  ASSERT_GE(ps.size(), 24u);
  using M = CRTreeOccupancyGridMap;
  struct Config {
    M::TLikelihoodMethod method;
    bool on_view;
    const char* name;
  };
  for (const Config c : {Config{M::lmLikelihoodField_Thrun, false, "native likelihood field"},
                         Config{M::lmRayTracing, false, "native ray tracing"},
                         Config{M::lmLikelihoodField_Thrun, true, "likelihood field on the 2D view"},
                         Config{M::lmConsensus, true, "consensus on the 2D view"}}) {
    // A fresh map per method: planar cache pending and every cache cold when the threads start.
    M serial = build(fr), shared = build(fr);
    ASSERT_TRUE(shared.map().hasPendingCover());
    for (M* m : {&serial, &shared}) {
      m->likelihoodOptions.likelihoodMethod = c.method;
      m->likelihoodOptions.scanLikelihoodOnGridView = c.on_view;
    }
    expectThreadsAgree(serial, shared, ps, c.name);
    EXPECT_EQ(shared.map().checkInvariants(), "");
  }
}
