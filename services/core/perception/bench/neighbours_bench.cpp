// The nearest-neighbour queries and normals of registration at its sizes: a model of ~60k
// points (a 0.28 m sphere and box sampled and downsampled to 2 mm, as register_frame does) and
// a frame of ~20k points (one side of it) 5 mm off.
//   BM_BuildIndex         - the k-d tree over the model
//   BM_NearestWithin20mm  - every frame point's nearest model point within 20 mm (ICP's
//                           correspondences at the coarsest stage)
//   BM_Knn12              - every model point's 12 nearest (the normals' neighbourhoods)
//   BM_Normals            - normals of the model (k = 12), on the cores the policy allows
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "core/geometry/mesh.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/perception/cloud_filter.hpp"
#include "core/perception/neighbours.hpp"

namespace {

using pbnbv::PointCloud;

struct Clouds {
  PointCloud model, frame;
};

// Surface samples with 0.3 mm noise, downsampled to 2 mm.
PointCloud sampled(const pbnbv::TriangleMesh& m, std::size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 0.0003);
  PointCloud out;
  for (const auto& p : pbnbv::sample_surface(m, n, seed)) {
    out.push_back((p + Eigen::Vector3d(g(rng), g(rng), g(rng))).cast<float>());
  }
  return pbnbv::voxel_downsample(out, 0.002);
}

const Clouds& clouds() {
  static const Clouds c = [] {
    pbnbv::TriangleMesh m = pbnbv::make_icosphere(0.1, 4);
    const pbnbv::TriangleMesh box = pbnbv::make_box(Eigen::Vector3d(0.28, 0.17, 0.06));
    const int base = static_cast<int>(m.vertices.size());
    for (const auto& v : box.vertices) m.vertices.push_back(v + Eigen::Vector3d(0, 0, -0.12));
    for (const auto& t : box.triangles) m.triangles.push_back(t + Eigen::Vector3i::Constant(base));
    Clouds out;
    out.model = sampled(m, 600000, 1);
    for (const auto& p : sampled(m, 600000, 2)) {
      if (p.x() + 0.5f * p.y() > 0.02f) out.frame.push_back(p + Eigen::Vector3f(0.003f, -0.004f, 0.0f));
    }
    return out;
  }();
  return c;
}

void BM_BuildIndex(benchmark::State& state) {
  const Clouds& c = clouds();
  for (auto _ : state) {
    pbnbv::NeighbourIndex index(c.model);
    benchmark::DoNotOptimize(index.size());
  }
  state.counters["points"] = static_cast<double>(c.model.size());
}
BENCHMARK(BM_BuildIndex)->Unit(benchmark::kMillisecond);

void BM_NearestWithin20mm(benchmark::State& state) {
  const Clouds& c = clouds();
  const pbnbv::NeighbourIndex index(c.model);
  std::size_t found = 0;
  for (auto _ : state) {
    found = 0;
    float d2;
    for (const auto& p : c.frame) found += index.nearest(p, 0.02f * 0.02f, d2) >= 0;
    benchmark::DoNotOptimize(found);
  }
  state.counters["queries"] = static_cast<double>(c.frame.size());
  state.counters["found"] = static_cast<double>(found);
}
BENCHMARK(BM_NearestWithin20mm)->Unit(benchmark::kMillisecond);

void BM_Knn12(benchmark::State& state) {
  const Clouds& c = clouds();
  const pbnbv::NeighbourIndex index(c.model);
  std::vector<int> nn;
  std::vector<float> d2;
  for (auto _ : state) {
    for (const auto& p : c.model) index.knn(p, 12, nn, d2);
    benchmark::DoNotOptimize(nn.data());
  }
  state.counters["queries"] = static_cast<double>(c.model.size());
}
BENCHMARK(BM_Knn12)->Unit(benchmark::kMillisecond);

void BM_Normals(benchmark::State& state) {
  const Clouds& c = clouds();
  std::size_t valid = 0;
  for (auto _ : state) {
    const pbnbv::SurfaceNormals n = pbnbv::estimate_normals(c.model, 12);
    valid = 0;
    for (char v : n.valid) valid += v != 0;
    benchmark::DoNotOptimize(valid);
  }
  state.counters["points"] = static_cast<double>(c.model.size());
  state.counters["valid"] = static_cast<double>(valid);
}
BENCHMARK(BM_Normals)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
