// Meshing 10 frames of a sphere (r = 0.15 m, like a default object of 0.3 m) seen from 0.6 m by
// the default camera (1280 x 720), points downsampled to 2 mm like a scan's frames: our TSDF
// fusion + marching cubes against PCL's Poisson, side by side. Figures: time per meshing, and
// the mesh's triangles and median |distance - r| (mm).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>

#include "core/perception/cloud_filter.hpp"
#include "core/surface/mesh_topology.hpp"
#include "core/surface/surface.hpp"

namespace pbnbv {
namespace {

constexpr double kRadius = 0.15;

std::vector<SurfaceFrame> sphere_frames(const CameraIntrinsics& k) {
  std::vector<SurfaceFrame> frames;
  for (int i = 0; i < 10; ++i) {
    // Ten views spread over the sphere (a spiral from below to above).
    const double z = -0.9 + 1.8 * i / 9.0, a = 2.4 * i;
    const Eigen::Vector3d eye = 0.6 * Eigen::Vector3d(std::sqrt(1 - z * z) * std::cos(a), std::sqrt(1 - z * z) * std::sin(a), z);
    SurfaceFrame f;
    f.object_T_camera = look_at_z_up(eye, Eigen::Vector3d::Zero());
    const Eigen::Vector3d c = f.object_T_camera.inverse() * Eigen::Vector3d::Zero();
    for (int v = 0; v < k.height; ++v)
      for (int u = 0; u < k.width; ++u) {
        const Eigen::Vector3d d = back_project(k, u, v, 1.0).normalized();
        const double b = d.dot(c), disc = b * b - (c.squaredNorm() - kRadius * kRadius);
        if (disc >= 0) f.points.push_back((f.object_T_camera * ((b - std::sqrt(disc)) * d)).cast<float>());
      }
    f.points = voxel_downsample(f.points, 0.002);
    frames.push_back(std::move(f));
  }
  return frames;
}

void BM_Mesh10Frames(benchmark::State& state) {
  SurfaceSettings s;
  s.method = state.range(0) == 0 ? MeshMethod::kTsdf : MeshMethod::kPoisson;
  s.point_spacing_m = 0.002;
  s.poisson_depth = 8;  // 1.2 mm cells over the sphere's 0.3 m; depth 9 takes about 4 times as long
  static const std::vector<SurfaceFrame> frames = sphere_frames(s.camera);
  TriangleMesh mesh;
  for (auto _ : state) {
    mesh = build_surface(frames, s);
    benchmark::DoNotOptimize(mesh.vertices.data());
  }
  std::vector<double> err;
  for (const auto& p : mesh.vertices) err.push_back(std::abs(p.norm() - kRadius) * 1e3);
  std::nth_element(err.begin(), err.begin() + err.size() / 2, err.end());
  state.counters["triangles"] = double(mesh.triangles.size());
  state.counters["median_err_mm"] = err[err.size() / 2];
  state.counters["watertight"] = mesh_topology(mesh).watertight ? 1 : 0;
  state.SetLabel(s.method == MeshMethod::kTsdf ? "tsdf 2 mm" : "poisson depth 8");
}
BENCHMARK(BM_Mesh10Frames)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

}  // namespace
}  // namespace pbnbv
