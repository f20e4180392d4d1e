#pragma once
// Point cloud filters: voxel-grid downsampling.
#include <cmath>
#include <cstdint>

#include "core/geometry/point_cloud.hpp"

namespace pbnbv {

// A point's voxel index (floor of each coordinate over voxel_m); false for a non-finite point or
// an absurdly far one (voxel_downsample drops those).
inline bool voxel_index(const Eigen::Vector3f& p, double voxel_m, int64_t q[3]) {
  constexpr double kMaxIndex = 4.0e18;
  for (int k = 0; k < 3; ++k) {
    const double f = std::floor(static_cast<double>(p[k]) / voxel_m);
    if (!(std::fabs(f) < kMaxIndex)) return false;  // also catches NaN
    q[k] = static_cast<int64_t>(f);
  }
  return true;
}

// One point per occupied voxel of edge `voxel_m`: the centroid of the points in it.
// Deterministic (output in the lexicographic order of the voxel indices; each centroid summed
// in the points' order). voxel_m <= 0 returns the input unchanged.
PointCloud voxel_downsample(const PointCloud& cloud, double voxel_m);

}  // namespace pbnbv
