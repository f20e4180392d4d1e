// Loading the default object meshes (build/data/meshes: the .off set, bunny.obj, teapot.obj),
// each registered as BM_LoadMesh/<file>, the largest of them as binary STL and as a binary PLY
// mesh, and writing / reading a scan-sized point cloud (PLY).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "core/geometry/mesh.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/mesh_file.hpp"

namespace {

namespace fs = std::filesystem;

// Loads one mesh file; counters: its vertices and triangles.
void load_mesh_file(benchmark::State& state, const std::string& path) {
  pbnbv::TriangleMesh m;
  for (auto _ : state) {
    m = pbnbv::load_mesh(path);
    benchmark::DoNotOptimize(m.vertices.data());
  }
  state.counters["vertices"] = static_cast<double>(m.vertices.size());
  state.counters["triangles"] = static_cast<double>(m.triangles.size());
}

// One BM_LoadMesh/<file> per mesh of the fetched data (none if it has not been fetched).
const bool kMeshesRegistered = [] {
  const fs::path dir = fs::path(PBNBV_DATA_DIR) / "meshes";
  std::error_code ec;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".off" || ext == ".obj" || ext == ".stl" || ext == ".ply") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    benchmark::RegisterBenchmark(("BM_LoadMesh/" + f.filename().string()).c_str(), load_mesh_file,
                                 f.string())
        ->Unit(benchmark::kMillisecond);
  }
  return true;
}();

// The eval runner reads each scan's normalised mesh back as binary STL: armadillo.off (52k
// triangles) written once as binary STL and loaded.
void BM_LoadMeshBinaryStl(benchmark::State& state) {
  const fs::path off = fs::path(PBNBV_DATA_DIR) / "meshes" / "armadillo.off";
  std::error_code ec;
  if (!fs::exists(off, ec)) {
    state.SkipWithError(("no " + off.string()).c_str());
    return;
  }
  const std::string stl =
      (fs::temp_directory_path() / ("pbnbv_io_bench_" + std::to_string(::getpid()) + "_armadillo.stl")).string();
  pbnbv::write_stl_binary(pbnbv::load_mesh(off.string()), stl);
  load_mesh_file(state, stl);
  fs::remove(stl, ec);
}
BENCHMARK(BM_LoadMeshBinaryStl)->Unit(benchmark::kMillisecond);

// A scan's mesh.ply as the surface step writes it (binary little endian, float vertices, a uchar
// count and int indices per face): armadillo.off's triangles, read back by load_mesh, which walks
// every face list of the body before CGAL reads it (a list longer than the rest of the file is
// refused). The walk took a system call per value before it counted its own position.
void BM_LoadMeshBinaryPly(benchmark::State& state) {
  const fs::path off = fs::path(PBNBV_DATA_DIR) / "meshes" / "armadillo.off";
  std::error_code ec;
  if (!fs::exists(off, ec)) {
    state.SkipWithError(("no " + off.string()).c_str());
    return;
  }
  const pbnbv::TriangleMesh mesh = pbnbv::load_mesh(off.string());
  const std::string ply =
      (fs::temp_directory_path() / ("pbnbv_io_bench_" + std::to_string(::getpid()) + "_armadillo.ply")).string();
  {
    std::ofstream out(ply, std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex " << mesh.vertices.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << mesh.triangles.size()
        << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const auto& v : mesh.vertices) {
      const float xyz[3] = {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
      out.write(reinterpret_cast<const char*>(xyz), sizeof(xyz));
    }
    for (const auto& t : mesh.triangles) {
      const unsigned char n = 3;
      const int32_t idx[3] = {static_cast<int32_t>(t[0]), static_cast<int32_t>(t[1]), static_cast<int32_t>(t[2])};
      out.write(reinterpret_cast<const char*>(&n), 1);
      out.write(reinterpret_cast<const char*>(idx), sizeof(idx));
    }
  }
  load_mesh_file(state, ply);
  fs::remove(ply, ec);
}
BENCHMARK(BM_LoadMeshBinaryPly)->Unit(benchmark::kMillisecond);

// A 300k-point cloud (about what a scan accumulates), Gaussian around the origin.
const pbnbv::PointCloud& cloud() {
  static const pbnbv::PointCloud c = [] {
    std::mt19937 rng(7);
    std::normal_distribution<float> g(0.0f, 0.1f);
    pbnbv::PointCloud out;
    for (int i = 0; i < 300000; ++i) out.emplace_back(g(rng), g(rng), g(rng));
    return out;
  }();
  return c;
}

std::string temp_path(const char* name) {
  return (fs::temp_directory_path() / ("pbnbv_io_bench_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

void BM_WritePly(benchmark::State& state) {
  const std::string p = temp_path("w.ply");
  for (auto _ : state) pbnbv::write_ply(cloud(), p);
  fs::remove(p);
  state.counters["points"] = static_cast<double>(cloud().size());
}
BENCHMARK(BM_WritePly)->Unit(benchmark::kMillisecond);

void BM_ReadPly(benchmark::State& state) {
  const std::string p = temp_path("r.ply");
  pbnbv::write_ply(cloud(), p);
  for (auto _ : state) {
    pbnbv::PointCloud c = pbnbv::read_ply(p);
    benchmark::DoNotOptimize(c.data());
  }
  fs::remove(p);
  state.counters["points"] = static_cast<double>(cloud().size());
}
BENCHMARK(BM_ReadPly)->Unit(benchmark::kMillisecond);

}  // namespace
