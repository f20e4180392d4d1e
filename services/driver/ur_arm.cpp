#include "driver/ur_arm.hpp"

#include <cmath>
#include <sstream>

namespace pbnbv::driver::ur {

namespace {

using rtde::Type;

// pbnbv-ur-driver's URScript program, with SPEED and ACCEL (rad/s, rad/s^2, at speed scale 1)
// filled in by program(). Registers: input_double_register_0..5 the target (rad), _6 the speed
// scale, input_int_register_0 the command number, input_int_register_1 1 for a stop;
// output_int_register_0 echoes the number of the command the program last started.
// A new number first stops a move in progress (kill its thread, stopj), then echoes the number,
// then holds (stopj) or starts movej in the mover thread. The number standing when the program
// starts counts as done: a restarted program never repeats a command.
constexpr const char* kProgram = R"(def pbnbv_follow_registers():
  # pbnbv-ur-driver: follows the RTDE input registers (services/driver/ur_arm.cpp).
  global pbnbv_target = [0, 0, 0, 0, 0, 0]
  global pbnbv_speed = 0.01
  global pbnbv_accel = 0.01
  global pbnbv_moving = False
  thread pbnbv_move():
    movej(pbnbv_target, a=pbnbv_accel, v=pbnbv_speed)
    pbnbv_moving = False
  end
  pbnbv_done = read_input_integer_register(0)
  write_output_integer_register(0, pbnbv_done)
  pbnbv_mover = 0
  while True:
    pbnbv_number = read_input_integer_register(0)
    if pbnbv_number != pbnbv_done:
      if pbnbv_moving:
        kill pbnbv_mover
        pbnbv_moving = False
        stopj(ACCEL)
      end
      pbnbv_done = pbnbv_number
      if read_input_integer_register(1) == 1:
        write_output_integer_register(0, pbnbv_number)
        stopj(ACCEL)
      else:
        pbnbv_target = [read_input_float_register(0), read_input_float_register(1), read_input_float_register(2), read_input_float_register(3), read_input_float_register(4), read_input_float_register(5)]
        pbnbv_speed = read_input_float_register(6) * SPEED
        pbnbv_accel = read_input_float_register(6) * ACCEL
        pbnbv_moving = True
        write_output_integer_register(0, pbnbv_number)
        pbnbv_mover = run pbnbv_move()
      end
    end
    sync()
  end
end
)";

std::string replaced(std::string text, const std::string& what, const std::string& with) {
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + with.size())) {
    text.replace(at, what.size(), with);
  }
  return text;
}

std::array<double, 6> vector6_of(const rtde::Value& v) {
  std::array<double, 6> a{};
  for (std::size_t i = 0; i < 6; ++i) a[i] = v.vector.at(i);
  return a;
}

// Throws unless `data` holds `types` one by one.
void check_recipe(const rtde::Data& data, const std::vector<Type>& types, const char* what) {
  bool ok = data.values.size() == types.size();
  for (std::size_t i = 0; ok && i < types.size(); ++i) ok = data.values[i].type == types[i];
  if (!ok) throw rtde::RtdeError(std::string("data package is not the ") + what + " recipe");
}

const char* safety_mode_name(int32_t mode) {
  switch (mode) {
    case 3: return "protective stop";
    case 4: return "recovery";
    case 5: return "safeguard stop";
    case 6: return "system emergency stop";
    case 7: return "robot emergency stop";
    case 8: return "violation";
    case 9: return "fault";
    case 10: return "validate joint id";
    case 12: return "automatic mode safeguard stop";
    case 13: return "three-position enabling stop";
  }
  return "undefined safety mode";
}

}  // namespace

const std::vector<std::string>& output_names() {
  static const std::vector<std::string> names = {"timestamp",    "actual_q",    "actual_qd",     "target_q",
                                                 "robot_mode",   "safety_mode", "runtime_state", "output_int_register_0"};
  return names;
}

const std::vector<Type>& output_types() {
  static const std::vector<Type> types = {Type::kDouble,   Type::kVector6d, Type::kVector6d, Type::kVector6d,
                                          Type::kInt32,    Type::kInt32,    Type::kUint32,   Type::kInt32};
  return types;
}

const std::vector<std::string>& input_names() {
  static const std::vector<std::string> names = {
      "input_double_register_0", "input_double_register_1", "input_double_register_2", "input_double_register_3",
      "input_double_register_4", "input_double_register_5", "input_double_register_6", "input_int_register_0",
      "input_int_register_1"};
  return names;
}

const std::vector<Type>& input_types() {
  static const std::vector<Type> types = {Type::kDouble, Type::kDouble, Type::kDouble, Type::kDouble, Type::kDouble,
                                          Type::kDouble, Type::kDouble, Type::kInt32,  Type::kInt32};
  return types;
}

State state_of(const rtde::Data& data) {
  check_recipe(data, output_types(), "output");
  State s;
  s.timestamp_s = data.values[0].number;
  s.q = vector6_of(data.values[1]);
  s.qd = vector6_of(data.values[2]);
  s.target_q = vector6_of(data.values[3]);
  s.robot_mode = static_cast<int32_t>(data.values[4].number);
  s.safety_mode = static_cast<int32_t>(data.values[5].number);
  s.runtime_state = static_cast<uint32_t>(data.values[6].number);
  s.echo = static_cast<int32_t>(data.values[7].number);
  return s;
}

rtde::Data data_of(uint8_t recipe_id, const State& s) {
  rtde::Data d;
  d.recipe_id = recipe_id;
  d.values = {rtde::scalar(Type::kDouble, s.timestamp_s), rtde::vector6(s.q),
              rtde::vector6(s.qd),                        rtde::vector6(s.target_q),
              rtde::scalar(Type::kInt32, s.robot_mode),   rtde::scalar(Type::kInt32, s.safety_mode),
              rtde::scalar(Type::kUint32, s.runtime_state), rtde::scalar(Type::kInt32, s.echo)};
  return d;
}

rtde::Data data_of(uint8_t recipe_id, const Registers& r) {
  rtde::Data d;
  d.recipe_id = recipe_id;
  for (double x : r.target) d.values.push_back(rtde::scalar(Type::kDouble, x));
  d.values.push_back(rtde::scalar(Type::kDouble, r.speed_scale));
  d.values.push_back(rtde::scalar(Type::kInt32, r.number));
  d.values.push_back(rtde::scalar(Type::kInt32, r.stop ? 1 : 0));
  return d;
}

Registers registers_of(const rtde::Data& data) {
  check_recipe(data, input_types(), "input");
  Registers r;
  for (std::size_t i = 0; i < 6; ++i) r.target[i] = data.values[i].number;
  r.speed_scale = data.values[6].number;
  r.number = static_cast<int32_t>(data.values[7].number);
  r.stop = data.values[8].number == 1;
  return r;
}

std::string drive_fault(const State& s) {
  if (s.safety_mode != kSafetyModeNormal && s.safety_mode != kSafetyModeReduced) {
    const std::string what = std::string(safety_mode_name(s.safety_mode)) + " (safety mode " +
                             std::to_string(s.safety_mode) + ")";
    if (s.safety_mode == 6 || s.safety_mode == 7) {
      return what + ": release the emergency stop and reset the robot on the teach pendant";
    }
    return what + ": clear it on the teach pendant";
  }
  if (s.robot_mode != kRobotModeRunning) {
    return "robot mode " + std::to_string(s.robot_mode) +
           ", not running (7): power the arm on and release its brakes on the teach pendant";
  }
  if (s.runtime_state != kRuntimePlaying) {
    return "the driver's program is not playing (runtime state " + std::to_string(s.runtime_state) +
           "): is the controller in remote control?";
  }
  return "";
}

ArmReading reading_of(const State& s, const Sent& sent, const std::vector<std::string>& joint_names) {
  ArmReading r;
  r.joint_names = joint_names;
  r.position_rad.assign(s.q.begin(), s.q.end());
  r.velocity_rad_s.assign(s.qd.begin(), s.qd.end());
  const bool targeted = sent.number != 0 && !sent.hold;
  r.commanded_rad = targeted ? std::vector<double>(sent.target.begin(), sent.target.end())
                             : std::vector<double>(s.target_q.begin(), s.target_q.end());
  bool still = true, there = true;
  for (std::size_t i = 0; i < 6; ++i) {
    still = still && std::abs(s.qd[i]) < kStillRad_s;
    there = there && std::abs(s.q[i] - r.commanded_rad[i]) <= kSettledRad &&
            std::abs(s.target_q[i] - r.commanded_rad[i]) <= kSettledRad;
  }
  const bool echoed = sent.number != 0 && s.echo == sent.number;
  r.command_seq = echoed ? sent.seq : -1;
  if (sent.number == 0) {
    r.motion = still ? Motion::kIdle : Motion::kMoving;
  } else {
    r.motion = echoed && still && (sent.hold || there) ? Motion::kSettled : Motion::kMoving;
  }
  return r;
}

std::string program(double speed_rad_s, double acceleration_rad_s2) {
  if (!(std::isfinite(speed_rad_s) && speed_rad_s > 0 && std::isfinite(acceleration_rad_s2) && acceleration_rad_s2 > 0)) {
    std::ostringstream os;
    os << "UR program: speed " << speed_rad_s << " rad/s and acceleration " << acceleration_rad_s2
       << " rad/s^2 must be positive";
    throw std::invalid_argument(os.str());
  }
  std::ostringstream speed, accel;
  speed.precision(6);
  accel.precision(6);
  speed << speed_rad_s;
  accel << acceleration_rad_s2;
  return replaced(replaced(kProgram, "SPEED", speed.str()), "ACCEL", accel.str());
}

bool is_program(const std::string& text) {
  const std::string end = "\nend\n";
  return text.rfind(kProgramName, 0) == 0 && text.find("read_input_integer_register(0)") != std::string::npos &&
         text.find("write_output_integer_register(0, pbnbv_number)") != std::string::npos &&
         text.find("movej(") != std::string::npos && text.find("stopj(") != std::string::npos &&
         text.size() >= end.size() && text.compare(text.size() - end.size(), end.size(), end) == 0;
}

}  // namespace pbnbv::driver::ur
