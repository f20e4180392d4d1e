// PNG and JPEG through libpng and libjpeg: round trips to the sample, the bytes a PNG header must
// hold (read by hand), OpenCV's decoder reading what we write and ours reading what OpenCV
// writes, and every broken or oversized input refused naming it.
#include "core/io/image_codec.hpp"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdlib>
#include <functional>
#include <stdexcept>
#include <string>

#include "error_message.hpp"

namespace pbnbv {
namespace {

using testing::error_message;

// A 5 x 3 ramp of 16-bit samples whose two bytes differ (0x0102, 0x0103, ...) and the extremes:
// a byte-order mistake anywhere shows.
std::vector<uint16_t> ramp16() {
  std::vector<uint16_t> s(15);
  for (std::size_t i = 0; i < s.size(); ++i) s[i] = static_cast<uint16_t>(0x0102 + 257 * i);
  s[0] = 0;
  s[14] = 65535;
  return s;
}

uint32_t be32(const std::vector<uint8_t>& b, std::size_t at) {
  return (uint32_t{b[at]} << 24) | (uint32_t{b[at + 1]} << 16) | (uint32_t{b[at + 2]} << 8) | b[at + 3];
}

// CRC-32 of PNG chunks (ISO 3309, the polynomial 0xEDB88320 reflected), bit by bit.
uint32_t crc32(const uint8_t* p, std::size_t n) {
  uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? (c >> 1) ^ 0xEDB88320u : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

TEST(ImageCodec, ASixteenBitGreyPngHoldsItsHeaderAndComesBackToTheSample) {
  const std::vector<uint16_t> s = ramp16();
  const std::vector<uint8_t> png = encode_png(s.data(), 5, 3, PngPixels::kGray16, 6, "ramp");
  // Signature, then IHDR: length 13, "IHDR", width, height, bit depth, colour type 0 (grey).
  ASSERT_GT(png.size(), 33u);
  EXPECT_EQ(std::vector<uint8_t>(png.begin(), png.begin() + 8),
            (std::vector<uint8_t>{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'}));
  EXPECT_EQ(be32(png, 8), 13u);
  EXPECT_EQ(std::string(png.begin() + 12, png.begin() + 16), "IHDR");
  EXPECT_EQ(be32(png, 16), 5u);
  EXPECT_EQ(be32(png, 20), 3u);
  EXPECT_EQ(png[24], 16);
  EXPECT_EQ(png[25], 0);
  EXPECT_EQ(be32(png, 29), crc32(png.data() + 12, 17));
  const Gray16Image back = decode_png_gray16(png.data(), png.size(), "ramp", 100);
  EXPECT_EQ(back.width, 5);
  EXPECT_EQ(back.height, 3);
  EXPECT_EQ(back.samples, s);
  // OpenCV's decoder reads the same samples (row 1, column 2 is sample 7: 0x0102 + 7 * 257).
  const cv::Mat cv16 = cv::imdecode(png, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(cv16.type(), CV_16UC1);
  EXPECT_EQ(cv16.at<uint16_t>(1, 2), 0x0102 + 7 * 257);
  EXPECT_EQ(cv16.at<uint16_t>(2, 4), 65535);
  EXPECT_EQ(cv16.at<uint16_t>(0, 0), 0);
}

TEST(ImageCodec, APngOpenCvWroteIsReadSampleForSample) {
  cv::Mat m(3, 5, CV_16UC1);
  const std::vector<uint16_t> s = ramp16();
  for (int v = 0; v < 3; ++v)
    for (int u = 0; u < 5; ++u) m.at<uint16_t>(v, u) = s[static_cast<std::size_t>(v * 5 + u)];
  std::vector<uint8_t> png;
  ASSERT_TRUE(cv::imencode(".png", m, png));
  const Gray16Image back = decode_png_gray16(png.data(), png.size(), "opencv", 100);
  EXPECT_EQ(back.samples, s);
}

TEST(ImageCodec, ColourPngsKeepTheirChannelOrder) {
  // One pixel R 10, G 20, B 30 given as R G B; the same bytes given as B G R mean R 30, B 10.
  const uint8_t px[3] = {10, 20, 30};
  const cv::Mat rgb = cv::imdecode(encode_png(px, 1, 1, PngPixels::kRgb8, 6, "rgb"), cv::IMREAD_COLOR);
  const cv::Mat bgr = cv::imdecode(encode_png(px, 1, 1, PngPixels::kBgr8, 6, "bgr"), cv::IMREAD_COLOR);
  ASSERT_EQ(rgb.type(), CV_8UC3);
  EXPECT_EQ(rgb.at<cv::Vec3b>(0, 0), cv::Vec3b(30, 20, 10));  // OpenCV hands back B G R
  EXPECT_EQ(bgr.at<cv::Vec3b>(0, 0), cv::Vec3b(10, 20, 30));
  const uint8_t grey[2] = {7, 250};
  const cv::Mat g = cv::imdecode(encode_png(grey, 2, 1, PngPixels::kGray8, 6, "grey"), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(g.type(), CV_8UC1);
  EXPECT_EQ(g.at<uint8_t>(0, 1), 250);
}

TEST(ImageCodec, ABrokenOrOversizedPngIsRefusedNamingIt) {
  const std::vector<uint16_t> s = ramp16();
  const std::vector<uint8_t> png = encode_png(s.data(), 5, 3, PngPixels::kGray16, 6, "ramp");
  const std::vector<uint8_t> half(png.begin(), png.begin() + static_cast<long>(png.size() / 2));
  EXPECT_EQ(error_message([&] { decode_png_gray16(half.data(), half.size(), "depth/view_001.png", 100); }),
            "depth/view_001.png: a broken PNG (libpng: the PNG ends early (truncated))");
  const std::vector<uint8_t> text = {'h', 'e', 'l', 'l', 'o', ' ', 'p', 'n', 'g', '!'};
  EXPECT_EQ(error_message([&] { decode_png_gray16(text.data(), text.size(), "x.png", 100); }),
            "x.png: not a PNG (10 bytes that do not begin with the PNG signature)");
  // 15 pixels against a bound of 14.
  EXPECT_EQ(error_message([&] { decode_png_gray16(png.data(), png.size(), "ramp", 14); }),
            "ramp: declares 5 x 3 pixels, more than the 14 allowed");
  // A header that claims 100000 x 100000 (its CRC made right) is refused before anything is
  // allocated.
  std::vector<uint8_t> huge = png;
  for (std::size_t at : {std::size_t{16}, std::size_t{20}}) {
    huge[at] = 0;
    huge[at + 1] = 0x01;
    huge[at + 2] = 0x86;
    huge[at + 3] = 0xA0;  // 100000
  }
  const uint32_t crc = crc32(huge.data() + 12, 17);
  for (int k = 0; k < 4; ++k) huge[static_cast<std::size_t>(29 + k)] = static_cast<uint8_t>(crc >> (24 - 8 * k));
  EXPECT_EQ(error_message([&] { decode_png_gray16(huge.data(), huge.size(), "huge", int64_t{64} << 20); }),
            "huge: declares 100000 x 100000 pixels, more than the 67108864 allowed");
  // An 8-bit colour PNG is not a depth image.
  const uint8_t px[3] = {1, 2, 3};
  const std::vector<uint8_t> colour = encode_png(px, 1, 1, PngPixels::kRgb8, 6, "c");
  EXPECT_EQ(error_message([&] { decode_png_gray16(colour.data(), colour.size(), "colour.png", 100); }),
            "colour.png: holds 8-bit colour samples, not 16-bit grey (one channel)");
  EXPECT_EQ(error_message([&] { encode_png(px, 0, 1, PngPixels::kRgb8, 6, "empty"); }),
            "encode_png: empty: 0 x 1 is not an image size (1..65535 a side)");
  EXPECT_EQ(error_message([&] { encode_png(px, 1, 1, PngPixels::kRgb8, 10, "level"); }),
            "encode_png: level: compression 10 is not a zlib level (0..9)");
}

// A flat colour (R 200, G 100, B 50) as JPEG: every pixel back within a few levels, in our decoder
// and in OpenCV's; the frame header says 32 x 16.
TEST(ImageCodec, AFlatColourJpegComesBackWithinAFewLevels) {
  std::vector<uint8_t> rgb(32 * 16 * 3);
  for (std::size_t i = 0; i < rgb.size(); i += 3) {
    rgb[i] = 200;
    rgb[i + 1] = 100;
    rgb[i + 2] = 50;
  }
  const std::vector<uint8_t> jpeg = encode_jpeg(rgb.data(), 32, 16, 90, "flat");
  ASSERT_GT(jpeg.size(), 4u);
  EXPECT_EQ(jpeg[0], 0xFF);
  EXPECT_EQ(jpeg[1], 0xD8);
  const Rgb8Image back = decode_jpeg_rgb(jpeg.data(), jpeg.size(), "flat", 1000);
  EXPECT_EQ(back.width, 32);
  EXPECT_EQ(back.height, 16);
  ASSERT_EQ(back.rgb.size(), rgb.size());
  int worst = 0;
  for (std::size_t i = 0; i < rgb.size(); ++i) worst = std::max(worst, std::abs(back.rgb[i] - rgb[i]));
  EXPECT_LE(worst, 3);
  const cv::Mat cv8 = cv::imdecode(jpeg, cv::IMREAD_COLOR);
  ASSERT_EQ(cv8.size(), cv::Size(32, 16));
  const cv::Vec3b p = cv8.at<cv::Vec3b>(8, 16);
  EXPECT_NEAR(p[0], 50, 3);
  EXPECT_NEAR(p[2], 200, 3);
  // And a JPEG OpenCV wrote (from B G R) decodes to the same colour in R G B.
  std::vector<uint8_t> theirs;
  ASSERT_TRUE(cv::imencode(".jpg", cv::Mat(16, 32, CV_8UC3, cv::Scalar(50, 100, 200)), theirs));
  const Rgb8Image ours = decode_jpeg_rgb(theirs.data(), theirs.size(), "opencv", 1000);
  EXPECT_NEAR(ours.rgb[0], 200, 3);
  EXPECT_NEAR(ours.rgb[1], 100, 3);
  EXPECT_NEAR(ours.rgb[2], 50, 3);
}

TEST(ImageCodec, ABrokenOrOversizedJpegIsRefusedNamingIt) {
  std::vector<uint8_t> rgb(64 * 48 * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<uint8_t>(i * 7);
  const std::vector<uint8_t> jpeg = encode_jpeg(rgb.data(), 64, 48, 90, "noise");
  const std::vector<uint8_t> half(jpeg.begin(), jpeg.begin() + static_cast<long>(jpeg.size() / 2));
  EXPECT_EQ(error_message([&] { decode_jpeg_rgb(half.data(), half.size(), "DEPTH_FRAME 3 colour (jpeg)", 10000); }),
            "DEPTH_FRAME 3 colour (jpeg): a broken JPEG (libjpeg: Premature end of JPEG file)");
  const std::vector<uint8_t> head(jpeg.begin(), jpeg.begin() + 20);
  EXPECT_NE(error_message([&] { decode_jpeg_rgb(head.data(), head.size(), "head", 10000); }).find("head: a broken JPEG"),
            std::string::npos);
  const std::vector<uint8_t> text = {'n', 'o', 't', ' ', 'j', 'p', 'e', 'g'};
  EXPECT_EQ(error_message([&] { decode_jpeg_rgb(text.data(), text.size(), "t", 10000); }),
            "t: not a JPEG (8 bytes that do not begin with a start-of-image marker)");
  EXPECT_EQ(error_message([&] { decode_jpeg_rgb(jpeg.data(), jpeg.size(), "noise", 3071); }),
            "noise: declares 64 x 48 pixels, more than the 3071 allowed");
  EXPECT_EQ(error_message([&] { encode_jpeg(rgb.data(), 64, 48, 0, "q"); }), "encode_jpeg: q: quality 0 is not in 1..100");
}

}  // namespace
}  // namespace pbnbv
