// The camera a rig file states (RigModel::camera, <custom> pbnbv_camera / pbnbv_camera_id): read
// from both rig models with the twin's defaults, absent when not stated, and every bad value an
// error naming the file and the value.
#include <gtest/gtest.h>

#include <array>

#include <fstream>
#include <sstream>
#include <string>

#include "core/rig/rig.hpp"
#include "error_message.hpp"
#include "file_test_util.hpp"

namespace pbnbv {
namespace {

using testing::file_text;

// The arm rig's file with its pbnbv_camera line replaced by `line` ("" removes it), written to a
// temporary file; returns the path.
std::string arm_rig_with(const std::string& name, const std::string& line) {
  std::string text = file_text(default_rig_path(RigKind::kArm));
  const std::string needle = "<numeric name=\"pbnbv_camera\" data=\"1280 720 696 696 640 360 0.1 3.0\"/>";
  const std::size_t at = text.find(needle);
  EXPECT_NE(at, std::string::npos) << "models/rig_arm.xml no longer states the camera as expected";
  if (at != std::string::npos) text.replace(at, needle.size(), line);
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

TEST(RigCamera, BothModelsStateTheTwinsDefaultCamera) {
  for (RigKind kind : {RigKind::kArm, RigKind::kFree}) {
    const RigModel rig = load_rig(default_rig_path(kind));
    ASSERT_TRUE(rig.camera.has_value()) << to_string(kind);
    const RigCamera& c = *rig.camera;
    EXPECT_EQ(c.intrinsics.width, 1280);
    EXPECT_EQ(c.intrinsics.height, 720);
    EXPECT_EQ(c.intrinsics.fx, 696);
    EXPECT_EQ(c.intrinsics.fy, 696);
    EXPECT_EQ(c.intrinsics.cx, 640);
    EXPECT_EQ(c.intrinsics.cy, 360);
    EXPECT_EQ(c.range.min_m, 0.1);
    EXPECT_EQ(c.range.max_m, 3.0);
    EXPECT_EQ(c.id, "");
  }
}

TEST(RigCamera, OptionalAndWithAnId) {
  EXPECT_FALSE(load_rig(arm_rig_with("rig_no_camera.xml", "")).camera.has_value());
  const RigModel rig = load_rig(arm_rig_with(
      "rig_camera_id.xml",
      "<numeric name=\"pbnbv_camera\" data=\"640 480 380 381 320.5 240.5 0.2 4\"/>"
      "<text name=\"pbnbv_camera_id\" data=\"D435-123456\"/>"));
  ASSERT_TRUE(rig.camera.has_value());
  EXPECT_EQ(rig.camera->intrinsics.width, 640);
  EXPECT_EQ(rig.camera->intrinsics.fy, 381);
  EXPECT_EQ(rig.camera->intrinsics.cx, 320.5);
  EXPECT_EQ(rig.camera->range.max_m, 4);
  EXPECT_EQ(rig.camera->id, "D435-123456");
  EXPECT_FALSE(rig.camera->model.has_value());
}

// <text name="pbnbv_camera_model">: the camera the twin plays, by the names --camera takes.
TEST(RigCamera, ANamedCameraModel) {
  EXPECT_FALSE(load_rig(default_rig_path(RigKind::kArm)).camera->model.has_value());
  const RigModel rig = load_rig(arm_rig_with(
      "rig_camera_model.xml",
      "<numeric name=\"pbnbv_camera\" data=\"1280 720 674.4 674.4 640 360 0.28 3\"/>"
      "<text name=\"pbnbv_camera_model\" data=\"d435\"/>"));
  ASSERT_TRUE(rig.camera->model.has_value());
  EXPECT_EQ(*rig.camera->model, CameraKind::kD435);
  using testing::expect_error;
  const std::string unknown = arm_rig_with(
      "rig_camera_unknown_model.xml",
      "<numeric name=\"pbnbv_camera\" data=\"1280 720 696 696 640 360 0.1 3\"/>"
      "<text name=\"pbnbv_camera_model\" data=\"d455\"/>");
  expect_error([&] { load_rig(unknown); },
               "rig model " + unknown + ": pbnbv_camera_model \"d455\" is not a camera pbnbv knows (ideal, d405, d435, "
               "azure-kinect-nfov or structured-light)");
  const std::string lonely = arm_rig_with("rig_camera_lonely_model.xml", "<text name=\"pbnbv_camera_model\" data=\"d435\"/>");
  expect_error([&] { load_rig(lonely); }, "pbnbv_camera_model is given without");
}

// <numeric name="pbnbv_camera_distortion" data="k1 k2 p1 p2 k3">: the lens the camera's frames come
// through; none unless given; a lens that folds the image over is refused with the file's name.
TEST(RigCamera, ALensDistortion) {
  EXPECT_TRUE(load_rig(default_rig_path(RigKind::kArm)).camera->distortion.none());
  const RigModel rig = load_rig(arm_rig_with(
      "rig_camera_lens.xml",
      "<numeric name=\"pbnbv_camera\" data=\"640 576 504 504 320 288 0.5 3.86\"/>"
      "<numeric name=\"pbnbv_camera_distortion\" data=\"-0.3 0.1 0.001 -0.002 -0.02\"/>"));
  EXPECT_EQ(rig.camera->distortion.coefficients(), (std::array<double, 5>{-0.3, 0.1, 0.001, -0.002, -0.02}));
  using testing::expect_error;
  const std::string folded = arm_rig_with(
      "rig_camera_folded_lens.xml",
      "<numeric name=\"pbnbv_camera\" data=\"640 576 300 300 320 288 0.5 3.86\"/>"
      "<numeric name=\"pbnbv_camera_distortion\" data=\"-1.5 0 0 0 0\"/>");
  expect_error([&] { load_rig(folded); }, "rig model " + folded + ": pbnbv_camera_distortion (data=\"k1 k2 p1 p2 k3\"): "
                                          "distortion k1 k2 k3 = -1.5 0 0 fold the image over");
  const std::string lonely =
      arm_rig_with("rig_camera_lonely_lens.xml", "<numeric name=\"pbnbv_camera_distortion\" data=\"0 0 0 0 0\"/>");
  expect_error([&] { load_rig(lonely); }, "pbnbv_camera_distortion is given without");
}

TEST(RigCamera, BadValuesNameTheFileAndTheValue) {
  using testing::expect_error;
  const std::string few = arm_rig_with("rig_camera_few.xml", "<numeric name=\"pbnbv_camera\" data=\"1280 720 696\"/>");
  expect_error([&] { load_rig(few); }, "rig model " + few + ": custom numeric pbnbv_camera has 3 values, expected 8");
  const std::string half =
      arm_rig_with("rig_camera_half.xml", "<numeric name=\"pbnbv_camera\" data=\"1280.5 720 696 696 640 360 0.1 3\"/>");
  expect_error([&] { load_rig(half); }, "pbnbv_camera width = 1280.5");
  const std::string cx =
      arm_rig_with("rig_camera_cx.xml", "<numeric name=\"pbnbv_camera\" data=\"1280 720 696 696 1300 360 0.1 3\"/>");
  expect_error([&] { load_rig(cx); }, "cx");
  const std::string range =
      arm_rig_with("rig_camera_range.xml", "<numeric name=\"pbnbv_camera\" data=\"1280 720 696 696 640 360 3 0.1\"/>");
  expect_error([&] { load_rig(range); }, "depth range [3, 0.1] m is invalid");
  const std::string lonely = arm_rig_with("rig_camera_lonely_id.xml", "<text name=\"pbnbv_camera_id\" data=\"X\"/>");
  expect_error([&] { load_rig(lonely); }, "pbnbv_camera_id is given without");
}

}  // namespace
}  // namespace pbnbv
