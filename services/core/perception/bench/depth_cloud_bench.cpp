// What the camera service does with each frame, side by side: the object-frame cloud of a
// 1280 x 720 depth frame of a 0.3 m sphere 0.8 m away (the twin's camera; 2 mm voxels, ~25k
// points, as a scan's views), and the same with each point's normal from the depth image (what
// CLOUD carries since the camera sends normals).
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "core/base/pose.hpp"
#include "core/geometry/camera_model.hpp"
#include "core/perception/depth_cloud.hpp"

namespace {

using namespace pbnbv;

struct Frame {
  CameraIntrinsics k{1280, 720, 696, 696, 640, 360};
  DepthRange range{0.1, 3.0};
  Pose object_T_camera = look_at_z_up(Eigen::Vector3d(0.8, 0, 0), Eigen::Vector3d::Zero());
  std::vector<float> depth;

  // Planar depth of a sphere of radius 0.15 m at the origin, seen from object_T_camera.
  Frame() {
    depth.assign(static_cast<std::size_t>(k.width) * k.height, 0.0f);
    const Eigen::Vector3d c = object_T_camera.inverse() * Eigen::Vector3d::Zero();  // centre, camera frame
    for (int v = 0; v < k.height; ++v) {
      for (int u = 0; u < k.width; ++u) {
        const Eigen::Vector3d d = Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
        const double a = d.squaredNorm(), b = -2 * d.dot(c), cc = c.squaredNorm() - 0.15 * 0.15;
        const double disc = b * b - 4 * a * cc;
        if (disc < 0) continue;
        depth[static_cast<std::size_t>(v) * k.width + u] = static_cast<float>((-b - std::sqrt(disc)) / (2 * a));
      }
    }
  }
};

const Frame& frame() {
  static const Frame f;
  return f;
}

void BM_CloudOfAFrame(benchmark::State& state) {
  const Frame& f = frame();
  for (auto _ : state) {
    PointCloud c = depth_to_object_cloud(f.depth, f.k, f.range, f.object_T_camera, CloudCrop{}, 0.002, nullptr);
    benchmark::DoNotOptimize(c.data());
    state.counters["points"] = static_cast<double>(c.size());
  }
}
BENCHMARK(BM_CloudOfAFrame)->Unit(benchmark::kMillisecond);

void BM_CloudOfAFrameWithNormals(benchmark::State& state) {
  const Frame& f = frame();
  for (auto _ : state) {
    PointCloud c = depth_to_object_cloud(f.depth, f.k, f.range, f.object_T_camera, CloudCrop{}, 0.002, nullptr);
    std::vector<Eigen::Vector3f> n = depth_normals(c, f.depth, f.k, f.object_T_camera);
    benchmark::DoNotOptimize(n.data());
    state.counters["points"] = static_cast<double>(c.size());
  }
}
BENCHMARK(BM_CloudOfAFrameWithNormals)->Unit(benchmark::kMillisecond);

}  // namespace
