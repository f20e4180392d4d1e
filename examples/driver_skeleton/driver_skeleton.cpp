// A rig driver for your own arm, turntable and depth camera, on pbnbv's driver library. Replace
// the three marked device calls with your vendor's API; everything on the bus (checks, faults,
// sequence numbers, both clocks, frames) is the library's. As it stands it plays an ideal rig in
// software: the joints ramp to their targets at 0.5 rad/s, the camera sees a wall 1 m away.
// Check it with `pbnbv rig-check --passive` (README "Writing a driver").
#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "driver/rig_driver.hpp"

using namespace pbnbv;

int main() {
  install_stop_handlers();
  bus::Bus bus("my-driver");
  const std::vector<std::string> names = {"a1", "a2", "a3", "a4", "a5", "a6"};  // as the rig file names them
  const double a5_limit = 2.0943951023931953;                                  // your controller's limits
  std::vector<double> q(6, 0.0), target(6, 0.0);
  double table = 0, table_target = 0;
  int64_t arm_seq = -1, table_seq = -1;

  driver::RigDriver::Handlers h;
  h.move_arm = [&](const driver::ArmTarget& t) {  // DEVICE: command your arm
    if (!t.hold && std::abs(t.position_rad[4]) > a5_limit) throw driver::OutOfLimits("a5 target beyond its limit");
    target = t.hold ? q : t.position_rad;
    arm_seq = t.seq;
  };
  h.turn_table = [&](const driver::TurntableTarget& t) {  // DEVICE: command your turntable
    table_target = t.angle_rad;
    table_seq = t.seq;
  };
  driver::DepthCamera camera{"skeleton-0", 1280, 720, 696, 696, 640, 360, 0.1, 3.0};
  int64_t frame_seq = 0;
  h.capture = [&](const depth_trigger_t& t) {  // DEVICE: expose one frame
    const driver::Exposure exposure{bus::now_utime(), 0};
    const std::vector<float> depth_m(1280 * 720, 1.0f);
    return driver::depth_frame(camera, driver::depth_counts(depth_m, camera.depth_unit_m), exposure, frame_seq++, t);
  };
  driver::RigDriver rig(bus, h, driver::RigDriver::Options{});

  const auto start = std::chrono::steady_clock::now();
  while (!stop_requested()) {
    bus.spin_once(0);
    const double step = 0.5 * driver::kStatusPeriodS;  // DEVICE: read your joints instead
    bool settled = true;
    for (int i = 0; i < 6; ++i) {
      q[i] += std::clamp(target[i] - q[i], -step, step);
      settled = settled && q[i] == target[i];
    }
    table += std::clamp(table_target - table, -step, step);
    const driver::Motion arm_motion = arm_seq < 0 ? driver::Motion::kIdle : settled ? driver::Motion::kSettled : driver::Motion::kMoving;
    const driver::Motion table_motion = table_seq < 0 ? driver::Motion::kIdle
                                        : table == table_target ? driver::Motion::kSettled : driver::Motion::kMoving;
    const int64_t device_us = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start).count();
    rig.publish_statuses(driver::Stamp{bus::now_utime(), device_us},
                         driver::ArmReading{names, q, std::vector<double>(6, 0.0), target, arm_seq, arm_motion},
                         driver::TurntableReading{table, 0.0, table_target, table_seq, table_motion});
    std::this_thread::sleep_for(std::chrono::duration<double>(driver::kStatusPeriodS));
  }
  return 0;
}
