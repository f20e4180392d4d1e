#pragma once
// Lens distortion of a depth camera: the Brown-Conrady model (radial k1 k2 k3, tangential p1 p2),
// in OpenCV's order and convention, so a camera's factory calibration or cv::calibrateCamera's
// result goes in as it is. A depth image taken through the lens is resampled into the pinhole
// image of the same intrinsics (undistort_depth) before anything back-projects it; the twin does
// the opposite (distort_depth) to play such a camera.
//
// Normalised image coordinates: x = (u - cx) / fx, y = (v - cy) / fy. With r^2 = x^2 + y^2, a
// point (x, y) of the pinhole image is seen at
//   x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
//   y_d = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y.
// Depth is planar (along the optical axis): the lens moves where a point appears, not its depth.
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "core/geometry/camera_model.hpp"

namespace pbnbv {

struct LensDistortion {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;

  bool none() const { return k1 == 0 && k2 == 0 && p1 == 0 && p2 == 0 && k3 == 0; }
  std::array<double, 5> coefficients() const { return {k1, k2, p1, p2, k3}; }  // k1 k2 p1 p2 k3
  static LensDistortion from(const std::array<double, 5>& c) { return {c[0], c[1], c[2], c[3], c[4]}; }
  // Throws std::invalid_argument naming `what` and the coefficient when one is not finite or
  // beyond what a lens has (|k1|, |k2|, |k3| <= 10, |p1|, |p2| <= 1), or when the model folds over
  // inside the image of `k` (a larger pinhole radius seen at a smaller distorted one: such
  // coefficients do not describe this camera).
  void validate(const CameraIntrinsics& k, const std::string& what) const;
};

// The pinhole point (x, y) (normalised) where it appears through the lens.
Eigen::Vector2d distort_normalised(const LensDistortion& d, const Eigen::Vector2d& xy);
// Its inverse: the pinhole point seen at the distorted (x_d, y_d), by Newton's method (to 1e-12).
Eigen::Vector2d undistort_normalised(const LensDistortion& d, const Eigen::Vector2d& xy_d);

// The pinhole image of `k` from an image of the same intrinsics taken through the lens `d`: each
// pixel samples the distorted image where its ray appears; inverse depth is interpolated
// bilinearly between four readings within 2 % of each other (exact on a plane), else the nearest
// reading is taken (no depth between an edge's two sides); 0 where the ray falls outside the image
// or on no reading. `d.none()`: the image unchanged.
std::vector<float> undistort_depth(const std::vector<float>& depth_m, const CameraIntrinsics& k, const LensDistortion& d);

// The pinhole camera (same focal lengths) whose image holds every ray the lens `d` brings into the
// image of `k`, with a pixel of margin: what the twin renders before distort_depth. Throws as
// LensDistortion::validate when `d` is no lens for `k`.
CameraIntrinsics pinhole_cover(const CameraIntrinsics& k, const LensDistortion& d);

// The image of `k` through the lens `d` from the pinhole image `pinhole` of `k_pinhole` (the same
// focal lengths; pinhole_cover's): each pixel samples the pinhole image where its ray is, as
// undistort_depth samples.
std::vector<float> distort_depth(const std::vector<float>& pinhole, const CameraIntrinsics& k_pinhole,
                                 const CameraIntrinsics& k, const LensDistortion& d);

}  // namespace pbnbv
