// `pbnbv rig-check` against real drivers on a real bus: it passes on the twin (the reference
// driver), and fails, naming the fault, on the twin playing each faulty driver (--fault), on a
// frame whose size disagrees with the rig file, and with no driver at all; in the last two
// nothing is commanded to move (the test listens for ARM_COMMAND and TURNTABLE_COMMAND).
// Runs inside one private network namespace (see CMakeLists.txt); one twin at a time.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/turntable_command_t.hpp"
#include "process/processes.hpp"
#include "scan_checks.hpp"
#include "process_group.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;

namespace {

constexpr double kDeadlineS = 3.0;

// Counts the rig's commands and statuses on the bus.
class Listener {
 public:
  Listener() : lcm_("udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608") {
    lcm_.subscribe("ARM_COMMAND", &Listener::on_arm_command, this);
    lcm_.subscribe("TURNTABLE_COMMAND", &Listener::on_turntable_command, this);
    lcm_.subscribe("ARM_STATUS", &Listener::on_arm_status, this);
  }
  void spin(int ms) { lcm_.handleTimeout(ms); }
  int arm_commands = 0, turntable_commands = 0, arm_statuses = 0;

 private:
  void on_arm_command(const lcm::ReceiveBuffer*, const std::string&, const arm_command_t*) { ++arm_commands; }
  void on_turntable_command(const lcm::ReceiveBuffer*, const std::string&, const turntable_command_t*) {
    ++turntable_commands;
  }
  void on_arm_status(const lcm::ReceiveBuffer*, const std::string&, const arm_status_t*) { ++arm_statuses; }
  lcm::LCM lcm_;
};

// The arm rig's file with the camera the tests' twin renders (320 x 180, f = 174 px: the
// default camera at a quarter of the size, so frames render quickly).
fs::path small_camera_rig(const fs::path& dir) {
  return rig_with_camera(source_dir() + "/models", "rig_arm.xml", dir, "320 180 174 174 160 90 0.1 3.0");
}

struct Outcome {
  int exit_code = -1;
  std::string output;
  int arm_commands = 0, turntable_commands = 0;
  double seconds = 0;
};

class RigCheck : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fresh_dir(std::string("rig-check-") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    rig_ = small_camera_rig(dir_);
  }
  void TearDown() override { processes_.stop_expecting_clean_exits(); }

  // Starts the twin (no object; `camera`: its image size and focal lengths, by default the test
  // rig file's; `extra` appended) and waits for its ARM_STATUS.
  void start_twin(const std::vector<std::string>& extra,
                  const std::vector<std::string>& camera = {"--width", "320", "--height", "180", "--fx", "174",
                                                            "--fy", "174"}) {
    std::vector<std::string> argv = {bin_dir() + "/pbnbv-twin", "--rig", "arm", "--model-out", (dir_ / "twin_model.xml").string()};
    argv.insert(argv.end(), camera.begin(), camera.end());
    argv.insert(argv.end(), extra.begin(), extra.end());
    processes_.start(dir_, "twin", argv);
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (listener_.arm_statuses == 0 && std::chrono::steady_clock::now() < end) listener_.spin(50);
    ASSERT_GT(listener_.arm_statuses, 0) << "the twin did not start:\n" << process::tail_lines((dir_ / "twin.log").string(), 20);
    listener_.arm_commands = listener_.turntable_commands = 0;
  }

  // Runs `pbnbv rig-check` against the test's rig file, counting the commands on the bus while it
  // runs.
  Outcome rig_check(const std::vector<std::string>& extra = {}) {
    std::vector<process::Child> run(1);
    run[0].name = "rig-check";
    run[0].argv = {bin_dir() + "/pbnbv", "rig-check", "--rig-model", rig_.string(), "--deadline", "3"};
    run[0].argv.insert(run[0].argv.end(), extra.begin(), extra.end());
    run[0].log_path = (dir_ / "rig_check.log").string();
    const auto t0 = std::chrono::steady_clock::now();
    process::start(run[0]);
    const auto end = t0 + std::chrono::seconds(120);
    while (run[0].running && std::chrono::steady_clock::now() < end) {
      listener_.spin(20);
      process::reap(run);
    }
    if (run[0].running) process::stop_all(run, 1.0);
    Outcome o;
    o.exit_code = run[0].exit_code;
    o.output = read_file(run[0].log_path);
    o.arm_commands = listener_.arm_commands;
    o.turntable_commands = listener_.turntable_commands;
    o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::cout << o.output << "(" << o.seconds << " s; " << o.arm_commands << " ARM_COMMAND, " << o.turntable_commands
              << " TURNTABLE_COMMAND seen)\n";
    return o;
  }

  // The twin playing `fault`: rig-check fails and one FAIL line names `words`.
  void expect_fault_named(const std::string& fault, const std::string& words) {
    start_twin({"--fault", fault});
    const Outcome o = rig_check();
    EXPECT_EQ(o.exit_code, 1) << o.output;
    EXPECT_TRUE(fails_naming(o.output, words)) << "no FAIL line names '" << words << "':\n" << o.output;
  }

  static bool fails_naming(const std::string& output, const std::string& words) {
    std::istringstream lines(output);
    for (std::string l; std::getline(lines, l);) {
      if (l.find("| FAIL |") != std::string::npos && l.find(words) != std::string::npos) return true;
    }
    return false;
  }

  fs::path dir_, rig_;
  ProcessGroup processes_;
  Listener listener_;
};

TEST_F(RigCheck, PassesOnTheTwin) {
  start_twin({});
  const Outcome o = rig_check();
  EXPECT_EQ(o.exit_code, 0) << o.output;
  EXPECT_EQ(o.output.find("FAIL"), std::string::npos) << o.output;
  // Every line of the table is there, the moves and refusals among them.
  for (const char* check : {"ARM_STATUS rate", "ARM_STATUS clocks increase", "TURNTABLE_STATUS rate",
                            "DEPTH_FRAME answers DEPTH_TRIGGER", "frame size", "frame intrinsics",
                            "exposure stamps on the status clock", "depth unit against geometry",
                            "arm small move (a5 +3 deg)", "arm refuses a5 5 deg beyond its limit", "arm back to its start",
                            "turntable small move (+5 deg)", "turntable refuses speed_scale 2",
                            "turntable back to its start"}) {
    EXPECT_NE(o.output.find(std::string(check) + " "), std::string::npos) << check << "\n" << o.output;
  }
  EXPECT_NE(o.output.find("| pass | out_of_limits"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("| pass | command_rejected"), std::string::npos) << o.output;
  EXPECT_GT(o.arm_commands, 0);
  EXPECT_GT(o.turntable_commands, 0);
}

// The driver contract's skeleton (docs/driver-contract.md; examples/driver_skeleton: the driver library, an ideal rig in
// software) passes every passive check against the shipped rig file: statuses, rates, both
// clocks, joint names, a frame answering its trigger with the rig file's camera and its exposure
// on the status clock. (Its frames show a wall 1 m away, not the rig: the active checks compare
// depth with forward kinematics, a real camera's to pass.)
TEST_F(RigCheck, TheDriverSkeletonPassesThePassiveChecks) {
  rig_ = source_dir() + "/models/rig_arm.xml";
  processes_.start(dir_, "skeleton", {bin_dir() + "/../tests/pbnbv-driver-skeleton"});
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (listener_.arm_statuses == 0 && std::chrono::steady_clock::now() < end) listener_.spin(50);
  ASSERT_GT(listener_.arm_statuses, 0) << process::tail_lines((dir_ / "skeleton.log").string(), 20);
  listener_.arm_commands = listener_.turntable_commands = 0;
  const Outcome o = rig_check({"--passive"});
  EXPECT_EQ(o.exit_code, 0) << o.output;
  EXPECT_EQ(o.output.find("FAIL"), std::string::npos) << o.output;
  for (const char* check : {"ARM_STATUS rate", "ARM_STATUS clocks increase", "TURNTABLE_STATUS rate",
                            "DEPTH_FRAME answers DEPTH_TRIGGER", "frame size", "exposure stamps on the status clock"}) {
    EXPECT_NE(o.output.find(std::string(check) + " "), std::string::npos) << check << "\n" << o.output;
  }
  EXPECT_EQ(o.arm_commands, 0);
}

TEST_F(RigCheck, PassiveCommandsNothing) {
  start_twin({});
  const Outcome o = rig_check({"--passive"});
  EXPECT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("frame size "), std::string::npos) << o.output;
  EXPECT_EQ(o.output.find("small move"), std::string::npos) << o.output;
  EXPECT_EQ(o.arm_commands, 0);
  EXPECT_EQ(o.turntable_commands, 0);
}

TEST_F(RigCheck, SlowStatusFails) { expect_fault_named("slow-status", "slow status"); }
TEST_F(RigCheck, NoSeqEchoFails) { expect_fault_named("no-seq-echo", "no seq echo"); }
TEST_F(RigCheck, DepthInMillimetresFails) { expect_fault_named("depth-unit-mm", "wrong depth unit"); }
TEST_F(RigCheck, FramesWithoutTheTriggerIdFail) { expect_fault_named("no-trigger-id", "no trigger id"); }
TEST_F(RigCheck, IgnoringLimitsFails) { expect_fault_named("ignore-limits", "ignores limits"); }
TEST_F(RigCheck, UtimeGoingBackwardsFails) { expect_fault_named("utime-backwards", "utime not monotonic"); }
TEST_F(RigCheck, LateExposureStampsFail) { expect_fault_named("late-exposure", "late exposure stamps"); }

TEST_F(RigCheck, AFrameOfAnotherSizeFailsAndNothingMoves) {
  start_twin({}, {"--width", "640", "--height", "360", "--fx", "348", "--fy", "348"});
  const Outcome o = rig_check();
  EXPECT_EQ(o.exit_code, 1) << o.output;
  EXPECT_TRUE(fails_naming(o.output, "frame size 640x360 disagrees with the rig file's camera 320x180")) << o.output;
  EXPECT_TRUE(fails_naming(o.output, "nothing was commanded to move")) << o.output;
  EXPECT_EQ(o.arm_commands, 0);
  EXPECT_EQ(o.turntable_commands, 0);
}

TEST_F(RigCheck, NoDriverFailsWithinItsDeadlineAndNothingMoves) {
  const Outcome o = rig_check();
  EXPECT_EQ(o.exit_code, 1) << o.output;
  EXPECT_TRUE(fails_naming(o.output, "no ARM_STATUS in 3.0 s: is the arm driver running and on this LCM URL")) << o.output;
  EXPECT_TRUE(fails_naming(o.output, "no TURNTABLE_STATUS in 3.0 s")) << o.output;
  EXPECT_TRUE(fails_naming(o.output, "no DEPTH_FRAME in 3.0 s")) << o.output;
  EXPECT_EQ(o.arm_commands, 0);
  EXPECT_EQ(o.turntable_commands, 0);
  // The statuses' deadline, then the frame's: about 2 x 3 s.
  EXPECT_LT(o.seconds, 2 * kDeadlineS + 4) << o.output;
}

}  // namespace
