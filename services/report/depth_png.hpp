#pragma once
// Depth images as the files other RGB-D tools read: 16-bit single-channel PNG of millimetres
// (0 = no reading), written and read with OpenCV's imgcodecs.
#include <cstdint>
#include <string>
#include <vector>

namespace pbnbv {

// Writes `depth_m` (row-major, width * height, metres; 0, negative or non-finite = no reading)
// as a 16-bit PNG of millimetres rounded to the nearest (values above 65.535 m are written 0).
// Throws std::runtime_error naming the path when it cannot be written, std::invalid_argument
// when the sizes disagree.
void write_depth_png(const std::vector<float>& depth_m, int width, int height, const std::string& path);

// Reads a 16-bit single-channel PNG back as millimetres (row-major); throws naming the path when
// it is missing or not a 16-bit single-channel image.
std::vector<uint16_t> read_depth_png(const std::string& path, int& width, int& height);

}  // namespace pbnbv
