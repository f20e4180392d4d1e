// Observable coverage at the benchmark's sizes: 10,000 surface samples, 800 candidate views on a
// hemisphere (sphere_band_views, 0.6 m radius) around a 0.3 m object.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "core/geometry/mesh.hpp"
#include "core/geometry/views.hpp"
#include "core/geometry/visibility.hpp"
#include "core/base/units.hpp"

namespace {

struct Scene {
  pbnbv::TriangleMesh mesh;
  pbnbv::SurfaceSamples samples;
};

const Scene& sphere() {
  static const Scene s = [] {
    Scene sc{pbnbv::make_icosphere(0.15, 4), {}};  // 5,120 triangles
    sc.samples = pbnbv::sample_surface_with_normals(sc.mesh, 10000, 1);
    return sc;
  }();
  return s;
}

const Scene& box() {
  static const Scene s = [] {
    Scene sc{pbnbv::make_box(Eigen::Vector3d(0.3, 0.2, 0.15)), {}};
    sc.samples = pbnbv::sample_surface_with_normals(sc.mesh, 10000, 1);
    return sc;
  }();
  return s;
}

const std::vector<pbnbv::Pose>& hemisphere_views() {
  static const std::vector<pbnbv::Pose> v =
      pbnbv::sphere_band_views(800, 10, 0.6, Eigen::Vector3d::Zero(), 0.0, pbnbv::kPi / 2);
  return v;
}

void run(benchmark::State& state, const Scene& sc) {
  pbnbv::VisibilityParams p;
  p.threads = static_cast<int>(state.range(0));
  std::size_t seen = 0;
  for (auto _ : state) {
    const auto mask =
        pbnbv::visible_from_any(sc.mesh, sc.samples.points, sc.samples.normals,
                                hemisphere_views(), p);
    seen = 0;
    for (uint8_t m : mask) seen += m;
    benchmark::DoNotOptimize(seen);
  }
  state.counters["visible_pct"] = 100.0 * seen / sc.samples.points.size();
}

void BM_VisibleFromAnySphere(benchmark::State& state) { run(state, sphere()); }
BENCHMARK(BM_VisibleFromAnySphere)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)
    ->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();

void BM_VisibleFromAnyBox(benchmark::State& state) { run(state, box()); }
BENCHMARK(BM_VisibleFromAnyBox)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)
    ->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();

}  // namespace
