// The depth camera model: how a frame's uint16 counts decode into metres.
#include "core/geometry/camera_model.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

using namespace pbnbv;

TEST(CameraModel, DecodesLittleEndianCountsAndRejectsABadFrame) {
  const std::vector<uint8_t> bytes = {0x10, 0x27, 0x00, 0x00, 0xff, 0xff, 0x01, 0x00};  // 10000, 0, 65535, 1
  const std::vector<float> d = decode_depth_u16(bytes, 2, 2, 1e-4);
  EXPECT_FLOAT_EQ(d[0], 1.0f);
  EXPECT_FLOAT_EQ(d[1], 0.0f);
  EXPECT_NEAR(d[2], 6.5535f, 1e-6);
  EXPECT_NEAR(d[3], 1e-4f, 1e-9);
  try {
    decode_depth_u16(bytes, 3, 2, 1e-4);
    FAIL() << "a size mismatch must throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("8 bytes"), std::string::npos) << e.what();
  }
  EXPECT_THROW(decode_depth_u16(bytes, 2, 2, 0.0), std::invalid_argument);
  EXPECT_THROW(decode_depth_u16({}, 0, 0, 1e-4), std::invalid_argument);
}
