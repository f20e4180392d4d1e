#include "report/depth_png.hpp"
#include "core/base/atomic_file.hpp"

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

namespace pbnbv {

void write_depth_png(const std::vector<float>& depth_m, int width, int height, int units_per_metre,
                     const std::string& path) {
  if (units_per_metre <= 0) {
    throw std::invalid_argument("write_depth_png: " + path + ": depth scale " + std::to_string(units_per_metre) +
                                " units per metre (must be positive)");
  }
  if (width <= 0 || height <= 0 || depth_m.size() != static_cast<std::size_t>(width) * height) {
    throw std::invalid_argument("write_depth_png: " + path + ": " + std::to_string(depth_m.size()) +
                                " depths for a " + std::to_string(width) + " x " + std::to_string(height) + " image");
  }
  cv::Mat image(height, width, CV_16UC1);
  for (int v = 0; v < height; ++v) {
    auto* row = image.ptr<uint16_t>(v);
    for (int u = 0; u < width; ++u) {
      const double units =
          std::round(static_cast<double>(depth_m[static_cast<std::size_t>(v) * width + u]) * units_per_metre);
      row[u] = (std::isfinite(units) && units > 0.0 && units <= 65535.0) ? static_cast<uint16_t>(units) : 0;
    }
  }
  // Atomically: a reader never sees half an image, a full disk leaves no part of one.
  std::vector<uchar> png;
  if (!cv::imencode(".png", image, png)) throw std::runtime_error("write_depth_png: cannot encode " + path);
  write_file_atomic(path, std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
}

std::vector<uint16_t> read_depth_png(const std::string& path, int& width, int& height) {
  const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty()) throw std::runtime_error("read_depth_png: cannot read " + path);
  if (image.type() != CV_16UC1) throw std::runtime_error("read_depth_png: " + path + " is not a 16-bit single-channel image");
  width = image.cols;
  height = image.rows;
  std::vector<uint16_t> mm(static_cast<std::size_t>(width) * height);
  for (int v = 0; v < height; ++v) {
    const auto* row = image.ptr<uint16_t>(v);
    for (int u = 0; u < width; ++u) mm[static_cast<std::size_t>(v) * width + u] = row[u];
  }
  return mm;
}

}  // namespace pbnbv
