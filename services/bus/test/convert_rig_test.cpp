// The rig channels <-> plain readings and commands: the fields carried over, and every
// validation failure naming the message and the field.
#include "bus/convert_rig.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace pbnbv {
namespace {

arm_status_t arm_status() {
  arm_status_t m;
  m.utime = 123456;
  m.driver_utime = 789;
  m.seq = 9;
  m.num_joints = 6;
  m.joint_names = {"a1", "a2", "a3", "a4", "a5", "a6"};
  m.joint_position_rad = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6};
  m.joint_velocity_rad_s = {0, 0, 0.02, 0, 0, 0};
  m.joint_position_commanded_rad = m.joint_position_rad;
  m.command_seq = 41;
  m.mode = arm_status_t::kModeSettled;
  m.fault_code = arm_status_t::kFaultNone;
  m.fault_command_seq = -1;
  m.contacts = 0;
  return m;
}

turntable_status_t turntable_status() {
  turntable_status_t m;
  m.utime = 123456;
  m.driver_utime = 790;
  m.seq = 9;
  m.angle_rad = 1.25;
  m.velocity_rad_s = -0.5;
  m.angle_commanded_rad = 1.25;
  m.command_seq = 41;
  m.mode = turntable_status_t::kModeMoving;
  m.fault_code = turntable_status_t::kFaultNone;
  m.fault_command_seq = -1;
  return m;
}

// The message of the std::invalid_argument `f` throws ("" when it does not).
template <class F>
std::string error_of(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(ConvertRig, ArmStatusFieldsCarryOver) {
  arm_status_t m = arm_status();
  m.mode = arm_status_t::kModeFault;
  m.fault_code = arm_status_t::kFaultOutOfLimits;
  m.fault_command_seq = 42;
  m.fault = "rejected ARM_COMMAND seq 42: joint a3 target 10 is outside its limits";
  const ArmReading r = bus::from_msg(m);
  EXPECT_EQ(r.utime, 123456);
  EXPECT_EQ(r.driver_utime, 789);
  EXPECT_EQ(r.joint_position_rad[2], 0.3);
  EXPECT_EQ(r.joint_velocity_rad_s[2], 0.02);
  EXPECT_EQ(r.command_seq, 41);
  EXPECT_EQ(r.mode, RigMode::kFault);
  EXPECT_EQ(r.fault_code, RigFault::kOutOfLimits);
  EXPECT_EQ(r.fault_command_seq, 42);
  EXPECT_EQ(r.fault, m.fault);
}

// A contact: kFaultContact on the command it stopped, the count and the last one's text carry
// over, through an encoding and the message guard's check as every receiver decodes them.
TEST(ConvertRig, AContactCarriesOverWithItsCountAndText) {
  arm_status_t m = arm_status();
  m.mode = arm_status_t::kModeFault;
  m.fault_code = arm_status_t::kFaultContact;
  m.fault_command_seq = 41;
  m.fault = "contact: camera_optical / table, 1.4 mm deep, at rig time 12.345 s, during command 41";
  m.contacts = 3;
  m.last_contact = "camera_optical / table, 1.4 mm deep, at rig time 12.345 s, during command 41";
  std::vector<uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_EQ(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  arm_status_t decoded;
  std::string why;
  ASSERT_TRUE(bus::decode_checked("ARM_STATUS", bytes.data(), static_cast<int64_t>(bytes.size()), &decoded, &why)) << why;
  const ArmReading r = bus::from_msg(decoded);
  EXPECT_EQ(r.mode, RigMode::kFault);
  EXPECT_EQ(r.fault_code, RigFault::kContact);
  EXPECT_EQ(std::string(to_string(r.fault_code)), "contact");
  EXPECT_EQ(r.fault_command_seq, 41);
  EXPECT_EQ(r.contacts, 3);
  EXPECT_EQ(r.last_contact, m.last_contact);
  EXPECT_EQ(static_cast<int>(RigFault::kContact), arm_status_t::kFaultContact);
  // A driver that cannot tell.
  m = arm_status();
  m.contacts = -1;
  EXPECT_EQ(bus::from_msg(m).contacts, -1);
  // Cut short inside the text: the guard refuses it before the decoder sizes a string from it.
  bytes.resize(bytes.size() - 10);
  EXPECT_FALSE(bus::decode_checked("ARM_STATUS", bytes.data(), static_cast<int64_t>(bytes.size()), &decoded, &why));
  EXPECT_NE(why.find("arm_status_t.last_contact"), std::string::npos) << why;
}

TEST(ConvertRig, TurntableStatusHasItsOwnConstantsWithTheSameMeaning) {
  turntable_status_t m = turntable_status();
  const TurntableReading r = bus::from_msg(m);
  EXPECT_EQ(r.driver_utime, 790);
  EXPECT_EQ(r.angle_rad, 1.25);
  EXPECT_EQ(r.velocity_rad_s, -0.5);
  EXPECT_EQ(r.mode, RigMode::kMoving);
  EXPECT_EQ(r.fault_code, RigFault::kNone);
  m.mode = turntable_status_t::kModeFault;
  m.fault_code = turntable_status_t::kFaultDriver;
  m.fault_command_seq = 41;
  EXPECT_EQ(bus::from_msg(m).fault_code, RigFault::kDriver);
  EXPECT_EQ(bus::from_msg(m).fault_command_seq, 41);
  // The plain enums follow both messages' constants.
  EXPECT_EQ(static_cast<int>(RigMode::kSettled), turntable_status_t::kModeSettled);
  EXPECT_EQ(static_cast<int>(RigMode::kSettled), arm_status_t::kModeSettled);
  EXPECT_EQ(static_cast<int>(RigFault::kCommandRejected), turntable_status_t::kFaultCommandRejected);
  EXPECT_EQ(static_cast<int>(RigFault::kDriver), arm_status_t::kFaultDriver);
  EXPECT_EQ(static_cast<int>(RigFault::kOutOfLimits), arm_status_t::kFaultOutOfLimits);
  EXPECT_EQ(static_cast<int>(RigFault::kOutOfLimits), turntable_status_t::kFaultOutOfLimits);
}

TEST(ConvertRig, MalformedStatusesAreRejectedNamingTheField) {
  arm_status_t m = arm_status();
  m.joint_position_rad[4] = std::nan("");
  EXPECT_EQ(error_of([&] { bus::from_msg(m); }), "ARM_STATUS joint_position_rad: joint 4 value nan is not finite");
  m = arm_status();
  m.mode = 7;
  EXPECT_EQ(error_of([&] { bus::from_msg(m); }), "ARM_STATUS mode = 7 is not one of its constants (0..3)");
  m = arm_status();
  m.fault_code = 9;
  EXPECT_EQ(error_of([&] { bus::from_msg(m); }), "ARM_STATUS fault_code = 9 is not one of its constants (0..4)");
  m = arm_status();
  m.contacts = -2;
  EXPECT_EQ(error_of([&] { bus::from_msg(m); }), "ARM_STATUS contacts = -2 is below -1 (-1: the rig cannot tell)");
  m = arm_status();
  m.last_contact = "link_6 / platter";  // a text with no contact counted
  EXPECT_EQ(error_of([&] { bus::from_msg(m); }),
            "ARM_STATUS last_contact is given with ARM_STATUS contacts = 0 (only with a contact counted)");
  m = arm_status();
  m.mode = arm_status_t::kModeFault;  // a fault without its code
  EXPECT_NE(error_of([&] { bus::from_msg(m); }).find("fault_code = 0 disagrees with mode = 3"), std::string::npos);
  m = arm_status();
  m.fault_code = arm_status_t::kFaultDriver;  // a code without the fault mode
  EXPECT_NE(error_of([&] { bus::from_msg(m); }).find("fault_code = 2 disagrees with mode = 2"), std::string::npos);

  turntable_status_t t = turntable_status();
  t.angle_rad = INFINITY;
  EXPECT_NE(error_of([&] { bus::from_msg(t); }).find("TURNTABLE_STATUS angle_rad = inf"), std::string::npos);
  t = turntable_status();
  t.velocity_rad_s = std::nan("");
  EXPECT_NE(error_of([&] { bus::from_msg(t); }).find("TURNTABLE_STATUS velocity_rad_s"), std::string::npos);
  t = turntable_status();
  t.mode = -1;
  EXPECT_EQ(error_of([&] { bus::from_msg(t); }), "TURNTABLE_STATUS mode = -1 is not one of its constants (0..3)");
  t = turntable_status();
  t.mode = turntable_status_t::kModeFault;
  t.fault_code = 4;  // kFaultContact is the arm's only
  EXPECT_EQ(error_of([&] { bus::from_msg(t); }), "TURNTABLE_STATUS fault_code = 4 is not one of its constants (0..3)");
}

TEST(ConvertRig, CommandsArePositionCommandsWithTheirSequenceNumber) {
  ArmCommand a;
  a.seq = 77;
  a.joint_position_rad << 1, 2, 3, 4, 5, 6;
  a.speed_scale = 0.25;
  const arm_command_t m = bus::to_msg(a);
  EXPECT_EQ(m.seq, 77);
  EXPECT_EQ(m.num_joints, 6);
  EXPECT_EQ(m.joint_position_rad, std::vector<double>({1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(m.speed_scale, 0.25);
  EXPECT_EQ(m.mode, arm_command_t::kModePosition);
  TurntableCommand t;
  t.seq = 77;
  t.angle_rad = -3.5;
  t.speed_scale = 0.5;
  const turntable_command_t tm = bus::to_msg(t);
  EXPECT_EQ(tm.seq, 77);
  EXPECT_EQ(tm.angle_rad, -3.5);
  EXPECT_EQ(tm.speed_scale, 0.5);
}

// A 2 x 1 frame (f = 10 px, 0.1 mm units) without its depth bytes.
depth_frame_t two_pixel_frame(int8_t encoding) {
  depth_frame_t m{};
  m.utime = 5;
  m.exposure_start_utime = 4;
  m.exposure_us = 2;
  m.camera_id = "test-camera";
  m.seq = 6;
  m.trigger_seq = 7;
  m.width = 2;
  m.height = 1;
  m.fx = m.fy = 10;
  m.cx = 1;
  m.cy = 0.5;
  m.depth_min_m = 0.1;
  m.depth_max_m = 3;
  m.depth_unit_m = 1e-4;
  m.encoding = encoding;
  return m;
}

TEST(ConvertRig, DepthFrameIsDecodedToMetres) {
  depth_frame_t m = two_pixel_frame(depth_frame_t::kEncodingRaw);
  m.num_bytes = 4;
  m.depth = {0x10, 0x27, 0, 0};  // 10000 counts = 1 m; 0 = no return
  const DepthFrame f = bus::from_msg(m);
  EXPECT_EQ(f.utime, 5);
  EXPECT_EQ(f.seq, 6);
  EXPECT_EQ(f.trigger_seq, 7);
  EXPECT_EQ(f.exposure_start_utime, 4);
  EXPECT_EQ(f.exposure_us, 2);
  EXPECT_EQ(f.camera_id, "test-camera");
  EXPECT_EQ(f.intrinsics.width, 2);
  ASSERT_EQ(f.depth_m.size(), 2u);
  EXPECT_FLOAT_EQ(f.depth_m[0], 1.0f);
  EXPECT_EQ(f.depth_m[1], 0.0f);  // no return
  m.depth_unit_m = 0;
  EXPECT_NE(error_of([&] { bus::from_msg(m); }).find("depth_unit"), std::string::npos);
}

// The same image compressed (what the twin sends) decodes to the same metres; compressed data
// that is corrupt, or holds an image of another size, and an unknown encoding are named.
TEST(ConvertRig, AZlibDepthFrameDecodesToTheSameMetresAndBadDataIsNamed) {
  depth_frame_t m = two_pixel_frame(depth_frame_t::kEncodingZlib);
  m.depth = bus::deflate_bytes({0x10, 0x27, 0x88, 0x13});  // 1 m, 0.5 m
  m.num_bytes = static_cast<int32_t>(m.depth.size());
  const DepthFrame f = bus::from_msg(m);
  ASSERT_EQ(f.depth_m.size(), 2u);
  EXPECT_FLOAT_EQ(f.depth_m[0], 1.0f);
  EXPECT_FLOAT_EQ(f.depth_m[1], 0.5f);

  depth_frame_t longer = m;
  longer.depth = bus::deflate_bytes({1, 0, 2, 0, 3, 0});  // three pixels for a 2 x 1 image
  EXPECT_EQ(error_of([&] { bus::from_msg(longer); }),
            "DEPTH_FRAME 6 depth (zlib) inflates to more than 4 bytes, the image needs 4");
  depth_frame_t shorter = m;
  shorter.depth = bus::deflate_bytes({1, 0});
  EXPECT_EQ(error_of([&] { bus::from_msg(shorter); }), "DEPTH_FRAME 6 depth (zlib) inflates to 2 bytes, the image needs 4");
  depth_frame_t corrupt = m;
  corrupt.depth = {0x10, 0x27, 0x88, 0x13};  // raw bytes labelled zlib
  EXPECT_NE(error_of([&] { bus::from_msg(corrupt); }).find("DEPTH_FRAME 6 depth (zlib) is not valid zlib data"),
            std::string::npos);
  depth_frame_t unknown = m;
  unknown.encoding = 7;
  EXPECT_EQ(error_of([&] { bus::from_msg(unknown); }),
            "DEPTH_FRAME 6 encoding = 7 is not one of its constants (0 raw, 1 zlib)");
}

}  // namespace
}  // namespace pbnbv
