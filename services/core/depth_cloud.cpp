#include "core/depth_cloud.hpp"

#include <cmath>
#include <stdexcept>

namespace pbnbv {

std::vector<float> decode_depth_u16(const std::vector<uint8_t>& bytes, int width, int height,
                                    double depth_unit_m) {
  if (width <= 0 || height <= 0) {
    throw std::invalid_argument("depth frame size " + std::to_string(width) + "x" +
                                std::to_string(height) + " is empty");
  }
  const std::size_t n = static_cast<std::size_t>(width) * height;
  if (bytes.size() != 2 * n) {
    throw std::invalid_argument("depth frame has " + std::to_string(bytes.size()) + " bytes, " +
                                std::to_string(width) + "x" + std::to_string(height) +
                                " uint16 needs " + std::to_string(2 * n));
  }
  if (!(std::isfinite(depth_unit_m) && depth_unit_m > 0)) {
    throw std::invalid_argument("depth frame depth_unit_m = " + std::to_string(depth_unit_m) +
                                " is not a positive number");
  }
  std::vector<float> depth(n);
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned v = bytes[2 * i] | (static_cast<unsigned>(bytes[2 * i + 1]) << 8);
    depth[i] = static_cast<float>(v * depth_unit_m);
  }
  return depth;
}

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
      if ((p.array() < crop.min_m.array()).any() || (p.array() > crop.max_m.array()).any() ||
          p.z() <= floor_z) {
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
