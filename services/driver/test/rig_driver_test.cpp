// A driver built on RigDriver, on a real LCM bus inside this process (LCM's memq:// transport):
// a refused command is latched and reported by code in the next status until a command is
// accepted, the accepted command reaches the handler and is echoed, a trigger is answered with its
// frame, statuses are numbered.
#include "driver/rig_driver.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <vector>

#include "bus/channels.hpp"

namespace pbnbv::driver {
namespace {

class RigDriverTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { ::setenv("LCM_DEFAULT_URL", "memq://", 1); }
};

// Spins `bus` until `done` or 200 rounds.
template <class Done>
bool spin_until(bus::Bus& bus, Done done) {
  for (int i = 0; i < 200 && !done(); ++i) bus.spin_once(5);
  return done();
}

TEST_F(RigDriverTest, RefusalsAreLatchedByCodeAndAcceptedCommandsEchoed) {
  bus::Bus bus("driver-test");
  std::vector<ArmTarget> moves;
  RigDriver::Handlers h;
  h.move_arm = [&](const ArmTarget& t) {
    if (!t.hold && t.position_rad[0] > 3) throw OutOfLimits("joint a1 target " + std::to_string(t.position_rad[0]) + " is outside its limits");
    moves.push_back(t);
  };
  h.capture = [&](const depth_trigger_t& t) {
    DepthCamera cam;
    cam.camera_id = "test";
    cam.width = 2;
    cam.height = 1;
    cam.fx = cam.fy = 1;
    cam.depth_min_m = 0.1;
    cam.depth_max_m = 2;
    return depth_frame(cam, {1000, 2000}, Exposure{42, 0}, 1, t);
  };
  RigDriver::Options options;
  options.no_turntable = true;  // an arm-and-camera rig: its turntable commands are refused
  RigDriver driver(bus, h, options);
  std::vector<arm_status_t> statuses;
  std::vector<depth_frame_t> frames;
  bus.subscribe<arm_status_t>(channels::kArmStatus, [&](const arm_status_t& s) { statuses.push_back(s); });
  bus.subscribe<depth_frame_t>(channels::kDepthFrame, [&](const depth_frame_t& f) { frames.push_back(f); });
  lcm::LCM& lcm = bus.raw();

  ArmReading reading;
  reading.joint_names = {"a1", "a2", "a3", "a4", "a5", "a6"};
  reading.position_rad = reading.velocity_rad_s = reading.commanded_rad = std::vector<double>(6, 0.0);
  auto status = [&]() -> arm_status_t {
    const std::size_t before = statuses.size();
    driver.publish_statuses(Stamp{1000, 10}, reading, std::nullopt);
    EXPECT_TRUE(spin_until(bus, [&] { return statuses.size() > before; }));
    return statuses.back();
  };

  arm_command_t c{};
  c.seq = 1;
  c.mode = arm_command_t::kModePosition;
  c.num_joints = 5;  // malformed
  c.joint_position_rad.assign(5, 0.1);
  c.speed_scale = 0.5;
  lcm.publish(channels::kArmCommand, &c);
  EXPECT_TRUE(spin_until(bus, [&] { return driver.arm_fault().active(); }));
  arm_status_t s = status();
  EXPECT_EQ(s.seq, 0);
  EXPECT_EQ(s.mode, arm_status_t::kModeFault);
  EXPECT_EQ(s.fault_code, arm_status_t::kFaultCommandRejected);
  EXPECT_EQ(s.fault_command_seq, 1);
  EXPECT_EQ(s.fault, "rejected ARM_COMMAND seq 1: num_joints = 5, this arm has 6");
  EXPECT_EQ(bus.rejected(), 1);  // counted and logged by the bus as a rejected message

  c.seq = 2;
  c.num_joints = 6;
  c.joint_position_rad.assign(6, 3.5);  // beyond the handler's limit
  lcm.publish(channels::kArmCommand, &c);
  EXPECT_TRUE(spin_until(bus, [&] { return driver.arm_fault().command_seq() == 2; }));
  s = status();
  EXPECT_EQ(s.seq, 1);
  EXPECT_EQ(s.fault_code, arm_status_t::kFaultOutOfLimits);
  EXPECT_NE(s.fault.find("rejected ARM_COMMAND seq 2: joint a1 target 3.5"), std::string::npos) << s.fault;
  EXPECT_TRUE(moves.empty());

  c.seq = 3;
  c.joint_position_rad.assign(6, 0.5);
  lcm.publish(channels::kArmCommand, &c);
  EXPECT_TRUE(spin_until(bus, [&] { return !moves.empty(); }));
  ASSERT_EQ(moves.size(), 1u);
  EXPECT_EQ(moves[0].seq, 3);
  EXPECT_EQ(moves[0].position_rad, std::vector<double>(6, 0.5));
  reading.command_seq = moves[0].seq;  // what the driver echoes once it tracks the command
  reading.motion = Motion::kMoving;
  s = status();
  EXPECT_EQ(s.seq, 2);
  EXPECT_EQ(s.mode, arm_status_t::kModeMoving);
  EXPECT_EQ(s.fault_code, arm_status_t::kFaultNone);
  EXPECT_EQ(s.command_seq, 3);

  // The arm touches something under command 3 and stops: kFaultContact with its text in every
  // status, the count and the last contact in the reading, until the next command is accepted.
  driver.set_arm_contact(3, "contact: link_6 / platter, 3.2 mm deep, at rig time 12.345 s, during command 3");
  reading.contacts = 1;
  reading.last_contact = "link_6 / platter, 3.2 mm deep, at rig time 12.345 s, during command 3";
  for (int k = 0; k < 2; ++k) {
    s = status();
    EXPECT_EQ(s.mode, arm_status_t::kModeFault);
    EXPECT_EQ(s.fault_code, arm_status_t::kFaultContact);
    EXPECT_EQ(s.fault_command_seq, 3);
    EXPECT_EQ(s.fault, "contact: link_6 / platter, 3.2 mm deep, at rig time 12.345 s, during command 3");
    EXPECT_EQ(s.contacts, 1);
    EXPECT_EQ(s.last_contact, reading.last_contact);
  }
  c.seq = 4;
  lcm.publish(channels::kArmCommand, &c);
  EXPECT_TRUE(spin_until(bus, [&] { return moves.size() == 2; }));
  reading.command_seq = 4;
  s = status();
  EXPECT_EQ(s.mode, arm_status_t::kModeMoving);
  EXPECT_EQ(s.fault_code, arm_status_t::kFaultNone);
  EXPECT_EQ(s.contacts, 1) << "the count stays";
  EXPECT_THROW(driver.set_arm_contact(4, ""), std::invalid_argument);

  // No turntable handler: a turntable command is refused and latched on the turntable's fault.
  turntable_command_t tc{};
  tc.seq = 8;
  tc.speed_scale = 1;
  lcm.publish(channels::kTurntableCommand, &tc);
  EXPECT_TRUE(spin_until(bus, [&] { return driver.turntable_fault().active(); }));
  EXPECT_EQ(driver.turntable_fault().text(), "rejected TURNTABLE_COMMAND seq 8: this rig has no turntable");

  depth_trigger_t trigger{};
  trigger.seq = 31;
  trigger.scan_id = "s";
  lcm.publish(channels::kDepthTrigger, &trigger);
  EXPECT_TRUE(spin_until(bus, [&] { return !frames.empty(); }));
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].trigger_seq, 31);
  EXPECT_EQ(frames[0].scan_id, "s");
  EXPECT_EQ(driver.statuses_published(), 6);
}

// A driver owning the arm only (pbnbv-ur-driver): it publishes ARM_STATUS alone, leaves the
// turntable's commands and the triggers to the other driver (no refusal, no frame), and a drive
// fault is reported ahead of a refused command's until it is cleared.
TEST_F(RigDriverTest, AnArmOnlyDriverOwnsTheArmAlone) {
  bus::Bus bus("driver-test");
  std::vector<ArmTarget> moves;
  RigDriver::Handlers h;
  h.move_arm = [&](const ArmTarget& t) { moves.push_back(t); };
  RigDriver driver(bus, h, RigDriver::Options{});
  EXPECT_TRUE(driver.owns_arm());
  EXPECT_FALSE(driver.owns_turntable());
  EXPECT_FALSE(driver.owns_camera());
  int arm_statuses = 0, turntable_statuses = 0, frames = 0;
  arm_status_t last{};
  bus.subscribe<arm_status_t>(channels::kArmStatus, [&](const arm_status_t& s) { ++arm_statuses; last = s; });
  bus.subscribe<turntable_status_t>(channels::kTurntableStatus, [&](const turntable_status_t&) { ++turntable_statuses; });
  bus.subscribe<depth_frame_t>(channels::kDepthFrame, [&](const depth_frame_t&) { ++frames; });
  lcm::LCM& lcm = bus.raw();

  turntable_command_t tc{};
  tc.seq = 8;
  tc.speed_scale = 1;
  lcm.publish(channels::kTurntableCommand, &tc);
  depth_trigger_t trigger{};
  trigger.seq = 31;
  lcm.publish(channels::kDepthTrigger, &trigger);
  arm_command_t c{};
  c.seq = 4;
  c.mode = arm_command_t::kModePosition;
  c.num_joints = 6;
  c.joint_position_rad.assign(6, 0.2);
  c.speed_scale = 0.5;
  lcm.publish(channels::kArmCommand, &c);
  EXPECT_TRUE(spin_until(bus, [&] { return !moves.empty(); }));
  for (int i = 0; i < 10; ++i) bus.spin_once(5);  // the turntable command and the trigger, had they been heard
  EXPECT_FALSE(driver.turntable_fault().active());
  EXPECT_EQ(frames, 0);
  EXPECT_EQ(bus.rejected(), 0);

  ArmReading reading;
  reading.joint_names = {"a1", "a2", "a3", "a4", "a5", "a6"};
  reading.position_rad = reading.velocity_rad_s = reading.commanded_rad = std::vector<double>(6, 0.0);
  reading.command_seq = 4;
  reading.motion = Motion::kMoving;
  driver.publish_statuses(Stamp{1000, 10}, reading, std::nullopt);
  EXPECT_TRUE(spin_until(bus, [&] { return arm_statuses == 1; }));
  EXPECT_EQ(last.mode, arm_status_t::kModeMoving);
  EXPECT_THROW(driver.publish_statuses(Stamp{1001, 11}, std::nullopt, TurntableReading{}), std::invalid_argument);

  driver.set_arm_drive_fault("protective stop (safety mode 3)");
  driver.publish_statuses(Stamp{1002, 12}, reading, std::nullopt);
  EXPECT_TRUE(spin_until(bus, [&] { return arm_statuses == 2; }));
  EXPECT_EQ(last.mode, arm_status_t::kModeFault);
  EXPECT_EQ(last.fault_code, arm_status_t::kFaultDriver);
  EXPECT_EQ(last.fault, "protective stop (safety mode 3)");
  driver.set_arm_drive_fault("");
  driver.publish_statuses(Stamp{1003, 13}, reading, std::nullopt);
  EXPECT_TRUE(spin_until(bus, [&] { return arm_statuses == 3; }));
  EXPECT_EQ(last.mode, arm_status_t::kModeMoving);
  EXPECT_EQ(last.fault_code, arm_status_t::kFaultNone);
  EXPECT_EQ(turntable_statuses, 0);
}

TEST_F(RigDriverTest, ADriverWithoutHandlersIsRefused) {
  bus::Bus bus("driver-test");
  EXPECT_THROW(RigDriver(bus, RigDriver::Handlers{}, RigDriver::Options{}), std::invalid_argument);
}

}  // namespace
}  // namespace pbnbv::driver
