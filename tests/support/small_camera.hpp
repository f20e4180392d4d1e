#pragma once
// A small pinhole camera for the tests that work projections out by hand: 64 x 48 pixels,
// fx = fy = 50 px, principal point at the image centre (32, 24).
#include "core/geometry/camera_model.hpp"

namespace pbnbv::testing {

inline CameraIntrinsics small_camera() {
  CameraIntrinsics k;
  k.width = 64;
  k.height = 48;
  k.fx = k.fy = 50.0;
  k.cx = 32.0;
  k.cy = 24.0;
  return k;
}

}  // namespace pbnbv::testing
