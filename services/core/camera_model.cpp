#include "core/camera_model.hpp"

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

}  // namespace pbnbv
