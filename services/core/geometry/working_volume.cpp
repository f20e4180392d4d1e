#include "core/geometry/working_volume.hpp"

#include <fmt/format.h>

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "core/base/format.hpp"

namespace pbnbv {

namespace {

constexpr double kMaxSizeM = 3.0;

std::vector<double> numbers(const std::string& list, const std::string& text) {
  std::vector<double> v;
  std::stringstream in(list);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    double x = 0;
    try {
      x = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size()) {
      throw std::invalid_argument("working volume '" + text + "': '" + item + "' is not a number");
    }
    if (!(x > 0) || x > kMaxSizeM) {
      throw std::invalid_argument(fmt::format("working volume '{}': {} m is not a size in (0, {}] m", text, item, kMaxSizeM));
    }
    v.push_back(x);
  }
  return v;
}

}  // namespace

Eigen::AlignedBox3d WorkingVolume::bounds() const {
  const Eigen::Vector3d half = shape == Shape::kCylinder ? Eigen::Vector3d(radius_m, radius_m, height_m / 2)
                                                         : Eigen::Vector3d(size_x_m / 2, size_y_m / 2, height_m / 2);
  return Eigen::AlignedBox3d(-half, half);
}

std::string WorkingVolume::to_text() const {
  if (shape == Shape::kCylinder) return "cylinder:" + exact(radius_m) + "," + exact(height_m);
  return "box:" + exact(size_x_m) + "," + exact(size_y_m) + "," + exact(height_m);
}

WorkingVolume parse_working_volume(const std::string& text) {
  const std::size_t colon = text.find(':');
  const std::string shape = text.substr(0, colon);
  const std::string list = colon == std::string::npos ? "" : text.substr(colon + 1);
  WorkingVolume w;
  if (shape == "cylinder") {
    const std::vector<double> v = numbers(list, text);
    if (v.size() != 2) throw std::invalid_argument("working volume '" + text + "': a cylinder is cylinder:RADIUS,HEIGHT (m)");
    w.shape = WorkingVolume::Shape::kCylinder;
    w.radius_m = v[0];
    w.height_m = v[1];
  } else if (shape == "box") {
    const std::vector<double> v = numbers(list, text);
    if (v.size() != 3) throw std::invalid_argument("working volume '" + text + "': a box is box:X,Y,Z (edges, m)");
    w.shape = WorkingVolume::Shape::kBox;
    w.size_x_m = v[0];
    w.size_y_m = v[1];
    w.height_m = v[2];
  } else {
    throw std::invalid_argument("working volume '" + text + "': expected cylinder:RADIUS,HEIGHT or box:X,Y,Z (m)");
  }
  return w;
}

}  // namespace pbnbv
