#include "driver/rig_contract.hpp"

#include <cmath>
#include <sstream>
#include <utility>

#include "bus/depth_codec.hpp"

namespace pbnbv::driver {

namespace {

static_assert(static_cast<int8_t>(FaultCode::kCommandRejected) == arm_status_t::kFaultCommandRejected &&
                  static_cast<int8_t>(FaultCode::kDriver) == arm_status_t::kFaultDriver &&
                  static_cast<int8_t>(FaultCode::kOutOfLimits) == arm_status_t::kFaultOutOfLimits &&
                  static_cast<int8_t>(FaultCode::kContact) == arm_status_t::kFaultContact &&
                  static_cast<int8_t>(FaultCode::kCommandRejected) == turntable_status_t::kFaultCommandRejected &&
                  static_cast<int8_t>(FaultCode::kDriver) == turntable_status_t::kFaultDriver &&
                  static_cast<int8_t>(FaultCode::kOutOfLimits) == turntable_status_t::kFaultOutOfLimits,
              "FaultCode is the statuses' fault_code");

// The status mode of `motion` (Status: arm_status_t or turntable_status_t), or kModeFault.
template <class Status>
int8_t mode_of(Motion motion, const FaultLatch& fault) {
  if (fault.active()) return Status::kModeFault;
  return motion == Motion::kIdle ? Status::kModeIdle : motion == Motion::kMoving ? Status::kModeMoving : Status::kModeSettled;
}

template <class Status>
void fill_fault(Status& s, const FaultLatch& fault) {
  s.fault_code = static_cast<int8_t>(fault.code());
  s.fault_command_seq = fault.active() ? fault.command_seq() : -1;
  s.fault = fault.active() ? fault.text() : "";
}

// A speed scale in (0, 1]; `any`: any finite one (a driver that clamps it itself).
void check_speed_scale(double s, const char* what, bool any) {
  if (any ? !std::isfinite(s) : !(s > 0 && s <= 1)) {
    std::ostringstream os;
    os << what << " speed_scale " << s << (any ? " is not finite" : " is outside (0, 1]");
    throw std::invalid_argument(os.str());
  }
}

}  // namespace

arm_status_t arm_status(const Stamp& stamp, int64_t seq, const std::string& scan_id, const ArmReading& reading,
                        const FaultLatch& fault) {
  const std::size_t n = reading.joint_names.size();
  if (reading.position_rad.size() != n || reading.velocity_rad_s.size() != n || reading.commanded_rad.size() != n) {
    throw std::invalid_argument("arm_status: " + std::to_string(n) + " joint names, " +
                                std::to_string(reading.position_rad.size()) + " positions, " +
                                std::to_string(reading.velocity_rad_s.size()) + " velocities, " +
                                std::to_string(reading.commanded_rad.size()) + " targets");
  }
  if (reading.contacts < -1) {
    throw std::invalid_argument("arm_status: contacts " + std::to_string(reading.contacts) +
                                " (a count, or -1 when the driver cannot tell)");
  }
  if (reading.contacts <= 0 && !reading.last_contact.empty()) {
    throw std::invalid_argument("arm_status: a last contact ('" + reading.last_contact + "') with contacts " +
                                std::to_string(reading.contacts));
  }
  arm_status_t s;
  s.utime = stamp.utime;
  s.driver_utime = stamp.driver_utime;
  s.seq = seq;
  s.scan_id = scan_id;
  s.num_joints = static_cast<int32_t>(n);
  s.joint_names = reading.joint_names;
  s.joint_position_rad = reading.position_rad;
  s.joint_velocity_rad_s = reading.velocity_rad_s;
  s.joint_position_commanded_rad = reading.commanded_rad;
  s.command_seq = reading.command_seq;
  s.mode = mode_of<arm_status_t>(reading.motion, fault);
  fill_fault(s, fault);
  s.contacts = reading.contacts;
  s.last_contact = reading.last_contact;
  return s;
}

turntable_status_t turntable_status(const Stamp& stamp, int64_t seq, const std::string& scan_id,
                                    const TurntableReading& reading, const FaultLatch& fault) {
  if (fault.code() == FaultCode::kContact) {
    throw std::invalid_argument("turntable_status: fault kContact is the arm's (ARM_STATUS only)");
  }
  turntable_status_t t;
  t.utime = stamp.utime;
  t.driver_utime = stamp.driver_utime;
  t.seq = seq;
  t.scan_id = scan_id;
  t.angle_rad = reading.angle_rad;
  t.velocity_rad_s = reading.velocity_rad_s;
  t.angle_commanded_rad = reading.commanded_rad;
  t.command_seq = reading.command_seq;
  t.mode = mode_of<turntable_status_t>(reading.motion, fault);
  fill_fault(t, fault);
  return t;
}

ArmTarget arm_target(const arm_command_t& c, int num_joints, bool any_speed_scale) {
  ArmTarget t;
  t.seq = c.seq;
  if (c.mode == arm_command_t::kModeHold) {
    t.hold = true;
    return t;
  }
  if (c.mode != arm_command_t::kModePosition) throw std::invalid_argument("unknown mode " + std::to_string(c.mode));
  if (c.num_joints != num_joints) {
    throw std::invalid_argument("num_joints = " + std::to_string(c.num_joints) + ", this arm has " +
                                std::to_string(num_joints));
  }
  for (int i = 0; i < num_joints; ++i) {
    if (!std::isfinite(c.joint_position_rad[static_cast<std::size_t>(i)])) {
      std::ostringstream os;
      os << "joint_position_rad: joint " << i << " value " << c.joint_position_rad[static_cast<std::size_t>(i)]
         << " is not finite";
      throw std::invalid_argument(os.str());
    }
  }
  check_speed_scale(c.speed_scale, "ARM_COMMAND", any_speed_scale);
  t.position_rad = c.joint_position_rad;
  t.speed_scale = c.speed_scale;
  return t;
}

TurntableTarget turntable_target(const turntable_command_t& c, bool any_speed_scale) {
  if (!std::isfinite(c.angle_rad)) {
    std::ostringstream os;
    os << "angle_rad " << c.angle_rad << " is not finite";
    throw std::invalid_argument(os.str());
  }
  check_speed_scale(c.speed_scale, "TURNTABLE_COMMAND", any_speed_scale);
  return TurntableTarget{c.angle_rad, c.speed_scale, c.seq};
}

std::vector<uint16_t> depth_counts(const std::vector<float>& depth_m, double unit_m) {
  if (!(unit_m > 0)) throw std::invalid_argument("depth_counts: unit " + std::to_string(unit_m) + " m is not positive");
  std::vector<uint16_t> counts(depth_m.size());
  for (std::size_t i = 0; i < depth_m.size(); ++i) {
    const double c = std::round(depth_m[i] / unit_m);
    counts[i] = c > 0 && c < 65535 ? static_cast<uint16_t>(c) : 0;  // NaN compares false: 0
  }
  return counts;
}

depth_frame_t depth_frame(const DepthCamera& camera, const std::vector<uint16_t>& counts, const Exposure& exposure,
                          int64_t frame_seq, const depth_trigger_t& trigger) {
  const std::size_t pixels = static_cast<std::size_t>(camera.width) * static_cast<std::size_t>(camera.height);
  if (camera.width <= 0 || camera.height <= 0 || counts.size() != pixels) {
    throw std::invalid_argument("depth_frame: " + std::to_string(counts.size()) + " counts for a " +
                                std::to_string(camera.width) + "x" + std::to_string(camera.height) + " camera");
  }
  depth_frame_t f{};  // every field zero: no colour image (bus::set_colour adds one)
  f.depth_T_colour.quat_wxyz[0] = 1;  // the identity, for a reader of the message
  f.utime = exposure.start_utime + exposure.duration_us / 2;
  f.exposure_start_utime = exposure.start_utime;
  f.exposure_us = exposure.duration_us;
  f.camera_id = camera.camera_id;
  f.seq = frame_seq;
  f.trigger_seq = trigger.seq;
  f.scan_id = trigger.scan_id;
  f.width = camera.width;
  f.height = camera.height;
  f.fx = camera.fx;
  f.fy = camera.fy;
  f.cx = camera.cx;
  f.cy = camera.cy;
  f.depth_min_m = camera.depth_min_m;
  f.depth_max_m = camera.depth_max_m;
  f.depth_unit_m = camera.depth_unit_m;
  for (int i = 0; i < 5; ++i) f.distortion[i] = camera.distortion[static_cast<std::size_t>(i)];
  std::vector<uint8_t> raw(2 * pixels);
  for (std::size_t i = 0; i < pixels; ++i) {  // little-endian, whatever the host
    raw[2 * i] = static_cast<uint8_t>(counts[i] & 0xff);
    raw[2 * i + 1] = static_cast<uint8_t>(counts[i] >> 8);
  }
  if (camera.compress) {
    f.encoding = depth_frame_t::kEncodingZlib;
    f.depth = bus::deflate_bytes(raw, 1);
  } else {
    f.encoding = depth_frame_t::kEncodingRaw;
    f.depth = std::move(raw);
  }
  f.num_bytes = static_cast<int32_t>(f.depth.size());
  return f;
}

}  // namespace pbnbv::driver
