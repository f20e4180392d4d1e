// Depth images as 16-bit PNGs of millimetres, read back (libpng; OpenCV reads them too: image_codec_test).
#include "report/depth_png.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>

namespace pbnbv {
namespace {

// A plane tilted about the camera's y axis, z = 0.6 + 0.001 * (u - 32) m over a 64 x 48 image,
// with no reading in the top row: pixel (u, v) holds 600 + (u - 32) mm exactly, 0 in row 0;
// a NaN and a depth above 65.535 m are written 0.
TEST(DepthPng, APlaneAtAKnownDepthReadsBackInMillimetres) {
  const int w = 64, h = 48;
  std::vector<float> depth(w * h);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) depth[v * w + u] = v == 0 ? 0.0f : static_cast<float>(0.6 + 0.001 * (u - 32));
  }
  depth[5 * w + 5] = std::numeric_limits<float>::quiet_NaN();
  depth[6 * w + 6] = 70.0f;
  const std::string path =
      (std::filesystem::temp_directory_path() / ("pbnbv_depth_" + std::to_string(::getpid()) + ".png")).string();
  write_depth_png(depth, w, h, 1000, path);
  int rw = 0, rh = 0;
  const std::vector<uint16_t> mm = read_depth_png(path, rw, rh);
  std::filesystem::remove(path);
  ASSERT_EQ(rw, w);
  ASSERT_EQ(rh, h);
  EXPECT_EQ(mm[0 * w + 10], 0);
  EXPECT_EQ(mm[1 * w + 32], 600);
  EXPECT_EQ(mm[20 * w + 0], 568);
  EXPECT_EQ(mm[47 * w + 63], 631);
  EXPECT_EQ(mm[5 * w + 5], 0);
  EXPECT_EQ(mm[6 * w + 6], 0);
  int wrong = 0;
  for (int v = 1; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      if ((v == 5 && u == 5) || (v == 6 && u == 6)) continue;
      wrong += mm[v * w + u] != 600 + (u - 32);
    }
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_THROW(write_depth_png(depth, w + 1, h, 1000, path), std::invalid_argument);
  EXPECT_THROW(write_depth_png(depth, w, h, 0, path), std::invalid_argument);
  EXPECT_THROW(read_depth_png(path, rw, rh), std::runtime_error);  // removed above
}

// At the pipeline's 0.1 mm (10000 units per metre): 0.6123 m reads 6123, a step of 0.1 mm is
// one unit, and 6.5535 m is the last depth that fits.
TEST(DepthPng, TenthsOfAMillimetreKeepTheStepsThePipelineResolves) {
  const int w = 4, h = 1;
  const std::vector<float> depth = {0.6123f, 0.6124f, 6.5535f, 6.6f};
  const std::string path =
      (std::filesystem::temp_directory_path() / ("pbnbv_depth_tenths_" + std::to_string(::getpid()) + ".png")).string();
  write_depth_png(depth, w, h, 10000, path);
  int rw = 0, rh = 0;
  const std::vector<uint16_t> units = read_depth_png(path, rw, rh);
  std::filesystem::remove(path);
  EXPECT_EQ(units, (std::vector<uint16_t>{6123, 6124, 65535, 0}));
}

}  // namespace
}  // namespace pbnbv
