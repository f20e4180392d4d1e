#pragma once
// Point cloud files (PLY).
#include <string>

#include "core/geometry/point_cloud.hpp"

namespace pbnbv {

// Binary little-endian PLY with float x y z. Throws std::runtime_error naming the path on error.
void write_ply(const PointCloud& cloud, const std::string& path);
// Reads a PLY point cloud (ascii or binary, float or double x y z; other properties skipped).
PointCloud read_ply(const std::string& path);

}  // namespace pbnbv
