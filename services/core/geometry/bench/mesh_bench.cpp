// Mesh loading/normalisation, point-to-surface distances and voxel downsampling at the sizes the
// scanner uses.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <random>
#include <string>

#include "core/geometry/point_cloud.hpp"
#include "core/geometry/mesh.hpp"
#include "core/io/mesh_file.hpp"
#include "core/perception/cloud_filter.hpp"

namespace {

using pbnbv::TriangleMesh;

// An ~80k-triangle icosphere (subdivision 6: 81,920 triangles) written once as OBJ.
const std::string& icosphere_obj() {
  static const std::string path = [] {
    const std::string p = (std::filesystem::temp_directory_path() /
                           ("pbnbv_mesh_bench_" + std::to_string(::getpid()) + ".obj"))
                              .string();
    pbnbv::write_obj(pbnbv::make_icosphere(1.0, 6), p);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove(icosphere_obj(), ec);
    });
    return p;
  }();
  return path;
}

void BM_LoadNormaliseObj(benchmark::State& state) {
  const std::string& path = icosphere_obj();
  for (auto _ : state) {
    TriangleMesh m = pbnbv::load_mesh(path);
    auto n = pbnbv::normalise_mesh(m, 0.3, pbnbv::UpAxis::kY);
    benchmark::DoNotOptimize(n);
    state.counters["triangles"] = static_cast<double>(m.triangles.size());
  }
}
BENCHMARK(BM_LoadNormaliseObj)->Unit(benchmark::kMillisecond);

// 10,000 points around the normalised (0.15 m radius) sphere, `off_m` = largest offset from the
// surface: 2 mm is a reconstruction's error, 5 cm a coarse shell (the slow case for an AABB
// tree: the query sphere runs almost parallel to the surface).
void BM_DistancesToSurface(benchmark::State& state) {
  TriangleMesh m = pbnbv::load_mesh(icosphere_obj());
  pbnbv::normalise_mesh(m, 0.3, pbnbv::UpAxis::kZ);
  const double off_m = static_cast<double>(state.range(0)) * 1e-3;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.15 - off_m, 0.15 + off_m);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 10000; ++i) {
    pts.push_back(u(rng) * Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized());
  }
  for (auto _ : state) {
    auto d = pbnbv::distances_to_surface(m, pts);  // includes building the tree
    benchmark::DoNotOptimize(d);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * 10000);
}
BENCHMARK(BM_DistancesToSurface)->ArgName("max_offset_mm")->Arg(2)->Arg(50)
    ->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_VoxelDownsample(benchmark::State& state) {
  // 900k points on and near a 0.3 m object's surface (a depth-camera scan), 2 mm voxels.
  const TriangleMesh m = pbnbv::make_icosphere(0.15, 4);
  const auto surf = pbnbv::sample_surface(m, 900000, 3);
  std::mt19937_64 rng(2);
  std::normal_distribution<double> noise(0.0, 0.001);
  pbnbv::PointCloud cloud;
  cloud.reserve(surf.size());
  for (const auto& p : surf) {
    cloud.emplace_back(static_cast<float>(p.x() + noise(rng)), static_cast<float>(p.y() + noise(rng)),
                       static_cast<float>(p.z() + noise(rng)));
  }
  size_t out = 0;
  for (auto _ : state) {
    auto d = pbnbv::voxel_downsample(cloud, 0.002);
    out = d.size();
    benchmark::DoNotOptimize(d);
  }
  state.counters["out_points"] = static_cast<double>(out);
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * 900000);
}
BENCHMARK(BM_VoxelDownsample)->Unit(benchmark::kMillisecond);

}  // namespace
