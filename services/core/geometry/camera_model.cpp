#include "core/geometry/camera_model.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace pbnbv {

namespace {
void require(bool ok, const std::string& field, double value, const char* rule) {
  if (ok) return;
  std::ostringstream os;
  os << "camera intrinsics: " << field << " = " << value << " is invalid (" << rule << ")";
  throw std::invalid_argument(os.str());
}
}  // namespace

void CameraIntrinsics::validate() const {
  require(width > 0 && width <= 16384, "width", width, "must be in 1..16384");
  require(height > 0 && height <= 16384, "height", height, "must be in 1..16384");
  if (static_cast<long long>(width) * height > kMaxImagePixels) {
    throw std::invalid_argument("camera intrinsics: " + std::to_string(width) + " x " + std::to_string(height) +
                                " = " + std::to_string(static_cast<long long>(width) * height) +
                                " pixels is more than the largest image, " + std::to_string(kMaxImagePixels));
  }
  require(std::isfinite(fx) && fx > 0, "fx", fx, "must be a positive number of pixels");
  require(std::isfinite(fy) && fy > 0, "fy", fy, "must be a positive number of pixels");
  require(std::isfinite(cx) && cx >= 0 && cx <= width, "cx", cx, "must lie inside the image");
  require(std::isfinite(cy) && cy >= 0 && cy <= height, "cy", cy, "must lie inside the image");
}

void DepthRange::validate() const {
  if (!(std::isfinite(min_m) && min_m > 0 && std::isfinite(max_m) && max_m > min_m)) {
    std::ostringstream os;
    os << "depth range [" << min_m << ", " << max_m
       << "] m is invalid (need 0 < min < max, both finite)";
    throw std::invalid_argument(os.str());
  }
}

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

}  // namespace pbnbv
