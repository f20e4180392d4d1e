#pragma once
// The pinhole depth camera: intrinsics, depth range, back-projection. One camera model for the
// twin's renderer, the camera service and (later) the view scorer.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/geometry/camera_options.hpp"

namespace pbnbv {

// Pinhole intrinsics in pixels. Defaults: the paper's simulated RealSense D435.
struct CameraIntrinsics {
  int width = kImageWidth.value;
  int height = kImageHeight.value;
  double fx = kFocalX.value;
  double fy = kFocalY.value;
  double cx = kPrincipalX.value;
  double cy = kPrincipalY.value;

  // Throws std::invalid_argument naming the bad field when a value is out of range
  // (size <= 0, focal length <= 0, principal point outside the image, non-finite).
  void validate() const;
};

// Valid depth interval of the sensor, metres along the optical axis (planar depth).
struct DepthRange {
  double min_m = kDepthMin.value;
  double max_m = kDepthMax.value;
  void validate() const;  // throws std::invalid_argument when min <= 0 or max <= min
};

// The 3-D point in the optical frame seen at pixel centre (u, v) (pixel (0,0)'s centre is at
// u = 0, v = 0) with planar depth z_m.
inline Eigen::Vector3d back_project(const CameraIntrinsics& k, double u, double v, double z_m) {
  return Eigen::Vector3d((u - k.cx) * z_m / k.fx, (v - k.cy) * z_m / k.fy, z_m);
}

// Decodes little-endian uint16 counts (0 = invalid) into metres. Throws std::invalid_argument
// naming the field when sizes disagree or depth_unit is not positive.
std::vector<float> decode_depth_u16(const std::vector<uint8_t>& bytes, int width, int height,
                                    double depth_unit_m);

}  // namespace pbnbv
