// What the camera service does with each frame, side by side: the object-frame cloud of a
// 1280 x 720 depth frame of a 0.3 m sphere 0.8 m away (the twin's camera; 2 mm voxels, ~25k
// points, as a scan's views), and the same with each point's normal from the depth image (what
// CLOUD carries since the camera sends normals).
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "core/base/pose.hpp"
#include "core/geometry/camera_model.hpp"
#include "core/perception/cloud_filter.hpp"
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

// What the registration service does with each merged view, side by side: a model of a 0.3 m
// sphere's whole surface at 2 mm (~90k points, a scan's model after a few views), and a frame
// of it from a new side merged in. By downsampling everything again (what it did) and by
// merge_into_voxels (what it does: the same result, the untouched voxels copied).
struct Merge {
  VoxelCloud model;
  PointCloud frame;
  std::vector<Eigen::Vector3f> normals;

  Merge() {
    PointCloud all;
    std::vector<Eigen::Vector3f> all_normals;
    for (int i = 0; i < 400000; ++i) {  // a Fibonacci sphere, r = 0.15 m
      const double z = 1.0 - 2.0 * (i + 0.5) / 400000.0, r = std::sqrt(1 - z * z), a = 2.399963229728653 * i;
      const Eigen::Vector3f n(static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)), static_cast<float>(z));
      all.push_back(0.15f * n);
      all_normals.push_back(n);
    }
    model.points = voxel_downsample(all, 0.002);
    model.normals = voxel_normals(all, all_normals, model.points, 0.002);
    const Frame& f = ::frame();
    const Pose turned(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()));
    frame = depth_to_object_cloud(f.depth, f.k, f.range, turned * f.object_T_camera, CloudCrop{}, 0.002, nullptr);
    normals = depth_normals(frame, f.depth, f.k, turned * f.object_T_camera);
  }
};

const Merge& merge() {
  static const Merge m;
  return m;
}

void BM_MergeByDownsamplingAgain(benchmark::State& state) {
  const Merge& m = merge();
  for (auto _ : state) {
    PointCloud all = m.model.points;
    all.insert(all.end(), m.frame.begin(), m.frame.end());
    std::vector<Eigen::Vector3f> all_normals = m.model.normals;
    all_normals.insert(all_normals.end(), m.normals.begin(), m.normals.end());
    PointCloud points = voxel_downsample(all, 0.002);
    std::vector<Eigen::Vector3f> normals = voxel_normals(all, all_normals, points, 0.002);
    benchmark::DoNotOptimize(normals.data());
    state.counters["model"] = static_cast<double>(m.model.points.size());
    state.counters["frame"] = static_cast<double>(m.frame.size());
  }
}
BENCHMARK(BM_MergeByDownsamplingAgain)->Unit(benchmark::kMillisecond);

void BM_MergeIntoVoxels(benchmark::State& state) {
  const Merge& m = merge();
  for (auto _ : state) {
    VoxelCloud model = m.model;  // the copy is part of neither's cost in the service; counted here
    merge_into_voxels(model, m.frame, m.normals, {}, 0.002);
    benchmark::DoNotOptimize(model.normals.data());
    state.counters["model"] = static_cast<double>(m.model.points.size());
    state.counters["frame"] = static_cast<double>(m.frame.size());
  }
}
BENCHMARK(BM_MergeIntoVoxels)->Unit(benchmark::kMillisecond);

}  // namespace
