#pragma once
// Depth images as the files other RGB-D tools read: 16-bit single-channel PNG of depth in units of
// 1 / units_per_metre m (0 = no reading; the scale goes beside it, as Open3D's depth_scale),
// written and read with libpng (core/io/image_codec.hpp).
#include <cstdint>
#include <string>
#include <vector>

namespace pbnbv {

// Writes `depth_m` (row-major, width * height, metres; 0, negative or non-finite = no reading)
// as a 16-bit PNG of depth * units_per_metre rounded to the nearest (10000: 0.1 mm, up to
// 6.5535 m; 1000: millimetres; values beyond 65535 units are written 0). Throws
// std::runtime_error naming the path when it cannot be written, std::invalid_argument when the
// sizes disagree or the scale is not positive.
void write_depth_png(const std::vector<float>& depth_m, int width, int height, int units_per_metre,
                     const std::string& path);

// The most pixels read_depth_png takes from a file's header (64 Mpixel: far above any depth
// camera's).
inline constexpr int64_t kMaxDepthPngPixels = int64_t{64} << 20;

// Reads a 16-bit single-channel PNG back as its units (row-major); throws std::runtime_error
// naming the path when it is missing, not a PNG, broken or truncated, not a 16-bit
// single-channel image, or larger than kMaxDepthPngPixels.
std::vector<uint16_t> read_depth_png(const std::string& path, int& width, int& height);

}  // namespace pbnbv
