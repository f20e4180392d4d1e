// pbnbv-ur-driver: the arm driver for a Universal Robots e-Series arm, on the driver library
// (services/driver): it owns the arm alone (ARM_COMMAND in, ARM_STATUS out; the lab's other
// driver owns the turntable and the camera). It talks RTDE to the controller (port 30004) and
// sends it once per connection the program that moves the arm from the input registers
// (driver/ur_arm.hpp, on the secondary interface, port 30002). Every data package becomes an
// ARM_STATUS (utime: the controller's timestamp on the host's clock, offset at the connection's first
// package; driver_utime: the controller's timestamp); a safety
// stop or a lost connection is the status's kFaultDriver; the driver reconnects by itself and
// never clears a protective stop. docs/real-rig.md, "Universal Robots e-Series".
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <iostream>
#include <memory>
#include <sstream>

#include "bus/bus.hpp"
#include "cli/options.hpp"
#include "core/base/log.hpp"
#include "core/base/signals.hpp"
#include "core/rig/rig.hpp"
#include "driver/rig_driver.hpp"
#include "driver/ur_arm.hpp"
#include "rtde_client.hpp"

using namespace pbnbv;
namespace ur = driver::ur;

namespace {

constexpr double kStepTimeoutS = 1.0;      // connect, and each handshake answer
constexpr double kDataTimeoutS = 1.0;      // no data package for this long: the connection is lost
constexpr double kFirstBackoffS = 0.5;     // reconnect after this, doubling up to kMaxBackoffS
constexpr double kMaxBackoffS = 2.0;
constexpr double kWriteTimeoutS = 0.1;     // input registers
// movej's acceleration at speed scale 1: pbnbv::kAccelerationPerSpeed (core/rig/rig.hpp) times
// its speed per second, the rig-time model's default (full speed in a quarter of a second).

struct Options {
  std::string host;
  int64_t port = driver::rtde::kPort;
  int64_t script_port = ur::kScriptPort;
  std::string rig_model;
  std::string scope;
  double frequency_hz = 125;
};

// The driver: the RTDE session (or its absence), what was last sent and read, the statuses.
class UrDriver {
 public:
  UrDriver(const Options& o, const RigModel& rig, bus::Bus& bus)
      : o_(o), rig_(rig), bus_(bus), rig_driver_(bus, handlers(), driver::RigDriver::Options{}) {
    // movej's speed is its leading joint's: the slowest joint's limit keeps every joint within its own.
    const double speed = rig.qd_max.minCoeff();
    program_ = ur::program(speed, speed * kAccelerationPerSpeed);
  }

  // Connects (the first connection must succeed: its error is the program's), then serves until
  // SIGINT / SIGTERM: the arm stopped, the stream paused, the connection closed.
  void run() {
    connect();
    while (!stop_requested()) {
      if (client_) {
        serve();
      } else {
        reconnect_when_due();
        bus_.spin_once(10);
        publish_lost();
      }
    }
    shut_down();
  }

 private:
  // ARM_COMMAND (checked by the library): refused while the drive or the link is down, or out of
  // the rig file's limits; else written to the registers under a new command number.
  driver::RigDriver::Handlers handlers() {
    driver::RigDriver::Handlers h;
    h.move_arm = [this](const driver::ArmTarget& t) {
      if (!client_) throw std::invalid_argument("the arm cannot move: " + lost_text());
      if (const std::string f = ur::drive_fault(state_); !f.empty()) {
        throw std::invalid_argument("the arm cannot move: " + f);
      }
      if (!t.hold) check_limits(t.position_rad);
      Command c;
      c.sent.number = sent_.sent.number == INT32_MAX ? 1 : sent_.sent.number + 1;
      c.sent.seq = t.seq;
      c.sent.hold = t.hold;
      if (t.hold) {
        c.sent.target = state_.q;
      } else {
        std::copy(t.position_rad.begin(), t.position_rad.end(), c.sent.target.begin());
      }
      c.speed_scale = t.speed_scale;
      write(c);
    };
    return h;
  }

  void check_limits(const std::vector<double>& q) const {
    for (int i = 0; i < 6; ++i) {
      if (q[i] < rig_.q_lower[i] || q[i] > rig_.q_upper[i]) {
        std::ostringstream os;
        os << "joint " << rig_.joint_names[i] << " target " << q[i] << " rad is outside its limits [" << rig_.q_lower[i]
           << ", " << rig_.q_upper[i] << "] (" << rig_.model_path << ")";
        throw driver::OutOfLimits(os.str());
      }
    }
  }

  // The command written into the input registers; it is what the program's echo is read against.
  struct Command {
    ur::Sent sent;
    double speed_scale = 1;
  };

  // Writes `c` and makes it the command sent; a failed write loses the connection and refuses.
  void write(const Command& c) {
    try {
      write_registers(c);
    } catch (const std::exception& e) {
      lose(e.what());
      throw std::invalid_argument("the arm cannot move: " + lost_text());
    }
    sent_ = c;
  }

  void write_registers(const Command& c) {
    ur::Registers r;
    r.target = c.sent.target;
    r.speed_scale = c.speed_scale;
    r.number = c.sent.number;
    r.stop = c.sent.hold;
    client_->write(r, kWriteTimeoutS);
  }

  // One connection: the session, the registers as last written (so the program starts with
  // nothing to do), the program; a move the connection cut short is started again.
  void connect() {
    client_ = std::make_unique<ur_driver::RtdeClient>(o_.host, static_cast<int>(o_.port), o_.frequency_hz,
                                                      kStepTimeoutS, [this] { publish_lost(); });
    const driver::rtde::UrControlVersion& v = client_->version();
    log_info("RTDE: connected to " + client_->address() + ", URControl " + std::to_string(v.major) + "." +
             std::to_string(v.minor) + "." + std::to_string(v.bugfix) + "." + std::to_string(v.build) +
             fmt::format(", {:g} Hz", o_.frequency_hz));
    Command standing = sent_;
    standing.sent.hold = true;  // the number unchanged: the program starts with nothing to do
    write_registers(standing);
    ur_driver::send_program(o_.host, static_cast<int>(o_.script_port), program_, kStepTimeoutS);
    log_info("sent the program (" + std::to_string(program_.size()) + " bytes) to " + o_.host + ":" +
             std::to_string(o_.script_port));
    last_data_s_ = bus::now_s();
    if (!sent_.sent.hold && sent_.sent.number != 0 && lost_at_s_ >= 0) {
      Command again = sent_;
      again.sent.number = sent_.sent.number == INT32_MAX ? 1 : sent_.sent.number + 1;
      log_info("starting ARM_COMMAND seq " + std::to_string(again.sent.seq) + "'s move again after the reconnect");
      write(again);
    }
  }

  // Connected: every data package becomes a status; commands are taken between packages.
  void serve() {
    try {
      const std::optional<ur::State> s = client_->next_state(0.005);
      bus_.spin_once(0);
      if (!client_) return;  // a command's write lost the connection
      if (s) {
        last_data_s_ = bus::now_s();
        on_state(*s);
      } else if (bus::now_s() - last_data_s_ > kDataTimeoutS) {
        lose("no data package in " + std::to_string(kDataTimeoutS).substr(0, 3) + " s");
      }
    } catch (const std::exception& e) {
      lose(e.what());
    }
  }

  void on_state(const ur::State& s) {
    state_ = s;
    have_state_ = true;
    if (lost_at_s_ >= 0) {
      log_info(fmt::format("RTDE: data flows again, {:.2f} s after the connection was lost", bus::now_s() - lost_at_s_));
      lost_at_s_ = -1;
    }
    const std::string fault = ur::drive_fault(s);
    if (fault != rig_driver_.arm_drive_fault().text()) {
      if (fault.empty()) {
        log_info("the arm's drive is well again");
      } else {
        log_warn(fault);
      }
    }
    rig_driver_.set_arm_drive_fault(fault);
    const int64_t driver_us = std::llround(s.timestamp_s * 1e6);
    // The reading's time on the host's clock: the controller's timestamp moved by the offset
    // between the clocks taken at the connection's first package (its transport delay, under a
    // millisecond on the rig's network), so that the readings keep the controller's own spacing
    // (a loaded host receives them in bursts) and a twin playing the controller at --speed N,
    // whose camera stamps frames on its own rig clock, stays on that clock.
    if (!clock_offset_us_) clock_offset_us_ = bus::now_utime() - driver_us;
    publish(ur::reading_of(s, sent_.sent, rig_.joint_names), driver_us, driver_us + *clock_offset_us_);
  }

  // Publishes with both clocks strictly increasing (a reconnected controller's clock is floored
  // at the last stamp).
  void publish(const driver::ArmReading& reading, int64_t driver_us, int64_t host_us) {
    driver::Stamp stamp;
    stamp.utime = std::max(host_us, last_stamp_.utime + 1);
    stamp.driver_utime = std::max(driver_us, last_stamp_.driver_utime + 1);
    last_stamp_ = stamp;
    last_publish_s_ = bus::now_s();
    rig_driver_.publish_statuses(stamp, reading, std::nullopt);
  }

  // Without a connection the statuses keep going, every 10 ms, with the last reading and the
  // link's fault (the controller's clock carried on by the host's).
  void publish_lost() {
    if (lost_at_s_ < 0 || !have_state_ || bus::now_s() - last_publish_s_ < driver::kStatusPeriodS) return;
    rig_driver_.set_arm_drive_fault(lost_text());
    driver::ArmReading r = ur::reading_of(state_, sent_.sent, rig_.joint_names);
    std::fill(r.velocity_rad_s.begin(), r.velocity_rad_s.end(), 0.0);
    const int64_t elapsed_us = std::max<int64_t>(0, std::llround((bus::now_s() - last_publish_s_) * 1e6));
    publish(r, last_stamp_.driver_utime + elapsed_us, last_stamp_.utime + elapsed_us);
  }

  void lose(const std::string& why) {
    client_.reset();
    clock_offset_us_.reset();  // the next connection's first package sets it again
    lost_why_ = why;
    lost_at_s_ = bus::now_s();
    backoff_s_ = kFirstBackoffS;
    next_attempt_s_ = lost_at_s_ + backoff_s_;
    log_warn(lost_text() + "; reconnecting");
    publish_lost();
  }

  std::string lost_text() const {
    return "RTDE connection to " + o_.host + ":" + std::to_string(o_.port) + " lost: " + lost_why_;
  }

  void reconnect_when_due() {
    if (bus::now_s() < next_attempt_s_) return;
    try {
      connect();
    } catch (const std::exception& e) {
      client_.reset();
      backoff_s_ = std::min(2 * backoff_s_, kMaxBackoffS);
      next_attempt_s_ = bus::now_s() + backoff_s_;
      log_warn(std::string("reconnecting: ") + e.what() + fmt::format("; next attempt in {:.1f} s", backoff_s_));
    }
  }

  // Stops the arm where it is (a hold), pauses the stream; errors are logged, not thrown.
  void shut_down() {
    if (!client_) return;
    try {
      if (sent_.sent.number != 0 && !sent_.sent.hold) {
        Command hold = sent_;
        hold.sent.number = sent_.sent.number == INT32_MAX ? 1 : sent_.sent.number + 1;
        hold.sent.hold = true;
        write(hold);
      }
      if (client_) client_->pause(0.5);
    } catch (const std::exception& e) {
      log_warn(std::string("stopping: ") + e.what());
    }
    client_.reset();
  }

  const Options& o_;
  const RigModel& rig_;
  bus::Bus& bus_;
  std::unique_ptr<ur_driver::RtdeClient> client_;
  driver::RigDriver rig_driver_;
  std::string program_;
  Command sent_;
  ur::State state_;
  bool have_state_ = false;
  driver::Stamp last_stamp_;
  std::optional<int64_t> clock_offset_us_;  // host utime - controller time, this connection's
  double last_publish_s_ = 0, last_data_s_ = 0;
  double lost_at_s_ = -1, next_attempt_s_ = 0, backoff_s_ = kFirstBackoffS;
  std::string lost_why_;
};

void add_options(CLI::App& app, Options& o) {
  cli::add_text(app, "host", &o.host, "the UR controller's address (required)", "ADDRESS")->required();
  cli::add(app, Setting<int64_t>{"port", driver::rtde::kPort, 1, 65535, "", "the controller's RTDE port"}, &o.port);
  cli::add(app, Setting<int64_t>{"script-port", ur::kScriptPort, 1, 65535, "",
                                 "the controller's secondary interface, where the driver's URScript program is sent"},
           &o.script_port);
  cli::add_text(app, "rig-model", &o.rig_model, "the rig file: joint names, limits and speed limits (required)", "FILE")
      ->required();
  cli::add_text(app, "scan", &o.scope, "serve this scan only (default: every command, as a driver does)", "ID");
  cli::add(app, Setting<double>{"frequency", 125, 10, 500, "Hz", "RTDE data (and ARM_STATUS) rate"}, &o.frequency_hz);
}

}  // namespace

int main(int argc, char** argv) {
  set_log_name("ur-driver");
  CLI::App app{"pbnbv-ur-driver: the arm driver for a Universal Robots e-Series arm (RTDE), on the rig channels",
               "pbnbv-ur-driver"};
  cli::init(app);
  Options o;
  add_options(app, o);
  if (const std::optional<int> code = cli::parse(app, argc, argv, std::cout, std::cerr)) return *code;
  install_stop_handlers();
  try {
    if (o.port == o.script_port) throw std::invalid_argument("--port and --script-port are both " + std::to_string(o.port));
    const RigModel rig = load_rig(o.rig_model);
    if (rig.kind != RigKind::kArm) throw std::invalid_argument("--rig-model " + o.rig_model + " is not an arm's rig file");
    bus::Bus bus("ur-driver");
    bus.serve_scan(o.scope);
    UrDriver(o, rig, bus).run();
    log_info("stopped");
    return 0;
  } catch (const std::exception& e) {
    log_error(e.what());
    return 2;
  }
}
