#include "core/geometry/colour_image.hpp"

#include <cmath>
#include <stdexcept>

namespace pbnbv {

void ColourImage::validate_camera(const std::string& what) const {
  try {
    intrinsics.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(what + " intrinsics: " + e.what());
  }
  distortion.validate(intrinsics, what + " distortion");
  const Eigen::Matrix3d r = depth_T_colour.linear();
  if (!depth_T_colour.matrix().allFinite() || !(r.transpose() * r).isIdentity(1e-6) || r.determinant() < 0) {
    throw std::invalid_argument(what + " depth_T_colour is not a rigid transform");
  }
}

void ColourImage::validate(const std::string& what) const {
  validate_camera(what);
  const std::size_t want = static_cast<std::size_t>(intrinsics.width) * intrinsics.height * 3;
  if (rgb.size() != want) {
    throw std::invalid_argument(what + ": " + std::to_string(rgb.size()) + " bytes of colour for a " +
                                std::to_string(intrinsics.width) + " x " + std::to_string(intrinsics.height) +
                                " image (" + std::to_string(want) + " wanted)");
  }
}

std::vector<Rgb> point_colours(const PointCloud& points, const ColourImage& image, const Pose& object_T_depth,
                               int* seen) {
  const CameraIntrinsics& k = image.intrinsics;
  const Pose colour_T_object = (object_T_depth * image.depth_T_colour).inverse();
  const bool lens = !image.distortion.none();
  std::vector<Rgb> out(points.size(), kNoColour);
  int n = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d p = colour_T_object * points[i].cast<double>();
    if (!(p.z() > 0)) continue;
    Eigen::Vector2d xy(p.x() / p.z(), p.y() / p.z());
    if (lens) xy = distort_normalised(image.distortion, xy);
    const long u = std::lround(k.fx * xy.x() + k.cx);
    const long v = std::lround(k.fy * xy.y() + k.cy);
    if (u < 0 || v < 0 || u >= k.width || v >= k.height) continue;
    const std::size_t at = (static_cast<std::size_t>(v) * k.width + static_cast<std::size_t>(u)) * 3;
    out[i] = {image.rgb[at], image.rgb[at + 1], image.rgb[at + 2]};
    ++n;
  }
  if (seen) *seen = n;
  return out;
}

}  // namespace pbnbv
