// What one request of the page costs the server (pbnbv view), on a scene the size of a scan's:
//   decimate   - the merged cloud (N points on a 15 cm sphere, 1 mm noise) to the page's 5 mm
//                voxels, at most 60,000 points
//   score      - F of 800 candidates for 10 ellipsoids (the page's colours; the scorer's own step
//                for comparison is in planning's benchmarks)
//   scene_json - one scene (the decimated cloud of 100,000 points, 800 candidates, 10 ellipsoids,
//                10 views) to JSON text; "bytes" is the body the page downloads
#include <benchmark/benchmark.h>

#include <random>

#include "core/view/scene.hpp"

namespace {

using namespace pbnbv;

PointCloud sphere_cloud(int n) {
  std::mt19937 rng(1);
  std::normal_distribution<float> g(0.f, 1.f);
  PointCloud c;
  c.reserve(n);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3f d(g(rng), g(rng), g(rng));
    c.push_back(d.normalized() * (0.15f + 0.001f * g(rng)));
  }
  return c;
}

std::vector<Ellipsoid> ellipsoids() {
  std::vector<Ellipsoid> out;
  for (int i = 0; i < 10; ++i) {
    Ellipsoid e;
    e.cls = i % 2 ? EllipsoidClass::kFrontier : EllipsoidClass::kOccupied;
    e.centre = Eigen::Vector3d(0.1 * std::cos(i), 0.1 * std::sin(i), 0.02 * i - 0.1);
    e.semi_axes = Eigen::Vector3d(0.08, 0.05, 0.02);
    e.axes = Eigen::AngleAxisd(0.3 * i, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    out.push_back(e);
  }
  return out;
}

const Eigen::AlignedBox3d kBox(Eigen::Vector3d::Constant(-0.2), Eigen::Vector3d::Constant(0.2));

void BM_Decimate(benchmark::State& state) {
  const PointCloud c = sphere_cloud(static_cast<int>(state.range(0)));
  std::size_t kept = 0;
  for (auto _ : state) kept = decimate_cloud(c, 0.005, 60000).size();
  state.counters["kept"] = static_cast<double>(kept);
}
BENCHMARK(BM_Decimate)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);

void BM_Score(benchmark::State& state) {
  const std::vector<Ellipsoid> e = ellipsoids();
  CandidateSpec spec;
  spec.num_views = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(score_candidates(e, kBox, spec, CameraIntrinsics{}));
}
BENCHMARK(BM_Score)->Arg(800)->Unit(benchmark::kMillisecond);

void BM_SceneJson(benchmark::State& state) {
  Scene s;
  s.cloud = decimate_cloud(sphere_cloud(100000), 0.005, 60000);
  for (const Ellipsoid& e : ellipsoids()) s.ellipsoids.push_back(ellipsoid_mesh(e));
  s.candidates = score_candidates(ellipsoids(), kBox, CandidateSpec{}, CameraIntrinsics{});
  for (int i = 0; i < 10; ++i) s.views_taken.push_back(s.candidates[i * 50].object_T_camera);
  std::size_t bytes = 0;
  for (auto _ : state) bytes = scene_json(s).dump().size();
  state.counters["points"] = static_cast<double>(s.cloud.size());
  state.counters["bytes"] = static_cast<double>(bytes);
}
BENCHMARK(BM_SceneJson)->Unit(benchmark::kMillisecond);

}  // namespace
