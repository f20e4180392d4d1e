// Voxel map update time for one 1280x720 frame of a 0.3 m object (a cube, analytically
// ray-cast) with the camera 0.9 m from its centre, by resolution, with free and hidden space from
// voxels projected into the image (rays:0, the map's way) and from rays walked through B (rays:1,
// VoxelMapParams::reference_rays, the way before), both on the same map (built with the
// projection, restored with the other setting). One row per resolution, situation and method;
// the counters are the table: B's size, voxels, voxels projected or rays walked, sample / ray
// spacing, median ms.
//   first  - the first frame into an empty map (B = doubled-diagonal AABB behind the face)
//   second - an oblique frame into the map after the first (B grows to the new points and by
//            gamma around the Frontier)
//   seventh - one more frame into a map that has seen six views around the object (B is at
//            its full size, the common case during a scan)
// Time is the wall time of VoxelMap::integrate (manual time); the map is updated in place of a
// copy of the input map that keeps its working memory (as the mapping service's map does), the
// copy excluded; median_ms its median. cpu_ms is the median process CPU time of one update (both threads), a
// measure that does not depend on what else runs on the machine: on 2 idle cores the wall time
// lies between cpu_ms / 2 and cpu_ms.
#include <benchmark/benchmark.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <vector>

#include "core/mapping/voxel_map.hpp"

namespace {

using Eigen::Vector3d;
using pbnbv::CameraIntrinsics;
using pbnbv::DepthView;
using pbnbv::Pose;
using pbnbv::VoxelMap;
using pbnbv::VoxelMapParams;

constexpr double kHalf = 0.15;

double hit_cube(const Vector3d& o, const Vector3d& d) {
  double t0 = -1e300, t1 = 1e300;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-15) {
      if (std::abs(o[i]) > kHalf) return 0;
      continue;
    }
    double a = (-kHalf - o[i]) / d[i], b = (kHalf - o[i]) / d[i];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  return (t0 <= t1 && t0 > 0) ? t0 : 0;
}

struct Frame {
  Pose pose;
  std::vector<float> depth;
};

const Frame& frame(const Vector3d& eye) {
  static std::map<std::vector<double>, Frame> cache;
  const std::vector<double> key{eye.x(), eye.y(), eye.z()};
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  const CameraIntrinsics k;
  Frame f;
  f.pose = pbnbv::look_at_z_up(eye, Vector3d::Zero());
  f.depth.assign(static_cast<size_t>(k.width) * k.height, 0.0f);
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      const Vector3d d = f.pose.linear() * Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
      f.depth[static_cast<size_t>(v) * k.width + u] =
          static_cast<float>(hit_cube(f.pose.translation(), d));
    }
  return cache.emplace(key, std::move(f)).first->second;
}

pbnbv::MapUpdateResult integrate(VoxelMap& m, const Vector3d& eye) {
  const Frame& f = frame(eye);
  DepthView v;
  v.depth_m = &f.depth;
  v.object_T_camera = f.pose;
  return m.integrate(v);
}

const Vector3d kFirst(0.9, 0, 0);
const Vector3d kSecond(0.3, 0.75, 0.4);
const Vector3d kAround[] = {{-0.6, -0.2, 0.65}, {-0.9, 0.05, 0.0}, {0.1, -0.85, 0.3},
                            {0.05, 0.1, 0.9}, {0.5, -0.5, -0.5}};
const Vector3d kSeventh(-0.4, 0.6, -0.5);

// mode 0: first frame, 1: second frame, 2: seventh frame. rays: 1 = VoxelMapParams::reference_rays
// (the rays walked through B, as the map did before it projected voxels), 0 = the projection; the
// rows of the same resolution and frame compare the two in one run.
void BM_VoxelMapUpdate(benchmark::State& state) {
  VoxelMapParams p;
  p.resolution_m = state.range(0) * 1e-4;
  const int mode = static_cast<int>(state.range(1));
  VoxelMap built(p);
  if (mode >= 1) integrate(built, kFirst);
  if (mode >= 2) {
    integrate(built, kSecond);
    for (const Vector3d& e : kAround) integrate(built, e);
  }
  p.reference_rays = state.range(2) != 0;
  const VoxelMap before = VoxelMap::restore(built.serialise(), p, "the map before the frame");
  const Vector3d eye = mode == 0 ? kFirst : mode == 1 ? kSecond : kSeventh;
  frame(eye);  // render outside the timing
  VoxelMap m = before;
  integrate(m, eye);  // the map's working memory
  std::vector<double> ms, cpu_ms;
  pbnbv::MapUpdateResult r;
  auto cpu_now = [] {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
  };
  int stride = 0;
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();
  Eigen::AlignedBox3d b;
  for (auto _ : state) {
    m = before;  // the working memory stays
    const double c0 = cpu_now();
    r = integrate(m, eye);
    cpu_ms.push_back(cpu_now() - c0);
    state.SetIterationTime(r.time_s);
    ms.push_back(r.time_s * 1e3);
    stride = m.last_ray_stride_px();
    dims = m.dims();
    b = m.bounds();
  }
  std::sort(ms.begin(), ms.end());
  std::sort(cpu_ms.begin(), cpu_ms.end());
  const Vector3d size = b.sizes();
  state.counters["median_ms"] = ms[ms.size() / 2];
  state.counters["cpu_ms"] = cpu_ms[cpu_ms.size() / 2];  // both threads: load-independent
  state.counters["voxels"] = static_cast<double>(dims.prod());
  state.counters["rays"] = static_cast<double>(r.rays);
  state.counters["projected"] = static_cast<double>(r.projected);
  state.counters["stride_px"] = stride;
  char label[160];
  std::snprintf(label, sizeof(label), "%s res %.3f m: B %.2fx%.2fx%.2f m = %dx%dx%d",
                mode == 0 ? "first  " : mode == 1 ? "second " : "seventh", p.resolution_m,
                size.x(), size.y(), size.z(), dims.x(), dims.y(), dims.z());
  state.SetLabel(label);
}
BENCHMARK(BM_VoxelMapUpdate)
    ->ArgNames({"res_0.1mm", "frame", "rays"})
    ->ArgsProduct({{300, 200, 100, 50}, {0, 1, 2}, {0, 1}})
    ->Iterations(15)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
