// pbnbv-ur-driver against the twin playing a Universal Robots controller (pbnbv-twin
// --rtde-port), real processes on a real LCM bus: `pbnbv rig-check` passes through the driver
// (the driver owns the arm, the twin the turntable and the camera); a dropped RTDE connection is
// reported in ARM_STATUS, the driver reconnects by itself and a move after the drop completes; a
// protective stop is reported as a fault naming it and the driver does not clear it. Runs inside
// one private network namespace (see CMakeLists.txt); one twin at a time.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/turntable_status_t.hpp"
#include "process/processes.hpp"
#include "scan_checks.hpp"
#include "process_group.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;
using Clock = std::chrono::steady_clock;

namespace {

// The arm's statuses as they arrive, and the rig's commands sent from the test.
class Bus {
 public:
  Bus() : lcm_("udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608") {
    lcm_.subscribe("ARM_STATUS", &Bus::on_arm, this);
    lcm_.subscribe("TURNTABLE_STATUS", &Bus::on_turntable, this);
  }
  // Spins until `done` or `timeout_s`; returns done().
  bool until(const std::function<bool()>& done, double timeout_s) {
    const auto end = Clock::now() + std::chrono::duration<double>(timeout_s);
    while (!done() && Clock::now() < end) lcm_.handleTimeout(20);
    return done();
  }
  void move(int64_t seq, const std::vector<double>& q, double speed_scale = 1.0) {
    arm_command_t c{};
    c.utime = seq;
    c.seq = seq;
    c.mode = arm_command_t::kModePosition;
    c.num_joints = 6;
    c.joint_position_rad = q;
    c.speed_scale = speed_scale;
    lcm_.publish("ARM_COMMAND", &c);
  }
  std::vector<arm_status_t> arm;  // every ARM_STATUS heard
  int turntable = 0;

 private:
  void on_arm(const lcm::ReceiveBuffer*, const std::string&, const arm_status_t* s) { arm.push_back(*s); }
  void on_turntable(const lcm::ReceiveBuffer*, const std::string&, const turntable_status_t*) { ++turntable; }
  lcm::LCM lcm_;
};

class UrDriver : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fresh_dir(std::string("ur-driver-") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    // The UR5e rig file with a small camera (320 x 180), so that frames render quickly.
    rig_ = rig_with_camera(source_dir() + "/models", "rig_ur5e.xml", dir_, "320 180 174 174 160 90 0.1 3.0");
  }
  void TearDown() override { processes_.stop_expecting_clean_exits(); }

  void start(const std::string& name, const std::vector<std::string>& argv) { processes_.start(dir_, name, argv); }

  // The twin as the controller (`faults` played) on fresh ports, then the driver; both heard on the bus.
  void start_rig(const std::string& faults = "") {
    static int port = 31004;
    port += 2;
    port_ = port;
    std::vector<std::string> twin = {bin_dir() + "/pbnbv-twin", "--model", rig_.string(), "--model-out",
                                     (dir_ / "twin_model.xml").string(), "--rtde-port", std::to_string(port),
                                     "--ur-script-port", std::to_string(port + 1), "--width", "320", "--height", "180",
                                     "--fx", "174", "--fy", "174"};
    if (!faults.empty()) twin.insert(twin.end(), {"--fault", faults});
    start("twin", twin);
    ASSERT_TRUE(bus_.until([&] { return bus_.turntable > 0; }, 60)) << process::tail_lines((dir_ / "twin.log").string(), 20);
    EXPECT_TRUE(bus_.arm.empty()) << "the twin published ARM_STATUS while playing a UR controller";
    start("ur-driver", {bin_dir() + "/pbnbv-ur-driver", "--host", "127.0.0.1", "--port", std::to_string(port),
                        "--script-port", std::to_string(port + 1), "--rig-model", rig_.string()});
    ASSERT_TRUE(bus_.until([&] { return !bus_.arm.empty() && bus_.arm.back().mode != arm_status_t::kModeFault; }, 20))
        << process::tail_lines((dir_ / "ur-driver.log").string(), 20);
  }

  const arm_status_t& last() const { return bus_.arm.back(); }
  bool settled_at(int64_t seq) const {
    return !bus_.arm.empty() && last().mode == arm_status_t::kModeSettled && last().command_seq == seq;
  }
  // The last reading with wrist_2 (a5) turned by `deg`.
  std::vector<double> a5_turned(double deg) const {
    std::vector<double> q = last().joint_position_rad;
    q[4] += deg * M_PI / 180;
    return q;
  }
  std::string driver_log() const { return read_file(dir_ / "ur-driver.log"); }

  fs::path dir_, rig_;
  int port_ = 0;
  ProcessGroup processes_;
  Bus bus_;
};

TEST_F(UrDriver, RigCheckPassesThroughTheDriver) {
  start_rig();
  std::vector<process::Child> run(1);
  run[0].name = "rig-check";
  run[0].argv = {bin_dir() + "/pbnbv", "rig-check", "--rig-model", rig_.string(), "--deadline", "3"};
  run[0].log_path = (dir_ / "rig_check.log").string();
  process::start(run[0]);
  const auto end = Clock::now() + std::chrono::seconds(90);
  while (run[0].running && Clock::now() < end) {
    bus_.until([] { return false; }, 0.05);
    process::reap(run);
  }
  if (run[0].running) process::stop_all(run, 1.0);
  const std::string out = read_file(run[0].log_path);
  std::cout << out;
  EXPECT_EQ(run[0].exit_code, 0) << out << "\n" << process::tail_lines((dir_ / "ur-driver.log").string(), 20);
  EXPECT_EQ(out.find("FAIL"), std::string::npos) << out;
  for (const char* check : {"ARM_STATUS rate", "ARM_STATUS clocks increase", "ARM_STATUS joint names",
                            "arm small move (wrist_2 +3 deg)", "arm refuses wrist_2 5 deg beyond its limit",
                            "arm back to its start", "turntable small move (+5 deg)"}) {
    EXPECT_NE(out.find(std::string(check) + " "), std::string::npos) << check << "\n" << out;
  }
  EXPECT_NE(out.find("| pass | out_of_limits"), std::string::npos) << out;
  EXPECT_NE(driver_log().find("sent the program"), std::string::npos);
}

TEST_F(UrDriver, ADroppedConnectionIsReportedAndRecovered) {
  start_rig("rtde-drop");
  bus_.move(1, a5_turned(3));
  ASSERT_TRUE(bus_.until([&] { return settled_at(1); }, 10)) << process::tail_lines((dir_ / "ur-driver.log").string(), 20);
  // The twin closes the connection 2 s after the first move started.
  const std::string lost = "RTDE connection to 127.0.0.1:" + std::to_string(port_) + " lost";
  ASSERT_TRUE(bus_.until([&] { return last().fault_code == arm_status_t::kFaultDriver; }, 10)) << driver_log();
  const arm_status_t faulted = last();
  EXPECT_EQ(faulted.mode, arm_status_t::kModeFault);
  EXPECT_NE(faulted.fault.find(lost), std::string::npos) << faulted.fault;
  // Statuses keep coming while the link is down.
  const std::size_t at_fault = bus_.arm.size();
  ASSERT_TRUE(bus_.until([&] { return last().fault_code == arm_status_t::kFaultNone; }, 10)) << driver_log();
  const double reconnect_s = (last().utime - faulted.utime) * 1e-6;
  const std::size_t during = bus_.arm.size() - at_fault;
  std::cout << "fault reported, then statuses clean again after " << reconnect_s << " s (" << during
            << " statuses in between, the link's fault in each)\n";
  EXPECT_GT(during, 20u);
  EXPECT_LT(reconnect_s, 3.0);
  // Both clocks kept increasing across the drop.
  for (std::size_t i = 1; i < bus_.arm.size(); ++i) {
    ASSERT_GT(bus_.arm[i].utime, bus_.arm[i - 1].utime) << i;
    ASSERT_GT(bus_.arm[i].driver_utime, bus_.arm[i - 1].driver_utime) << i;
  }
  // A move after the drop completes.
  bus_.move(2, a5_turned(-3));
  ASSERT_TRUE(bus_.until([&] { return settled_at(2); }, 10)) << driver_log();
  EXPECT_NEAR(last().joint_position_rad[4], bus_.arm[at_fault].joint_position_rad[4] - 3 * M_PI / 180, 1e-3);
  EXPECT_NE(driver_log().find("data flows again"), std::string::npos);
}

TEST_F(UrDriver, AProtectiveStopIsReportedAndNotCleared) {
  start_rig("protective-stop");
  const std::vector<double> start = last().joint_position_rad;
  bus_.move(1, a5_turned(3));
  ASSERT_TRUE(bus_.until([&] { return settled_at(1); }, 10)) << driver_log();
  bus_.move(2, start);  // stops halfway in a protective stop
  ASSERT_TRUE(bus_.until([&] { return last().mode == arm_status_t::kModeFault; }, 10)) << driver_log();
  EXPECT_EQ(last().fault_code, arm_status_t::kFaultDriver);
  EXPECT_EQ(last().fault, "protective stop (safety mode 3): clear it on the teach pendant");
  // Still there 2 s later, and a new command neither clears it nor moves the arm.
  bus_.until([] { return false; }, 1.0);
  const double a5 = last().joint_position_rad[4];
  EXPECT_GT(std::abs(a5 - start[4]), 0.2 * 3 * M_PI / 180) << "the arm reached the target of the stopped move";
  bus_.move(3, start);
  bus_.until([] { return false; }, 1.0);
  EXPECT_EQ(last().mode, arm_status_t::kModeFault);
  EXPECT_EQ(last().fault, "protective stop (safety mode 3): clear it on the teach pendant");
  EXPECT_NEAR(last().joint_position_rad[4], a5, 1e-4);
  EXPECT_NE(driver_log().find("the arm cannot move: protective stop"), std::string::npos) << driver_log();
}

}  // namespace
