#pragma once
// Conversions between the rig channels (ARM_STATUS, TURNTABLE_STATUS, ARM_COMMAND,
// TURNTABLE_COMMAND, DEPTH_FRAME) and the plain types of core/scan/rig_readings.hpp, with the
// validation every receiver applies: each from_msg throws std::invalid_argument naming the
// message and the field.
#include <string>

#include "bus/colour_codec.hpp"
#include "bus/convert.hpp"
#include "bus/rig_log.hpp"
#include "core/scan/replay_rig.hpp"
#include "core/scan/rig_readings.hpp"
#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/turntable_command_t.hpp"
#include "pbnbv/turntable_status_t.hpp"

namespace pbnbv::bus {

// A status's mode and fault code as the plain enums; throws naming `what` (the message) when
// either is not one of its constants (fault codes 0..`max_fault`: kFaultContact, 4, is the arm's
// only), or when the fault code and the mode disagree (a fault code is set exactly when the mode
// is kModeFault).
inline void rig_mode_from_msg(int8_t mode, int8_t fault_code, const std::string& what, RigMode* mode_out,
                              RigFault* fault_out, int max_fault = 3) {
  if (mode < 0 || mode > 3) {
    throw std::invalid_argument(what + " mode = " + std::to_string(mode) + " is not one of its constants (0..3)");
  }
  if (fault_code < 0 || fault_code > max_fault) {
    throw std::invalid_argument(what + " fault_code = " + std::to_string(fault_code) +
                                " is not one of its constants (0.." + std::to_string(max_fault) + ")");
  }
  *mode_out = static_cast<RigMode>(mode);
  *fault_out = static_cast<RigFault>(fault_code);
  if ((*mode_out == RigMode::kFault) != (*fault_out != RigFault::kNone)) {
    throw std::invalid_argument(what + " fault_code = " + std::to_string(fault_code) + " disagrees with mode = " +
                                std::to_string(mode) + " (a fault code is set exactly when the mode is kModeFault)");
  }
}

inline ArmReading from_msg(const arm_status_t& m) {
  ArmReading r;
  r.utime = m.utime;
  r.driver_utime = m.driver_utime;
  r.joint_position_rad = to_vector6(m.joint_position_rad, "ARM_STATUS joint_position_rad");
  r.joint_velocity_rad_s = to_vector6(m.joint_velocity_rad_s, "ARM_STATUS joint_velocity_rad_s");
  r.command_seq = m.command_seq;
  rig_mode_from_msg(m.mode, m.fault_code, "ARM_STATUS", &r.mode, &r.fault_code, arm_status_t::kFaultContact);
  r.fault_command_seq = m.fault_command_seq;
  r.fault = m.fault;
  contacts_from_msg(m.contacts, m.last_contact, "ARM_STATUS contacts", "ARM_STATUS last_contact");
  r.contacts = m.contacts;
  r.last_contact = m.last_contact;
  return r;
}

inline TurntableReading from_msg(const turntable_status_t& m) {
  TurntableReading r;
  r.utime = m.utime;
  r.driver_utime = m.driver_utime;
  require_range(m.angle_rad, -1e6, 1e6, "TURNTABLE_STATUS angle_rad");
  r.angle_rad = m.angle_rad;
  require_range(m.velocity_rad_s, -1e6, 1e6, "TURNTABLE_STATUS velocity_rad_s");
  r.velocity_rad_s = m.velocity_rad_s;
  r.command_seq = m.command_seq;
  rig_mode_from_msg(m.mode, m.fault_code, "TURNTABLE_STATUS", &r.mode, &r.fault_code);
  r.fault_command_seq = m.fault_command_seq;
  r.fault = m.fault;
  return r;
}

inline arm_command_t to_msg(const ArmCommand& c) {
  arm_command_t m;
  m.utime = 0;
  m.seq = c.seq;
  m.num_joints = 6;
  m.joint_position_rad = to_std(c.joint_position_rad);
  m.speed_scale = c.speed_scale;
  m.mode = c.hold ? arm_command_t::kModeHold : arm_command_t::kModePosition;
  return m;
}

inline turntable_command_t to_msg(const TurntableCommand& c) {
  turntable_command_t m;
  m.utime = 0;
  m.seq = c.seq;
  m.angle_rad = c.angle_rad;
  m.speed_scale = c.speed_scale;
  return m;
}

// Throws naming the bad field (intrinsics, range, size, depth unit, colour), as decode_frame and
// decode_colour.
inline DepthFrame from_msg(const depth_frame_t& m) {
  DecodedFrame d = decode_frame(m);
  DepthFrame f;
  f.utime = m.utime;
  f.seq = m.seq;
  f.trigger_seq = m.trigger_seq;
  f.exposure_start_utime = m.exposure_start_utime;
  f.exposure_us = m.exposure_us;
  f.camera_id = m.camera_id;
  f.intrinsics = d.intrinsics;
  f.range = d.range;
  f.depth_m = std::move(d.depth_m);
  f.distortion = d.distortion;
  f.colour = decode_colour(m);
  return f;
}

// The recorded rig (bus/rig_log.hpp) as the timeline the replay player plays: each message's rig
// time, place in the log, stillness (mode settled or idle), the command followed, command targets.
inline RigTimeline timeline_of(const RigLog& log) {
  const auto still = [](int8_t mode) { return mode == arm_status_t::kModeSettled || mode == arm_status_t::kModeIdle; };
  RigTimeline t;
  for (const auto& s : log.arm_statuses) {
    t.arm.push_back({s.msg.utime, s.order, still(s.msg.mode), s.msg.command_seq,
                     to_vector6(s.msg.joint_position_commanded_rad, "ARM_STATUS joint_position_commanded_rad")});
  }
  for (const auto& s : log.turntable_statuses) {
    RecordedStatus r{s.msg.utime, s.order, still(s.msg.mode), s.msg.command_seq, Vector6d::Zero()};
    r.commanded_rad[0] = s.msg.angle_commanded_rad;
    t.turntable.push_back(r);
  }
  for (const auto& f : log.frames) t.frames.push_back({f.msg.utime, f.order});
  for (const auto& c : log.arm_commands) {
    if (c.msg.mode != arm_command_t::kModePosition) continue;  // a hold is no view's and no stop's command
    RecordedCommand r;
    r.order = c.order;
    r.seq = c.msg.seq;
    r.target_rad = to_vector6(c.msg.joint_position_rad, "ARM_COMMAND joint_position_rad");
    t.arm_commands.push_back(r);
  }
  for (const auto& c : log.turntable_commands) {
    RecordedCommand r;
    r.order = c.order;
    r.seq = c.msg.seq;
    r.target_rad[0] = c.msg.angle_rad;
    t.turntable_commands.push_back(r);
  }
  return t;
}

}  // namespace pbnbv::bus
