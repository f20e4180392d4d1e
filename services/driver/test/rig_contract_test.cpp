// The rig contract as the driver library speaks it: statuses with both clocks, the command echoed
// and faults by code; commands checked as lcmtypes/ says; a depth image as the frame answering a
// trigger, stamped with its exposure, that the pipeline's decoder reads back to the depths given.
#include "driver/rig_contract.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "bus/convert.hpp"
#include "error_message.hpp"

namespace pbnbv::driver {
namespace {

using pbnbv::testing::expect_error;

ArmReading two_joints(Motion motion) {
  ArmReading r;
  r.joint_names = {"a1", "a2"};
  r.position_rad = {0.1, -0.2};
  r.velocity_rad_s = {0.0, 0.5};
  r.commanded_rad = {0.1, 0.3};
  r.command_seq = 41;
  r.motion = motion;
  return r;
}

TEST(RigContract, StatusesCarryBothClocksTheEchoAndTheMotion) {
  const Stamp stamp{1700000000123456, 987654};
  const arm_status_t s = arm_status(stamp, 7, "scan-a", two_joints(Motion::kMoving), FaultLatch{});
  EXPECT_EQ(s.utime, 1700000000123456);
  EXPECT_EQ(s.driver_utime, 987654);
  EXPECT_EQ(s.seq, 7);
  EXPECT_EQ(s.scan_id, "scan-a");
  EXPECT_EQ(s.num_joints, 2);
  EXPECT_EQ(s.joint_position_commanded_rad[1], 0.3);
  EXPECT_EQ(s.command_seq, 41);
  EXPECT_EQ(s.mode, arm_status_t::kModeMoving);
  EXPECT_EQ(s.fault_code, arm_status_t::kFaultNone);
  EXPECT_EQ(s.fault_command_seq, -1);
  EXPECT_EQ(arm_status(stamp, 8, "", two_joints(Motion::kSettled), FaultLatch{}).mode, arm_status_t::kModeSettled);
  EXPECT_EQ(arm_status(stamp, 9, "", two_joints(Motion::kIdle), FaultLatch{}).mode, arm_status_t::kModeIdle);

  TurntableReading t;
  t.angle_rad = 1.25;
  t.commanded_rad = 1.5;
  t.command_seq = 3;
  t.motion = Motion::kSettled;
  const turntable_status_t ts = turntable_status(stamp, 7, "scan-a", t, FaultLatch{});
  EXPECT_EQ(ts.utime, stamp.utime);
  EXPECT_EQ(ts.driver_utime, stamp.driver_utime);
  EXPECT_EQ(ts.angle_rad, 1.25);
  EXPECT_EQ(ts.angle_commanded_rad, 1.5);
  EXPECT_EQ(ts.command_seq, 3);
  EXPECT_EQ(ts.mode, turntable_status_t::kModeSettled);

  ArmReading short_one = two_joints(Motion::kIdle);
  short_one.velocity_rad_s.pop_back();
  expect_error([&] { arm_status(stamp, 1, "", short_one, FaultLatch{}); },
               "arm_status: 2 joint names, 2 positions, 1 velocities, 2 targets");
}

TEST(RigContract, AFaultIsReportedByCodeUntilCleared) {
  FaultLatch fault;
  fault.set(FaultCode::kOutOfLimits, 12, "rejected ARM_COMMAND seq 12: joint a5 target 2.18 is outside its limits");
  const arm_status_t s = arm_status(Stamp{}, 1, "", two_joints(Motion::kSettled), fault);
  EXPECT_EQ(s.mode, arm_status_t::kModeFault);
  EXPECT_EQ(s.fault_code, arm_status_t::kFaultOutOfLimits);
  EXPECT_EQ(s.fault_command_seq, 12);
  EXPECT_EQ(s.fault, "rejected ARM_COMMAND seq 12: joint a5 target 2.18 is outside its limits");
  EXPECT_EQ(s.command_seq, 41);  // the last accepted command is still the one echoed
  fault.set(FaultCode::kDriver, -1, "following error on a3");
  const turntable_status_t t = turntable_status(Stamp{}, 1, "", TurntableReading{}, fault);
  EXPECT_EQ(t.mode, turntable_status_t::kModeFault);
  EXPECT_EQ(t.fault_code, turntable_status_t::kFaultDriver);
  fault.clear();
  const arm_status_t cleared = arm_status(Stamp{}, 2, "", two_joints(Motion::kSettled), fault);
  EXPECT_EQ(cleared.mode, arm_status_t::kModeSettled);
  EXPECT_EQ(cleared.fault_code, arm_status_t::kFaultNone);
  EXPECT_EQ(cleared.fault_command_seq, -1);
  EXPECT_EQ(cleared.fault, "");
}

// A contact: kFaultContact on the command the arm was executing, with the count and the last
// one's text in every status; a driver that cannot tell says -1 (the reading's default); a count
// below -1, a text with no contact, or a turntable kFaultContact is the driver's error.
TEST(RigContract, AContactIsAFaultOfTheArmWithItsCount) {
  ArmReading r = two_joints(Motion::kSettled);
  EXPECT_EQ(arm_status(Stamp{}, 1, "", r, FaultLatch{}).contacts, -1) << "a driver that cannot tell";
  FaultLatch fault;
  fault.set(FaultCode::kContact, 41, "contact: link_6 / platter, 3.2 mm deep, at rig time 12.345 s, during command 41");
  r.contacts = 2;
  r.last_contact = "link_6 / platter, 3.2 mm deep, at rig time 12.345 s, during command 41";
  const arm_status_t s = arm_status(Stamp{}, 2, "", r, fault);
  EXPECT_EQ(s.mode, arm_status_t::kModeFault);
  EXPECT_EQ(s.fault_code, arm_status_t::kFaultContact);
  EXPECT_EQ(s.fault_command_seq, 41);
  EXPECT_EQ(s.contacts, 2);
  EXPECT_EQ(s.last_contact, r.last_contact);
  ArmReading bad = r;
  bad.contacts = -2;
  expect_error([&] { arm_status(Stamp{}, 3, "", bad, FaultLatch{}); }, "arm_status: contacts -2");
  bad = r;
  bad.contacts = 0;
  expect_error([&] { arm_status(Stamp{}, 3, "", bad, FaultLatch{}); }, "arm_status: a last contact");
  expect_error([&] { turntable_status(Stamp{}, 3, "", TurntableReading{}, fault); },
               "turntable_status: fault kContact is the arm's");
}

arm_command_t arm_command(int joints) {
  arm_command_t c{};
  c.seq = 5;
  c.mode = arm_command_t::kModePosition;
  c.num_joints = joints;
  c.joint_position_rad.assign(static_cast<std::size_t>(joints), 0.25);
  c.speed_scale = 0.5;
  return c;
}

TEST(RigContract, CommandsAreCheckedAsTheContractSays) {
  const ArmTarget t = arm_target(arm_command(6), 6);
  EXPECT_FALSE(t.hold);
  EXPECT_EQ(t.position_rad, std::vector<double>(6, 0.25));
  EXPECT_EQ(t.speed_scale, 0.5);
  EXPECT_EQ(t.seq, 5);
  arm_command_t hold = arm_command(0);
  hold.mode = arm_command_t::kModeHold;
  EXPECT_TRUE(arm_target(hold, 6).hold);
  arm_command_t c = arm_command(6);
  c.mode = 4;
  expect_error([&] { arm_target(c, 6); }, "unknown mode 4");
  expect_error([&] { arm_target(arm_command(5), 6); }, "num_joints = 5, this arm has 6");
  c = arm_command(6);
  c.joint_position_rad[3] = std::numeric_limits<double>::quiet_NaN();
  expect_error([&] { arm_target(c, 6); }, "joint_position_rad: joint 3 value nan is not finite");
  for (double bad : {0.0, -0.1, 1.5}) {
    c = arm_command(6);
    c.speed_scale = bad;
    expect_error([&] { arm_target(c, 6); }, "is outside (0, 1]");
    EXPECT_EQ(arm_target(c, 6, true).speed_scale, bad) << "passed on when the driver clamps it itself";
  }
  c.speed_scale = std::numeric_limits<double>::quiet_NaN();
  expect_error([&] { arm_target(c, 6, true); }, "ARM_COMMAND speed_scale nan is not finite");
  turntable_command_t tc{};
  tc.seq = 9;
  tc.angle_rad = -7.5;  // not wrapped: the driver turns the long way as given
  tc.speed_scale = 1;
  EXPECT_EQ(turntable_target(tc).angle_rad, -7.5);
  tc.speed_scale = 2;
  expect_error([&] { turntable_target(tc); }, "TURNTABLE_COMMAND speed_scale 2 is outside (0, 1]");
  tc.speed_scale = 1;
  tc.angle_rad = std::numeric_limits<double>::infinity();
  expect_error([&] { turntable_target(tc); }, "angle_rad inf is not finite");
}

TEST(RigContract, DepthsBecomeCountsOfTheUnit) {
  const std::vector<float> m = {0.5f, 0.00004f, 6.5f, 6.6f, -1.0f, std::numeric_limits<float>::quiet_NaN(), 0.0f};
  // 0.5 m at 0.1 mm: 5000 counts; 0.04 mm rounds to 0 (no reading); 6.5 m: 65000; 6.6 m is
  // beyond 65,534 counts; negative, NaN and 0 are no reading.
  EXPECT_EQ(depth_counts(m, 1e-4), (std::vector<uint16_t>{5000, 0, 65000, 0, 0, 0, 0}));
  EXPECT_EQ(depth_counts({0.5f}, 1e-3), std::vector<uint16_t>{500});
  expect_error([&] { depth_counts(m, 0); }, "depth_counts: unit 0");
}

TEST(RigContract, AFrameAnswersItsTriggerAndDecodesToTheDepthsGiven) {
  DepthCamera cam;
  cam.camera_id = "serial-42";
  cam.width = 4;
  cam.height = 3;
  cam.fx = cam.fy = 3;
  cam.cx = 2;
  cam.cy = 1.5;
  cam.depth_min_m = 0.1;
  cam.depth_max_m = 3;
  std::vector<float> depth(12);
  for (int i = 0; i < 12; ++i) depth[static_cast<std::size_t>(i)] = 0.25f + 0.1f * i;  // 0.25 .. 1.35 m
  depth_trigger_t trigger{};
  trigger.seq = 77;
  trigger.scan_id = "scan-b";
  for (const bool compress : {true, false}) {
    cam.compress = compress;
    const depth_frame_t f = depth_frame(cam, depth_counts(depth, cam.depth_unit_m), Exposure{5000000, 3000}, 12, trigger);
    EXPECT_EQ(f.trigger_seq, 77);
    EXPECT_EQ(f.scan_id, "scan-b");
    EXPECT_EQ(f.seq, 12);
    EXPECT_EQ(f.camera_id, "serial-42");
    EXPECT_EQ(f.exposure_start_utime, 5000000);
    EXPECT_EQ(f.exposure_us, 3000);
    EXPECT_EQ(f.utime, 5001500);  // the middle of the exposure
    EXPECT_EQ(f.encoding, compress ? depth_frame_t::kEncodingZlib : depth_frame_t::kEncodingRaw);
    EXPECT_EQ(f.num_bytes, static_cast<int32_t>(f.depth.size()));
    if (!compress) {
      EXPECT_EQ(f.depth[0], 2500 & 0xff);  // little-endian counts: 0.25 m = 2500
      EXPECT_EQ(f.depth[1], 2500 >> 8);
    }
    const bus::DecodedFrame d = bus::decode_frame(f);
    ASSERT_EQ(d.depth_m.size(), 12u);
    for (std::size_t i = 0; i < 12; ++i) EXPECT_NEAR(d.depth_m[i], depth[i], 0.5e-4) << i;  // half a count
    EXPECT_EQ(d.intrinsics.cx, 2);
  }
  expect_error([&] { depth_frame(cam, std::vector<uint16_t>(11), Exposure{}, 1, trigger); },
               "depth_frame: 11 counts for a 4x3 camera");
}

}  // namespace
}  // namespace pbnbv::driver
