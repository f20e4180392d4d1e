#pragma once
// Reading point clouds in PCL's PCD format (what PCL, Open3D and many RGB-D tools write), for
// `pbnbv evaluate`: x, y, z of any cloud a user has.
#include <string>

#include "core/geometry/point_cloud.hpp"

namespace pbnbv {

// Reads a PCD file (version 0.7 header; DATA ascii or binary; x, y and z fields of type F, size
// 4 or 8, count 1; other fields skipped; non-finite points kept, as PCL writes them for an
// organised cloud). Throws std::runtime_error "read_pcd: <path>: ..." naming what is wrong: a
// missing or empty file, a header without FIELDS/SIZE/TYPE/POINTS/DATA or without x, y, z,
// DATA binary_compressed (not supported: save as binary or ascii), a body shorter than POINTS.
PointCloud read_pcd(const std::string& path);

}  // namespace pbnbv
