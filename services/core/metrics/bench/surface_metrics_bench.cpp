// What the surface metrics cost at a scan's sizes: a 100k-point cloud and a 50k-triangle mesh
// against a 50k-triangle reference (a bumpy sphere of radius 10 cm, 1,300 cm^2: 130k reference
// samples at the default 100 per cm^2). The parts side by side: building the reference (tree,
// distance hints, samples), comparing a cloud (accuracy by the tree, completeness by the k-d
// tree), comparing a mesh (sampled, then both ways by trees); and the one-shot call. Each part
// with CGAL's distance hints and the samples in the order drawn (hints:1, the method before the
// surface hints) beside the surface hints and the samples in Morton order (hints:2, the default):
// the same figures (mean_mm, F@5mm), the CPU time of every worker, and the wall time.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "core/metrics/surface_metrics.hpp"

namespace {

using pbnbv::TriangleMesh;

// A sphere of radius r with bumps of 1 cm, as a latitude-longitude grid: 125 x 200 quads, 50,000
// triangles (those at the poles have zero area and are left out of the tree: 49,600).
TriangleMesh bumpy_sphere(double r) {
  constexpr int kRows = 125, kCols = 200;
  const double pi = std::acos(-1.0);
  TriangleMesh m;
  for (int i = 0; i <= kRows; ++i) {
    const double theta = pi * i / kRows;
    for (int j = 0; j < kCols; ++j) {
      const double phi = 2 * pi * j / kCols;
      const double rr = r * (1 + 0.1 * std::sin(5 * theta) * std::sin(4 * phi));
      m.vertices.emplace_back(rr * std::sin(theta) * std::cos(phi), rr * std::sin(theta) * std::sin(phi),
                              rr * std::cos(theta));
    }
  }
  for (int i = 0; i < kRows; ++i) {
    for (int j = 0; j < kCols; ++j) {
      const int a = i * kCols + j, b = i * kCols + (j + 1) % kCols, c = a + kCols, d = b + kCols;
      m.triangles.emplace_back(a, c, b);
      m.triangles.emplace_back(b, c, d);
    }
  }
  return m;
}

const TriangleMesh& reference() {
  static const TriangleMesh m = bumpy_sphere(0.1);
  return m;
}

// 100,000 points on the reference with 1 mm Gaussian noise along each axis.
const pbnbv::PointCloud& cloud() {
  static const pbnbv::PointCloud c = [] {
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0.0, 0.001);
    pbnbv::PointCloud out;
    for (const auto& p : pbnbv::sample_surface(reference(), 100000, 3)) {
      out.emplace_back((p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng))).cast<float>());
    }
    return out;
  }();
  return c;
}

void report(benchmark::State& state, const pbnbv::SurfaceMetrics& m) {
  state.counters["mean_mm"] = m.accuracy.mean_m * 1e3;
  state.counters["F@5mm"] = m.f_score;
}

pbnbv::DistanceHints hints(const benchmark::State& state) {
  return static_cast<pbnbv::DistanceHints>(state.range(0));
}

void BM_BuildReference(benchmark::State& state) {
  for (auto _ : state) {
    pbnbv::ReferenceSurface ref(reference(), {}, hints(state));
    benchmark::DoNotOptimize(ref.samples().data());
  }
  state.counters["samples"] = static_cast<double>(pbnbv::ReferenceSurface(reference()).samples().size());
}

void BM_CompareCloud100k(benchmark::State& state) {
  const pbnbv::ReferenceSurface ref(reference(), {}, hints(state));
  pbnbv::SurfaceMetrics m;
  for (auto _ : state) m = ref.compare_cloud(cloud());
  report(state, m);
}

void BM_CompareMesh50k(benchmark::State& state) {
  const pbnbv::ReferenceSurface ref(reference(), {}, hints(state));
  const TriangleMesh model = bumpy_sphere(0.101);
  pbnbv::SurfaceMetrics m;
  for (auto _ : state) m = ref.compare_mesh(model);
  report(state, m);
}

void BM_CloudMetricsOneShot(benchmark::State& state) {
  pbnbv::SurfaceMetrics m;
  for (auto _ : state) m = pbnbv::cloud_metrics(reference(), cloud());
  report(state, m);
}

void before_and_now(benchmark::internal::Benchmark* b) {
  b->ArgName("hints")
      ->Arg(static_cast<int>(pbnbv::DistanceHints::kCgal))
      ->Arg(static_cast<int>(pbnbv::DistanceHints::kSurface));
  b->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
}

BENCHMARK(BM_BuildReference)->Apply(before_and_now);
BENCHMARK(BM_CompareCloud100k)->Apply(before_and_now);
BENCHMARK(BM_CompareMesh50k)->Apply(before_and_now);
BENCHMARK(BM_CloudMetricsOneShot)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

}  // namespace
