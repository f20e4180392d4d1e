#pragma once
// Point clouds: PLY I/O, voxel-grid downsampling, cropping.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace pbnbv {

using PointCloud = std::vector<Eigen::Vector3f>;

// Binary little-endian PLY with float x y z. Throws std::runtime_error naming the path on error.
void write_ply(const PointCloud& cloud, const std::string& path);
// Reads a PLY point cloud (ascii or binary, float or double x y z; other properties skipped).
PointCloud read_ply(const std::string& path);

// One point per occupied voxel of edge `voxel_m`: the centroid of the points in it.
// Deterministic (output sorted by voxel key). voxel_m <= 0 returns the input unchanged.
PointCloud voxel_downsample(const PointCloud& cloud, double voxel_m);

}  // namespace pbnbv
