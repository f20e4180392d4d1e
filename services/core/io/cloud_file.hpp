#pragma once
// Point cloud files (PLY): read by CGAL's point-set PLY reader, written by our own writer.
#include <string>

#include "core/geometry/point_cloud.hpp"

namespace pbnbv {

// Binary little-endian PLY with float x y z (what Open3D, PCL and MeshLab read), written
// atomically (temporary file + rename). Throws std::runtime_error naming the path on error.
void write_ply(const PointCloud& cloud, const std::string& path);
// Reads a PLY point cloud (ascii or binary, float or double x y z; other properties and
// elements skipped; non-finite points kept). Errors as load_mesh's for PLY.
PointCloud read_ply(const std::string& path);

}  // namespace pbnbv
