// A frame's colour image on DEPTH_FRAME: JPEG and raw R G B round trips, and every way a colour
// image from the wire can be wrong refused naming the frame and the field before any decoding.
#include "bus/colour_codec.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

namespace pbnbv {
namespace {

// A 64 x 48 image: red rising left to right, green top to bottom, blue constant.
ColourImage gradient() {
  ColourImage c;
  c.intrinsics = CameraIntrinsics{64, 48, 60, 60, 32, 24};
  c.depth_T_colour.translation() = Eigen::Vector3d(0.015, 0, 0);
  c.rgb.resize(64 * 48 * 3);
  for (int v = 0; v < 48; ++v) {
    for (int u = 0; u < 64; ++u) {
      uint8_t* p = &c.rgb[(static_cast<std::size_t>(v) * 64 + static_cast<std::size_t>(u)) * 3];
      p[0] = static_cast<uint8_t>(u * 4);
      p[1] = static_cast<uint8_t>(v * 5);
      p[2] = 100;
    }
  }
  return c;
}

depth_frame_t frame_with(const ColourImage& c, int8_t encoding) {
  depth_frame_t f{};
  f.seq = 7;
  bus::set_colour(f, c, 1234, encoding, 95);
  return f;
}

TEST(ColourCodec, AJpegComesBackAsTheImageWithItsCamera) {
  const ColourImage c = gradient();
  const depth_frame_t f = frame_with(c, depth_frame_t::kColourJpeg);
  EXPECT_LT(f.colour.size(), c.rgb.size() / 2);  // compressed
  EXPECT_EQ(bus::jpeg_size(f.colour), std::make_pair(64, 48));
  const std::optional<ColourImage> back = bus::decode_colour(f);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->intrinsics.width, 64);
  EXPECT_DOUBLE_EQ(back->intrinsics.fx, 60);
  EXPECT_NEAR((back->depth_T_colour.translation() - Eigen::Vector3d(0.015, 0, 0)).norm(), 0, 1e-12);
  EXPECT_EQ(f.colour_utime, 1234);
  ASSERT_EQ(back->rgb.size(), c.rgb.size());
  double sum = 0;
  int worst = 0;
  for (std::size_t i = 0; i < c.rgb.size(); ++i) {
    const int d = std::abs(static_cast<int>(back->rgb[i]) - static_cast<int>(c.rgb[i]));
    sum += d;
    worst = std::max(worst, d);
  }
  // JPEG at quality 95 on a smooth gradient: within a few levels.
  EXPECT_LT(sum / static_cast<double>(c.rgb.size()), 2.0);
  EXPECT_LE(worst, 16);
  // Raw R G B: exact.
  const std::optional<ColourImage> raw = bus::decode_colour(frame_with(c, depth_frame_t::kColourRgb8));
  ASSERT_TRUE(raw);
  EXPECT_EQ(raw->rgb, c.rgb);
  // No colour.
  depth_frame_t none{};
  EXPECT_FALSE(bus::decode_colour(none));
}

void expect_refused(const depth_frame_t& f, const std::string& what) {
  try {
    bus::decode_colour(f);
    FAIL() << "accepted; wanted: " << what;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

TEST(ColourCodec, AColourImageThatIsNotWhatItSaysIsRefusedNamingWhy) {
  const ColourImage c = gradient();
  depth_frame_t f = frame_with(c, depth_frame_t::kColourJpeg);
  f.colour_width = 640;
  f.colour_height = 480;
  f.colour_cx = 320;
  f.colour_cy = 240;
  expect_refused(f, "DEPTH_FRAME 7 colour (jpeg) is 64 x 48, the frame says 640 x 480");
  f = frame_with(c, depth_frame_t::kColourJpeg);
  f.colour.assign(100, 0x55);
  expect_refused(f, "DEPTH_FRAME 7 colour (jpeg): the bytes are not a JPEG with a frame header");
  f = frame_with(c, depth_frame_t::kColourRgb8);
  f.colour.pop_back();
  expect_refused(f, "DEPTH_FRAME 7 colour: 9215 bytes (rgb8) for a 64 x 48 image (9216 wanted)");
  f = frame_with(c, depth_frame_t::kColourRgb8);
  f.colour_encoding = 5;
  expect_refused(f, "DEPTH_FRAME 7 colour_encoding = 5 is not one of its constants (0 none, 1 rgb8, 2 jpeg)");
  f = frame_with(c, depth_frame_t::kColourRgb8);
  f.colour_fx = std::nan("");
  expect_refused(f, "DEPTH_FRAME 7 colour intrinsics");
  f = frame_with(c, depth_frame_t::kColourRgb8);
  f.depth_T_colour.quat_wxyz[0] = 3;
  expect_refused(f, "DEPTH_FRAME 7 colour depth_T_colour");
}

}  // namespace
}  // namespace pbnbv
