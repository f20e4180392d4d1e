#pragma once
// Point cloud files (PLY): read by CGAL's point-set PLY reader, written by our own writer.
#include <filesystem>
#include <string>
#include <vector>

#include "core/base/pose.hpp"
#include "core/geometry/colour_image.hpp"
#include "core/geometry/point_cloud.hpp"

namespace pbnbv {

// What a cloud file carries besides its points.
struct CloudExtras {
  std::vector<Eigen::Vector3f> normals;  // empty: none; else one unit normal per point (zero: none found)
  std::vector<Pose> camera_poses;        // object_T_camera of the view(s) the points came from
  std::vector<Rgb> colours;              // empty: none; else one colour per point
};

// Binary little-endian PLY with float x y z, float nx ny nz when `extras` has normals and uchar
// red green blue when it has colours (what
// Open3D, PCL and MeshLab read), written atomically (temporary file + rename). The header says
// the units and the frame and gives each camera pose in a comment a user can parse:
//   comment units metres
//   comment frame object (...)
//   comment camera_pose x y z qw qx qy qz
// one camera_pose line per pose, in order: the camera's optical frame (x right, y down, z
// forward) in the object frame, position in metres and unit quaternion w x y z.
// Throws std::runtime_error naming the path on error, std::invalid_argument when the normals
// or colours are not one per point.
void write_ply(const PointCloud& cloud, const std::string& path, const CloudExtras& extras = {});
// Reads a PLY point cloud (ascii or binary, float or double x y z; other properties and
// elements skipped; non-finite points kept). Errors as load_mesh's for PLY.
PointCloud read_ply(const std::string& path);
// Reads the points and, when the file has them, the normals (nx ny nz), the colours (as
// read_ply_colours) and camera_pose comments (files written before they were added have none:
// extras stay empty).
PointCloud read_ply(const std::string& path, CloudExtras& extras);

// The per-point colours of a PLY cloud: its vertex element's `red`, `green` and `blue` (uchar as
// they are, ushort scaled to 0..255, float and double read as 0..1), in the order of read_ply's
// points. Empty when the file has none, when its vertex count is not `points`, or when its layout
// is not one followed here (big-endian, a list property in the vertex element, another element
// with data before it). The binary form is read as this machine's little-endian.
std::vector<Rgb> read_ply_colours(const std::filesystem::path& path, std::size_t points);


}  // namespace pbnbv
