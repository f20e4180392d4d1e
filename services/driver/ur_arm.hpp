#pragma once
// A Universal Robots e-Series arm as the rig contract's arm, in plain functions (no sockets, no
// bus): the RTDE recipes pbnbv-ur-driver asks for, the controller's state read from a data
// package and turned into the arm's reading and drive fault, a command written into the input
// registers, and the URScript program that moves the arm from those registers. The twin plays the
// controller with the same functions (twin/ur_controller.hpp).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "driver/rig_contract.hpp"
#include "driver/rtde.hpp"

namespace pbnbv::driver::ur {

inline constexpr uint16_t kScriptPort = 30002;  // the secondary interface: URScript text

// The outputs the driver reads, in recipe order, and their types.
const std::vector<std::string>& output_names();
const std::vector<rtde::Type>& output_types();
// The inputs it writes: input_double_register_0..5 (target, rad), _6 (speed scale),
// input_int_register_0 (command number), input_int_register_1 (1: stop and hold).
const std::vector<std::string>& input_names();
const std::vector<rtde::Type>& input_types();

inline constexpr int32_t kRobotModeRunning = 7;
inline constexpr int32_t kSafetyModeNormal = 1;
inline constexpr int32_t kSafetyModeReduced = 2;
inline constexpr int32_t kSafetyModeProtectiveStop = 3;
inline constexpr uint32_t kRuntimePlaying = 2;

// The controller's state in one data package.
struct State {
  double timestamp_s = 0;  // the controller's clock
  std::array<double, 6> q{}, qd{}, target_q{};
  int32_t robot_mode = 0;
  int32_t safety_mode = 0;
  uint32_t runtime_state = 0;
  int32_t echo = 0;  // output_int_register_0: the command number the program last started
};
// Throws rtde::RtdeError when the values are not the output recipe's.
State state_of(const rtde::Data& data);
rtde::Data data_of(uint8_t recipe_id, const State& state);

// What the input registers say.
struct Registers {
  std::array<double, 6> target{};
  double speed_scale = 0;
  int32_t number = 0;  // the program starts a move (or the stop) when it changes
  bool stop = false;
};
rtde::Data data_of(uint8_t recipe_id, const Registers& registers);
// Throws rtde::RtdeError when the values are not the input recipe's.
Registers registers_of(const rtde::Data& data);

// The drive's fault, for the arm status ("" when the arm can move): a safety mode other than
// normal or reduced (e.g. "protective stop (safety mode 3): clear it on the teach pendant"), a
// robot mode other than running, or the program not playing.
std::string drive_fault(const State& state);

// The command the driver last wrote, to read the program's echo against.
struct Sent {
  int32_t number = 0;  // its register number (0: none since start-up)
  int64_t seq = -1;    // the ARM_COMMAND's seq
  bool hold = false;
  std::array<double, 6> target{};
};
// Still: every joint slower than this (rad/s) and within this of the controller's target (rad).
inline constexpr double kStillRad_s = 2e-3;
inline constexpr double kSettledRad = 1e-4;
// The arm's reading from the state: the echoed command's seq when the echo is the last command
// sent (-1 before), settled when still at the sent target (a hold: still anywhere), moving while
// the echo lags the command sent or the arm is not there yet, idle before any command.
ArmReading reading_of(const State& state, const Sent& sent, const std::vector<std::string>& joint_names);

// The program the driver sends once per connection on kScriptPort (text, newline-terminated):
// it loops reading the input registers; when input_int_register_0 changes it stops any move in
// progress, writes the number to output_int_register_0 and then either holds (stopj, when
// input_int_register_1 is 1) or starts movej to input_double_register_0..5 at
// speed = input_double_register_6 x `speed_rad_s` and acceleration = the same scale x
// `acceleration_rad_s2` (the move runs in a thread, so that the next command can interrupt it).
// `speed_rad_s` is the slowest joint's limit from the rig file: movej's speed is its leading
// joint's. Throws std::invalid_argument unless both are positive and finite.
std::string program(double speed_rad_s, double acceleration_rad_s2);
// The program's first line (the twin checks a script it receives against it).
inline constexpr const char* kProgramName = "def pbnbv_follow_registers():";
// Whether `text` is that program: its definition, the register reads and the echo, and its end.
bool is_program(const std::string& text);

}  // namespace pbnbv::driver::ur
