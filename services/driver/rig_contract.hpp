#pragma once
// The rig contract (lcmtypes/arm_*, turntable_*, depth_*) as a driver speaks it, in plain
// functions on the messages: a status from what the driver measured, with both clocks, the last
// accepted command echoed and a refused one reported by its fault code; a command checked as the
// contract says before anything moves; a depth image as the DEPTH_FRAME that answers a trigger,
// stamped with its exposure. No bus here: rig_driver.hpp puts these on LCM.
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/depth_trigger_t.hpp"
#include "pbnbv/turntable_command_t.hpp"
#include "pbnbv/turntable_status_t.hpp"

namespace pbnbv::driver {

// How often a driver publishes its statuses: the contract asks for 50 Hz at least; the twin
// publishes every 10 ms of rig time.
inline constexpr double kStatusPeriodS = 0.01;

// A joint group's motion, as the status's mode reports it when there is no fault.
enum class Motion { kIdle, kMoving, kSettled };

// Why a command was refused, or what stopped it: the status's fault_code (the same values in
// arm_status_t and turntable_status_t; kContact, the arm touching something, in arm_status_t only).
enum class FaultCode : int8_t { kNone = 0, kCommandRejected = 1, kDriver = 2, kOutOfLimits = 3, kContact = 4 };

// A command target outside its joint's limits or the turntable's travel: reported as
// kOutOfLimits (any other refusal is kCommandRejected). A driver's move handler throws it.
struct OutOfLimits : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// The last command a driver refused (or its drive's failure), until it accepts one: what the
// status's fault fields report.
class FaultLatch {
 public:
  void set(FaultCode code, int64_t command_seq, std::string text) {
    code_ = code;
    command_seq_ = command_seq;
    text_ = std::move(text);
  }
  void clear() { set(FaultCode::kNone, -1, ""); }
  bool active() const { return code_ != FaultCode::kNone; }
  FaultCode code() const { return code_; }
  int64_t command_seq() const { return command_seq_; }
  const std::string& text() const { return text_; }

 private:
  FaultCode code_ = FaultCode::kNone;
  int64_t command_seq_ = -1;
  std::string text_;
};

// One measurement's time on both clocks: utime on the host's clock (microseconds since the
// epoch; the clock DEPTH_FRAME exposures are stamped on), driver_utime on the device's own.
struct Stamp {
  int64_t utime = 0;
  int64_t driver_utime = 0;
};

// What an arm driver measured: one entry per joint, base to flange.
struct ArmReading {
  std::vector<std::string> joint_names;
  std::vector<double> position_rad;
  std::vector<double> velocity_rad_s;
  std::vector<double> commanded_rad;  // the target being tracked
  int64_t command_seq = -1;           // the last ARM_COMMAND accepted (-1: none yet)
  Motion motion = Motion::kIdle;
  // Contact events since the driver started (the arm touching anything else, each onset once),
  // -1 when the driver cannot tell (the default: a driver without collision detection), and the
  // last one for people ("" while there is none).
  int32_t contacts = -1;
  std::string last_contact = "";
};

struct TurntableReading {
  double angle_rad = 0;  // not wrapped
  double velocity_rad_s = 0;
  double commanded_rad = 0;
  int64_t command_seq = -1;  // the last TURNTABLE_COMMAND accepted (-1: none yet)
  Motion motion = Motion::kIdle;
};

// The statuses of a reading: mode kModeFault with the latch's code, command and text while it is
// active, else the reading's motion. `scan_id` is the scan the driver serves ("": any). Throws
// std::invalid_argument when the arm reading's vectors are not one entry per joint name, its
// contacts below -1, or a last contact given while contacts is 0 or -1 (and for a turntable fault
// kContact, which is the arm's).
arm_status_t arm_status(const Stamp& stamp, int64_t seq, const std::string& scan_id, const ArmReading& reading,
                        const FaultLatch& fault);
turntable_status_t turntable_status(const Stamp& stamp, int64_t seq, const std::string& scan_id,
                                    const TurntableReading& reading, const FaultLatch& fault);

// A command as a driver acts on it.
struct ArmTarget {
  bool hold = false;  // kModeHold: stop where the arm is (position_rad empty)
  std::vector<double> position_rad;
  double speed_scale = 1;
  int64_t seq = -1;
};
struct TurntableTarget {
  double angle_rad = 0;
  double speed_scale = 1;
  int64_t seq = -1;
};

// Checks a command as the contract says (a known mode, `num_joints` finite targets, a speed scale
// in (0, 1]; `any_speed_scale`: any finite one, for a driver that clamps it itself). Throws
// std::invalid_argument saying what is wrong; nothing is to move then.
ArmTarget arm_target(const arm_command_t& command, int num_joints, bool any_speed_scale = false);
TurntableTarget turntable_target(const turntable_command_t& command, bool any_speed_scale = false);

// What a depth camera reports with each frame.
struct DepthCamera {
  std::string camera_id;  // serial number or id
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;  // pixels
  double depth_min_m = 0;                 // valid range: other readings are reported as 0
  double depth_max_m = 0;
  double depth_unit_m = 1e-4;  // metres per count (0.1 mm: up to 6.55 m)
  std::array<double, 5> distortion{};  // k1 k2 p1 p2 k3 of the images as sent (0: pinhole images)
  bool compress = true;        // zlib (kEncodingZlib), else raw counts
};

// Planar depths in metres, row-major, as the frame's counts of `unit_m`: 0 for no reading (not
// finite, not positive, or beyond 65,534 counts).
std::vector<uint16_t> depth_counts(const std::vector<float>& depth_m, double unit_m);

// The exposure of a frame on the host's clock (the statuses' utime).
struct Exposure {
  int64_t start_utime = 0;
  int32_t duration_us = 0;  // 0: instantaneous
};

// The DEPTH_FRAME answering `trigger` (its seq and scan echoed) with `counts` (width x height,
// row-major, row 0 at the top); utime is the middle of the exposure. Throws std::invalid_argument
// when the counts are not width x height.
depth_frame_t depth_frame(const DepthCamera& camera, const std::vector<uint16_t>& counts, const Exposure& exposure,
                          int64_t frame_seq, const depth_trigger_t& trigger);

}  // namespace pbnbv::driver
