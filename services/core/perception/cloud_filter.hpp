#pragma once
// Point cloud filters: voxel-grid downsampling.
#include "core/geometry/point_cloud.hpp"

namespace pbnbv {

// One point per occupied voxel of edge `voxel_m`: the centroid of the points in it.
// Deterministic (output sorted by voxel key). voxel_m <= 0 returns the input unchanged.
PointCloud voxel_downsample(const PointCloud& cloud, double voxel_m);

}  // namespace pbnbv
