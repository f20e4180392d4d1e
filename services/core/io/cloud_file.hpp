#pragma once
// Point cloud files (PLY): read by CGAL's point-set PLY reader, written by our own writer.
#include <string>
#include <vector>

#include "core/base/pose.hpp"
#include "core/geometry/point_cloud.hpp"

namespace pbnbv {

// What a cloud file carries besides its points.
struct CloudExtras {
  std::vector<Eigen::Vector3f> normals;  // empty: none; else one unit normal per point (zero: none found)
  std::vector<Pose> camera_poses;        // object_T_camera of the view(s) the points came from
};

// Binary little-endian PLY with float x y z, and float nx ny nz when `extras` has normals (what
// Open3D, PCL and MeshLab read), written atomically (temporary file + rename). The header says
// the units and the frame and gives each camera pose in a comment a user can parse:
//   comment units metres
//   comment frame object (...)
//   comment camera_pose x y z qw qx qy qz
// one camera_pose line per pose, in order: the camera's optical frame (x right, y down, z
// forward) in the object frame, position in metres and unit quaternion w x y z.
// Throws std::runtime_error naming the path on error, std::invalid_argument when the normals
// are not one per point.
void write_ply(const PointCloud& cloud, const std::string& path, const CloudExtras& extras = {});
// Reads a PLY point cloud (ascii or binary, float or double x y z; other properties and
// elements skipped; non-finite points kept). Errors as load_mesh's for PLY.
PointCloud read_ply(const std::string& path);
// Reads the points and, when the file has them, the normals (nx ny nz) and camera_pose comments
// (files written before they were added have neither: extras stay empty).
PointCloud read_ply(const std::string& path, CloudExtras& extras);

}  // namespace pbnbv
