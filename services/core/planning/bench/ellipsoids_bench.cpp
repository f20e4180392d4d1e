// fit_ellipsoids for both classes (two calls) on 2,000 voxel centres each, T_max = 10.
//   occupied - four Gaussian blobs of different sizes, snapped to 1 cm voxels
//   frontier - two one-voxel-thin planar patches plus a blob (the shape of a frontier layer)
// Time is the wall time of both calls; "T_occ"/"T_front" are the chosen component counts and
// "ellipsoids" the number returned in total.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "core/planning/ellipsoid_fit.hpp"

namespace {

using Eigen::Vector3d;
using pbnbv::EllipsoidClass;
using pbnbv::EllipsoidParams;

constexpr double kVoxel = 0.01;
using Cell = std::tuple<long, long, long>;

Cell cell_of(const Vector3d& p) {
  return {std::lround(p.x() / kVoxel), std::lround(p.y() / kVoxel), std::lround(p.z() / kVoxel)};
}

std::vector<Vector3d> to_centres(const std::set<Cell>& cells) {
  std::vector<Vector3d> out;
  for (const auto& [i, j, k] : cells) out.push_back(kVoxel * Vector3d(i, j, k));
  return out;
}

std::vector<Vector3d> occupied_voxels(size_t count) {
  std::mt19937_64 rng(123);
  std::normal_distribution<double> nd;
  const std::vector<Vector3d> c = {{0, 0, 0}, {0.2, 0.05, 0}, {0.05, 0.2, 0.1}, {-0.1, 0.1, 0.2}};
  const std::vector<Vector3d> s = {{0.04, 0.03, 0.05}, {0.02, 0.05, 0.02}, {0.03, 0.03, 0.03}, {0.05, 0.02, 0.015}};
  std::set<Cell> cells;
  for (size_t it = 0; cells.size() < count; ++it) {
    const size_t b = it % c.size();
    cells.insert(cell_of(c[b] + Vector3d(nd(rng) * s[b].x(), nd(rng) * s[b].y(), nd(rng) * s[b].z())));
  }
  return to_centres(cells);
}

std::vector<Vector3d> frontier_voxels(size_t count) {
  std::mt19937_64 rng(321);
  std::uniform_real_distribution<double> ud(0.0, 1.0);
  std::normal_distribution<double> nd;
  std::set<Cell> cells;
  for (size_t it = 0; cells.size() < count; ++it) {
    switch (it % 3) {
      case 0: cells.insert(cell_of(Vector3d(0.3 * ud(rng), 0.25 * ud(rng), 0.25))); break;  // top
      case 1: cells.insert(cell_of(Vector3d(0.32, 0.25 * ud(rng), 0.2 * ud(rng)))); break;  // side
      default: cells.insert(cell_of(Vector3d(-0.15, -0.1, 0.1) + 0.03 * Vector3d(nd(rng), nd(rng), nd(rng))));
    }
  }
  return to_centres(cells);
}

void BM_FitEllipsoidsBothClasses(benchmark::State& state) {
  const size_t n = static_cast<size_t>(state.range(0));
  const auto occ = occupied_voxels(n);
  const auto front = frontier_voxels(n);
  EllipsoidParams p;
  p.voxel_m = kVoxel;
  p.t_max = 10;
  int t_occ = 0, t_front = 0;
  size_t count = 0;
  for (auto _ : state) {
    auto a = pbnbv::fit_ellipsoids(occ, EllipsoidClass::kOccupied, p, &t_occ);
    auto b = pbnbv::fit_ellipsoids(front, EllipsoidClass::kFrontier, p, &t_front);
    count = a.size() + b.size();
    benchmark::DoNotOptimize(a.data());
    benchmark::DoNotOptimize(b.data());
  }
  state.counters["T_occ"] = t_occ;
  state.counters["T_front"] = t_front;
  state.counters["ellipsoids"] = static_cast<double>(count);
}
BENCHMARK(BM_FitEllipsoidsBothClasses)->Arg(2000)->Arg(500)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
