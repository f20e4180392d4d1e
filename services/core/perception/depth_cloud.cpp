#include "core/perception/cloud_filter.hpp"
#include "core/perception/depth_cloud.hpp"

#include <cmath>
#include <stdexcept>

namespace pbnbv {

PointCloud depth_to_object_cloud(const std::vector<float>& depth_m, const CameraIntrinsics& k,
                                 const DepthRange& range, const Pose& object_T_camera,
                                 const CloudCrop& crop, double voxel_m, CloudStats* stats) {
  k.validate();
  if (depth_m.size() != static_cast<std::size_t>(k.width) * k.height) {
    throw std::invalid_argument("depth image has " + std::to_string(depth_m.size()) +
                                " pixels, intrinsics say " + std::to_string(k.width) + "x" +
                                std::to_string(k.height));
  }
  CloudStats s;
  PointCloud cloud;
  cloud.reserve(depth_m.size() / 4);
  const Eigen::Matrix3d r = object_T_camera.linear();
  const Eigen::Vector3d t = object_T_camera.translation();
  const double floor_z = crop.ground_z_m + crop.ground_clearance_m;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const double z = depth_m[static_cast<std::size_t>(v) * k.width + u];
      if (!std::isfinite(z) || z < range.min_m || z > range.max_m) continue;
      ++s.num_valid_pixels;
      const Eigen::Vector3d p = r * back_project(k, u, v, z) + t;
      if ((!crop.volume_m.isEmpty() && !crop.volume_m.contains(p)) || p.z() <= floor_z) {
        ++s.num_cropped;
        continue;
      }
      cloud.emplace_back(p.cast<float>());
    }
  }
  if (stats) *stats = s;
  return voxel_downsample(cloud, voxel_m);
}

}  // namespace pbnbv
