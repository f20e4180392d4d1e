#pragma once
// Turning one depth frame into an object-frame cloud: decode, back-project, transform, crop,
// downsample. Plain functions; the camera service calls them.
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "core/geometry/camera_model.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/base/pose.hpp"

namespace pbnbv {

struct CloudCrop {
  Eigen::AlignedBox3d volume_m;  // working volume, object frame (closed); empty: no limit
  double ground_z_m = -1e9;  // object-frame z of the turntable top; points at or below
  double ground_clearance_m = 0;  // ground_z + clearance are dropped
};

struct CloudStats {
  int num_valid_pixels = 0;
  int num_cropped = 0;
};


// Back-projects every pixel whose depth is finite and inside `range`, maps it with
// object_T_camera, keeps the points inside the crop, then voxel-downsamples.
PointCloud depth_to_object_cloud(const std::vector<float>& depth_m, const CameraIntrinsics& k,
                                 const DepthRange& range, const Pose& object_T_camera,
                                 const CloudCrop& crop, double voxel_m, CloudStats* stats);

}  // namespace pbnbv
