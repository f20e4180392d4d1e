// What colour adds to a frame, side by side with the depth it travels with, on the twin's 1280 x
// 720 image: the twin's JPEG encoding, the camera service's decoding (JPEG, and raw R G B), against
// the depth image's zlib inflation every service already does; and colouring a frame's points.
// The image is a scene like the twin's: a flat-shaded box in two colours on a lit plane, black
// above (the JPEG's size is printed as a counter, with the depth image's compressed size).
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "bus/colour_codec.hpp"
#include "bus/depth_codec.hpp"
#include "core/geometry/colour_image.hpp"

using namespace pbnbv;

namespace {

constexpr int kWidth = 1280, kHeight = 720;

ColourImage scene() {
  ColourImage c;
  c.intrinsics = CameraIntrinsics{kWidth, kHeight, 696, 696, 640, 360};
  c.rgb.resize(static_cast<std::size_t>(kWidth) * kHeight * 3);
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      uint8_t* p = &c.rgb[(static_cast<std::size_t>(v) * kWidth + static_cast<std::size_t>(u)) * 3];
      if (u > 400 && u < 880 && v > 200 && v < 560) {  // the box: red and blue faces, shaded
        const double shade = v < 260 ? 1.0 : 0.55 + 0.1 * std::sin(u * 0.01);
        p[0] = u < 600 ? static_cast<uint8_t>(230 * shade) : 20;
        p[1] = 20;
        p[2] = u < 600 ? 20 : static_cast<uint8_t>(230 * shade);
      } else if (v > 220) {  // the lit plane, brightest under the light
        const double d = std::hypot(u - 640.0, v - 500.0) / 800.0;
        const auto level = static_cast<uint8_t>(210 * (1 - d));
        p[0] = level;
        p[1] = static_cast<uint8_t>(level * 0.8);
        p[2] = static_cast<uint8_t>(level * 0.6);
      }
    }
  }
  return c;
}

// The depth image of the same scene (0.1 mm counts, little-endian), as the twin sends it.
std::vector<uint8_t> depth_bytes() {
  std::vector<uint8_t> raw(static_cast<std::size_t>(kWidth) * kHeight * 2, 0);
  for (int v = 221; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      const auto counts = static_cast<uint16_t>(6000 + (u > 400 && u < 880 && v < 560 ? -800 : 3 * (kHeight - v)));
      const std::size_t i = (static_cast<std::size_t>(v) * kWidth + static_cast<std::size_t>(u)) * 2;
      raw[i] = static_cast<uint8_t>(counts & 0xff);
      raw[i + 1] = static_cast<uint8_t>(counts >> 8);
    }
  }
  return raw;
}

void BM_EncodeColourJpeg(benchmark::State& state) {
  const ColourImage c = scene();
  std::size_t bytes = 0;
  for (auto _ : state) {
    depth_frame_t f{};
    bus::set_colour(f, c, 0, depth_frame_t::kColourJpeg);
    bytes = f.colour.size();
    benchmark::DoNotOptimize(f.colour.data());
  }
  state.counters["jpeg_kB"] = static_cast<double>(bytes) / 1024.0;
}
BENCHMARK(BM_EncodeColourJpeg)->Unit(benchmark::kMillisecond);

void BM_DecodeColourJpeg(benchmark::State& state) {
  depth_frame_t f{};
  bus::set_colour(f, scene(), 0, depth_frame_t::kColourJpeg);
  for (auto _ : state) benchmark::DoNotOptimize(bus::decode_colour(f));
}
BENCHMARK(BM_DecodeColourJpeg)->Unit(benchmark::kMillisecond);

void BM_DecodeColourRaw(benchmark::State& state) {
  depth_frame_t f{};
  bus::set_colour(f, scene(), 0, depth_frame_t::kColourRgb8);
  for (auto _ : state) benchmark::DoNotOptimize(bus::decode_colour(f));
}
BENCHMARK(BM_DecodeColourRaw)->Unit(benchmark::kMillisecond);

// The depth image's own decoding, for scale: what every frame already cost.
void BM_InflateDepthZlib(benchmark::State& state) {
  const std::vector<uint8_t> raw = depth_bytes();
  const std::vector<uint8_t> compressed = bus::deflate_bytes(raw, 1);
  for (auto _ : state) benchmark::DoNotOptimize(bus::inflate_bytes(compressed, raw.size(), raw.size(), "bench"));
  state.counters["zlib_kB"] = static_cast<double>(compressed.size()) / 1024.0;
}
BENCHMARK(BM_InflateDepthZlib)->Unit(benchmark::kMillisecond);

// Colouring a frame's cloud: 100,000 points (a twin frame's, downsampled) projected into the image.
void BM_PointColours(benchmark::State& state) {
  const ColourImage c = scene();
  PointCloud points;
  for (int i = 0; i < 100000; ++i) {
    const float x = -0.3f + 0.6f * static_cast<float>(i % 400) / 400.0f;
    const float y = -0.2f + 0.4f * static_cast<float>(i / 400) / 250.0f;
    points.emplace_back(x, y, 0.6f);
  }
  for (auto _ : state) benchmark::DoNotOptimize(point_colours(points, c, Pose::Identity()));
}
BENCHMARK(BM_PointColours)->Unit(benchmark::kMillisecond);

}  // namespace
