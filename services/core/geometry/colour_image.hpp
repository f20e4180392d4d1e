#pragma once
// A colour image taken with a depth image, and the colours of the points the depth image gave:
// each point projected into the colour sensor (its own intrinsics and lens, at depth_T_colour from
// the depth sensor) and the pixel under it read. Plain data and functions.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/base/pose.hpp"
#include "core/geometry/camera_model.hpp"
#include "core/geometry/lens_distortion.hpp"
#include "core/geometry/point_cloud.hpp"

namespace pbnbv {

// One colour, 8 bits per channel, R G B.
using Rgb = std::array<uint8_t, 3>;

// A point the colour sensor did not see (outside its image or behind it): mid grey.
inline constexpr Rgb kNoColour{128, 128, 128};

struct ColourImage {
  CameraIntrinsics intrinsics;      // the colour sensor's
  LensDistortion distortion;        // the image as taken (not resampled)
  Pose depth_T_colour = Pose::Identity();  // the colour sensor's optical frame in the depth sensor's
  std::vector<uint8_t> rgb;         // width * height * 3, R G B, row-major, row 0 at the top

  // Throws std::invalid_argument naming `what` and the bad field: intrinsics, lens, a pose that
  // is not rigid (validate_camera), or rgb not width * height * 3 bytes.
  void validate(const std::string& what) const;
  void validate_camera(const std::string& what) const;
};

// The colour of each point (object frame) of a frame the depth sensor took at object_T_depth:
// the colour image's pixel nearest the point's projection through the colour sensor's pinhole
// and lens. kNoColour for a point behind the colour sensor or outside its image. No occlusion
// test: where the two sensors see past different edges, a point may take the colour of what
// hides it from the colour sensor. `seen` (optional) receives how many points had a colour.
std::vector<Rgb> point_colours(const PointCloud& points, const ColourImage& image, const Pose& object_T_depth,
                               int* seen = nullptr);

}  // namespace pbnbv
