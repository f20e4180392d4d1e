// Depth render time (mjv_updateScene + mjr_render + depth read-back + linearisation) for
//   - a floor plane and a sphere, and
//   - a floor plane and a generated geodesic-sphere mesh (20 * f^2 triangles, f = 50: 50,000;
//     f = 64: 81,920),
// at 1280x720 and 640x480, seen from 1 m above. Reported as real (wall-clock) ms per frame:
// llvmpipe rasterises on worker threads, so the calling thread's CPU time would undercount.
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "twin/depth_renderer.hpp"

namespace {

namespace fs = std::filesystem;
using pbnbv::CameraIntrinsics;
using pbnbv::DepthRange;
using pbnbv::twin::DepthImage;
using pbnbv::twin::DepthRenderer;
using pbnbv::twin::EglContext;

EglContext& egl() {
  static EglContext context;
  return context;
}

fs::path temp_dir() {
  static const fs::path dir = [] {
    fs::path d = fs::temp_directory_path() / ("pbnbv_render_bench_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

// Geodesic sphere: each icosahedron face split into f^2 triangles, vertices pushed to the unit
// sphere, written as binary STL with outward (counter-clockwise) faces. Returns the face count.
std::size_t write_geodesic_sphere_stl(const fs::path& path, int f, double radius) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  const std::array<Eigen::Vector3d, 12> ico = {
      Eigen::Vector3d(-1, t, 0), Eigen::Vector3d(1, t, 0),   Eigen::Vector3d(-1, -t, 0),
      Eigen::Vector3d(1, -t, 0), Eigen::Vector3d(0, -1, t),  Eigen::Vector3d(0, 1, t),
      Eigen::Vector3d(0, -1, -t), Eigen::Vector3d(0, 1, -t), Eigen::Vector3d(t, 0, -1),
      Eigen::Vector3d(t, 0, 1),  Eigen::Vector3d(-t, 0, -1), Eigen::Vector3d(-t, 0, 1)};
  const int faces[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  std::vector<std::array<Eigen::Vector3f, 3>> tris;
  tris.reserve(20u * f * f);
  for (const auto& face : faces) {
    Eigen::Vector3d a = ico[face[0]], b = ico[face[1]], c = ico[face[2]];
    if ((b - a).cross(c - a).dot(a + b + c) < 0) std::swap(b, c);  // make it outward
    auto p = [&](int i, int j) -> Eigen::Vector3f {
      const Eigen::Vector3d q = a + (b - a) * (double(i) / f) + (c - a) * (double(j) / f);
      return (radius * q.normalized()).cast<float>();
    };
    for (int i = 0; i < f; ++i) {
      for (int j = 0; i + j < f; ++j) {
        tris.push_back({p(i, j), p(i + 1, j), p(i, j + 1)});
        if (i + j < f - 1) tris.push_back({p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)});
      }
    }
  }
  std::ofstream out(path, std::ios::binary);
  char header[80] = "pbnbv geodesic sphere";
  out.write(header, sizeof(header));
  const std::uint32_t n = static_cast<std::uint32_t>(tris.size());
  out.write(reinterpret_cast<const char*>(&n), sizeof(n));
  for (const auto& tri : tris) {
    const Eigen::Vector3f normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalized();
    out.write(reinterpret_cast<const char*>(normal.data()), 12);
    for (const auto& v : tri) out.write(reinterpret_cast<const char*>(v.data()), 12);
    const std::uint16_t attr = 0;
    out.write(reinterpret_cast<const char*>(&attr), sizeof(attr));
  }
  if (!out) throw std::runtime_error("could not write " + path.string());
  return tris.size();
}

struct Scene {
  mjModel* model = nullptr;
  mjData* data = nullptr;
  explicit Scene(const std::string& xml) {
    const fs::path path = temp_dir() / "scene.xml";
    {
      std::ofstream out(path);
      out << xml;
    }
    char error[1000] = "";
    model = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
    if (!model) throw std::runtime_error(std::string("mj_loadXML: ") + error);
    data = mj_makeData(model);
    mj_forward(model, data);
  }
  ~Scene() {
    mj_deleteData(data);
    mj_deleteModel(model);
  }
};

// Camera 1 m above the floor looking straight down (optical z = world -z).
std::string scene_xml(const std::string& assets, const std::string& object) {
  return "<mujoco>\n" + assets +
         "  <worldbody>\n"
         "    <light pos=\"0 0 3\" dir=\"0 0 -1\"/>\n"
         "    <geom name=\"floor\" type=\"plane\" size=\"0 0 0.1\"/>\n" +
         object +
         "    <body name=\"camera_body\" pos=\"0 0 1\" quat=\"0 1 0 0\">\n"
         "      <camera name=\"depth\" quat=\"0 1 0 0\"/>\n"
         "    </body>\n"
         "  </worldbody>\n</mujoco>\n";
}

std::string sphere_scene() {
  return scene_xml("", "    <geom type=\"sphere\" size=\"0.15\" pos=\"0 0 0.15\"/>\n");
}

std::string mesh_scene(int f, std::size_t* faces) {
  const fs::path stl = temp_dir() / ("geodesic_" + std::to_string(f) + ".stl");
  *faces = write_geodesic_sphere_stl(stl, f, 0.15);
  return scene_xml("  <asset><mesh name=\"ball\" file=\"" + stl.string() + "\"/></asset>\n",
                   "    <geom type=\"mesh\" mesh=\"ball\" pos=\"0 0 0.15\" contype=\"0\" "
                   "conaffinity=\"0\"/>\n");
}

// The benchmark's image size (its two arguments), the twin's camera scaled to it.
CameraIntrinsics intrinsics_of(const benchmark::State& state) {
  CameraIntrinsics k;
  k.width = static_cast<int>(state.range(0));
  k.height = static_cast<int>(state.range(1));
  k.fx = k.fy = k.width == 1280 ? 696.0 : 696.0 * 640.0 / 1280.0;
  k.cx = k.width / 2.0;
  k.cy = k.height / 2.0;
  return k;
}

void run(benchmark::State& state, const std::string& xml, std::size_t faces) {
  egl();
  Scene scene(xml);
  const CameraIntrinsics k = intrinsics_of(state);
  DepthRenderer renderer(scene.model, "depth", k, DepthRange{});
  DepthImage img = renderer.render(scene.data);  // warm-up
  const float centre = img.at(k.width / 2, k.height / 2);
  for (auto _ : state) {
    img = renderer.render(scene.data);
    benchmark::DoNotOptimize(img.depth_m.data());
  }
  state.counters["centre_depth_m"] = centre;
  if (faces) state.counters["triangles"] = static_cast<double>(faces);
  state.SetLabel(std::to_string(k.width) + "x" + std::to_string(k.height));
}

void BM_PlaneAndSphere(benchmark::State& state) { run(state, sphere_scene(), 0); }

void BM_Mesh50k(benchmark::State& state) {
  std::size_t faces = 0;
  const std::string xml = mesh_scene(50, &faces);
  run(state, xml, faces);
}

void BM_Mesh82k(benchmark::State& state) {
  std::size_t faces = 0;
  const std::string xml = mesh_scene(64, &faces);
  run(state, xml, faces);
}

// The colour image the twin renders with each depth image (lit, the geoms' colours), on the same
// scene: what colour adds to a frame's render, beside BM_Mesh82k's depth alone.
void BM_Mesh82kColour(benchmark::State& state) {
  std::size_t faces = 0;
  const std::string xml = mesh_scene(64, &faces);
  egl();
  Scene scene(xml);
  const CameraIntrinsics k = intrinsics_of(state);
  DepthRenderer renderer(scene.model, "depth", k, DepthRange{});
  std::vector<uint8_t> rgb = renderer.render_colour(scene.data, k, pbnbv::Pose::Identity());  // warm-up
  for (auto _ : state) {
    rgb = renderer.render_colour(scene.data, k, pbnbv::Pose::Identity());
    benchmark::DoNotOptimize(rgb.data());
  }
  state.counters["triangles"] = static_cast<double>(faces);
  state.SetLabel(std::to_string(k.width) + "x" + std::to_string(k.height));
}

#define PBNBV_SIZES ->Args({1280, 720})->Args({640, 480})->Unit(benchmark::kMillisecond)->UseRealTime()
BENCHMARK(BM_PlaneAndSphere) PBNBV_SIZES;
BENCHMARK(BM_Mesh50k) PBNBV_SIZES;
BENCHMARK(BM_Mesh82k) PBNBV_SIZES;
BENCHMARK(BM_Mesh82kColour) PBNBV_SIZES;

}  // namespace
