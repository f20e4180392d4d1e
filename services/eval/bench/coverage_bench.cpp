// Coverage evaluation at the paper's sizes: 10,000 samples on a 0.3 m object, a 100k-point scan,
// 5 mm radius. Each benchmark runs 9 repetitions and reports mean/median/stddev.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "eval/coverage.hpp"
#include "core/geometry/mesh.hpp"

namespace {

const pbnbv::TriangleMesh& sphere() {
  static const pbnbv::TriangleMesh m = pbnbv::make_icosphere(0.15, 4);  // 5,120 triangles
  return m;
}

// 100k points on the sphere with 1 mm noise, like a registered scan.
const std::vector<Eigen::Vector3d>& scan() {
  static const std::vector<Eigen::Vector3d> c = [] {
    auto pts = pbnbv::sample_surface(sphere(), 100000, 2);
    std::mt19937_64 rng(5);
    std::normal_distribution<double> noise(0.0, 0.001);
    for (auto& p : pts) p += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    return pts;
  }();
  return c;
}

// Constructor: 10k samples from the mesh and the grid over them.
void BM_CoverageConstruct(benchmark::State& state) {
  for (auto _ : state) {
    pbnbv::CoverageEvaluator ev(sphere());
    benchmark::DoNotOptimize(ev);
  }
}
BENCHMARK(BM_CoverageConstruct)->Unit(benchmark::kMillisecond)->Repetitions(9)
    ->ReportAggregatesOnly(true);

// add() of the 100k-point scan on a fresh evaluator (nothing covered yet).
void BM_CoverageAddFresh(benchmark::State& state) {
  const pbnbv::CoverageEvaluator base(sphere());
  double pct = 0;
  for (auto _ : state) {
    state.PauseTiming();
    pbnbv::CoverageEvaluator ev = base;
    state.ResumeTiming();
    pct = ev.add(scan());
    benchmark::DoNotOptimize(pct);
  }
  state.counters["coverage_pct"] = pct;
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * 100000);
}
BENCHMARK(BM_CoverageAddFresh)->Unit(benchmark::kMillisecond)->Repetitions(9)
    ->ReportAggregatesOnly(true);

// add() of the same scan again: every sample is covered, the later-views case.
void BM_CoverageAddCovered(benchmark::State& state) {
  pbnbv::CoverageEvaluator ev(sphere());
  ev.add(scan());
  for (auto _ : state) benchmark::DoNotOptimize(ev.add(scan()));
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * 100000);
}
BENCHMARK(BM_CoverageAddCovered)->Unit(benchmark::kMillisecond)->Repetitions(9)
    ->ReportAggregatesOnly(true);

}  // namespace
