// A contact on the bus: the twin (models/rig_arm.xml) and the motion executor as real processes
// on a real LCM bus (one private network namespace, see CMakeLists.txt). ARM_COMMANDs drive the
// camera straight down into the table, as twin/test/contact_monitor_test.cpp does without a bus:
// ARM_STATUS reports kFaultContact on that command with the pair named, counts it once and holds
// the arm; the next command clears the fault and the count stays; the motion executor, with no
// move in progress, warns of it in its log.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "bus/message_guard.hpp"
#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "process/processes.hpp"
#include "process_group.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;
using Clock = std::chrono::steady_clock;

namespace {

constexpr double kPi = 3.14159265358979323846;

// a1 = a4 = a6 = 0, the tool straight down (a2 + a3 + a5 = 90 deg), 0.70 m from the turntable
// axis towards the arm: the flange 0.25 m above the table, and 0.0104 m (the camera housing,
// 52 mm beyond the flange face, 41.6 mm into the table). Worked out in contact_monitor_test.cpp.
std::vector<double> planar(double a2, double a3) { return {0, a2, a3, 0, kPi / 2 - a2 - a3, 0}; }
const std::vector<double> kAbove = planar(0.3234, 1.6223);
const std::vector<double> kInto = planar(0.78, 0.9);

class RigContact : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fresh_dir("rig-contact");
    lcm_.subscribe("ARM_STATUS", &RigContact::on_arm, this);
    start("twin", {bin_dir() + "/pbnbv-twin", "--rig", "arm", "--model-out", (dir_ / "twin_model.xml").string(),
                   "--width", "320", "--height", "180", "--fx", "174", "--fy", "174", "--speed", "4"});
    start("motion", {bin_dir() + "/pbnbv-motion", "--rig", "arm"});
    ASSERT_TRUE(until([&] { return have_; }, 60)) << process::tail_lines((dir_ / "twin.log").string(), 20);
  }
  void TearDown() override { processes_.stop_expecting_clean_exits(); }
  void start(const std::string& name, const std::vector<std::string>& argv) { processes_.start(dir_, name, argv); }
  bool until(const std::function<bool()>& done, double timeout_s) {
    const auto end = Clock::now() + std::chrono::duration<double>(timeout_s);
    while (!done() && Clock::now() < end) lcm_.handleTimeout(20);
    return done();
  }
  void move(int64_t seq, const std::vector<double>& q) {
    arm_command_t c{};
    c.seq = seq;
    c.mode = arm_command_t::kModePosition;
    c.num_joints = 6;
    c.joint_position_rad = q;
    c.speed_scale = 1.0;
    lcm_.publish("ARM_COMMAND", &c);
  }
  bool settled_at(int64_t seq) const { return have_ && arm_.mode == arm_status_t::kModeSettled && arm_.command_seq == seq; }

  void on_arm(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    arm_status_t m;
    if (!bus::decode_checked(channel, rbuf->data, rbuf->data_size, &m)) return;
    arm_ = m;
    have_ = true;
  }

  fs::path dir_;
  ProcessGroup processes_;
  lcm::LCM lcm_{"udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608"};
  arm_status_t arm_{};
  bool have_ = false;
};

TEST_F(RigContact, TheTwinStopsTheArmOnAContactAndReportsItUntilTheNextCommand) {
  EXPECT_EQ(arm_.contacts, 0) << "the twin counts contacts, none at home";
  EXPECT_EQ(arm_.last_contact, "");
  move(101, kAbove);
  ASSERT_TRUE(until([&] { return settled_at(101); }, 20)) << process::tail_lines((dir_ / "twin.log").string(), 20);
  EXPECT_EQ(arm_.contacts, 0);

  move(102, kInto);
  ASSERT_TRUE(until([&] { return arm_.mode == arm_status_t::kModeFault; }, 20))
      << process::tail_lines((dir_ / "twin.log").string(), 20);
  EXPECT_EQ(arm_.fault_code, arm_status_t::kFaultContact);
  EXPECT_EQ(arm_.fault_command_seq, 102);
  EXPECT_EQ(arm_.command_seq, 102) << "the command it was executing";
  EXPECT_EQ(arm_.contacts, 1);
  EXPECT_EQ(arm_.last_contact.rfind("camera_optical / table, ", 0), 0u) << arm_.last_contact;
  EXPECT_NE(arm_.last_contact.find("during command 102"), std::string::npos) << arm_.last_contact;
  EXPECT_EQ(arm_.fault, "contact: " + arm_.last_contact);
  // Held where it touched, 1 s later: short of the target (a2 0.78 rad) and still in fault.
  until([] { return false; }, 1.0);
  EXPECT_EQ(arm_.mode, arm_status_t::kModeFault);
  EXPECT_EQ(arm_.contacts, 1);
  EXPECT_GT(kInto[1] - arm_.joint_position_rad[1], 0.05) << "a2 went on to its target";
  double speed = 0;
  for (double v : arm_.joint_velocity_rad_s) speed = std::max(speed, std::abs(v));
  EXPECT_LT(speed, 0.01);

  // The next command clears the fault and moves the arm back; the count stays.
  move(103, kAbove);
  ASSERT_TRUE(until([&] { return settled_at(103); }, 20));
  EXPECT_EQ(arm_.fault_code, arm_status_t::kFaultNone);
  EXPECT_EQ(arm_.contacts, 1);
  EXPECT_EQ(arm_.last_contact.rfind("camera_optical / table, ", 0), 0u);

  const std::string twin = read_file(dir_ / "twin.log");
  EXPECT_NE(twin.find("contact: camera_optical / table, "), std::string::npos) << twin;
  // The motion executor heard it with no move of its own in progress.
  const std::string motion = read_file(dir_ / "motion.log");
  EXPECT_NE(motion.find("the rig reports 1 new contact (1 since its driver started), while no move is in progress: "
                        "camera_optical / table, "),
            std::string::npos)
      << motion;
}

}  // namespace
