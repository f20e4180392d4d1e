#pragma once
// What the rig says and what it is told, as plain data: the arm's and the turntable's status
// (ARM_STATUS, TURNTABLE_STATUS), their position commands (ARM_COMMAND, TURNTABLE_COMMAND) and a
// decoded depth frame (DEPTH_FRAME). The bus translates them to and from the LCM messages
// (bus/convert_rig.hpp); the motion and capture sequencers of this library work on these alone.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/base/pose.hpp"
#include "core/geometry/camera_model.hpp"
#include "core/geometry/colour_image.hpp"
#include "core/geometry/lens_distortion.hpp"

namespace pbnbv {

// A driver's mode (arm_status_t / turntable_status_t kMode*; the same values for both).
enum class RigMode : int8_t {
  kIdle = 0,     // holding position, no command pending
  kMoving = 1,   // tracking a target
  kSettled = 2,  // at the target of command_seq, still
  kFault = 3,    // see the fault code
};

// Why a driver is in kFault (arm_status_t / turntable_status_t kFault*; the same values for both).
enum class RigFault : int8_t {
  kNone = 0,             // no fault
  kCommandRejected = 1,  // a command was refused as malformed (target not finite, speed_scale
                         // outside (0, 1], wrong joint count); the rig keeps holding
  kDriver = 2,           // the drive itself failed (amplifier, following error, emergency stop)
  kOutOfLimits = 3,      // a command was refused: a target outside its joint's limits
  kContact = 4,          // the arm touched something and stopped (ARM_STATUS only)
};
const char* to_string(RigFault f);  // "none", "command_rejected", "driver", "out_of_limits", "contact"

// ARM_STATUS: the measured state of the arm (or the free rig's gantry).
struct ArmReading {
  int64_t utime = 0;                          // rig clock, microseconds
  int64_t driver_utime = 0;                   // the driver's own clock, microseconds
  Vector6d joint_position_rad = Vector6d::Zero();
  Vector6d joint_velocity_rad_s = Vector6d::Zero();
  int64_t command_seq = -1;                   // last ARM_COMMAND accepted (-1: none)
  RigMode mode = RigMode::kIdle;
  RigFault fault_code = RigFault::kNone;
  int64_t fault_command_seq = -1;             // the command the fault refers to (-1: none)
  std::string fault;                          // the fault for people
  int32_t contacts = -1;                      // contact events since the driver started (-1: it cannot tell)
  std::string last_contact;                   // the last one for people ("" while none)
};

// TURNTABLE_STATUS: the measured state of the turntable.
struct TurntableReading {
  int64_t utime = 0;                          // rig clock, microseconds
  int64_t driver_utime = 0;                   // the driver's own clock, microseconds
  double angle_rad = 0;                       // not wrapped
  double velocity_rad_s = 0;
  int64_t command_seq = -1;                   // last TURNTABLE_COMMAND accepted (-1: none)
  RigMode mode = RigMode::kIdle;
  RigFault fault_code = RigFault::kNone;
  int64_t fault_command_seq = -1;
  std::string fault;
};

// ARM_COMMAND in position mode: move every joint to its target, all arriving together.
struct ArmCommand {
  int64_t seq = 0;                            // increasing; ARM_STATUS command_seq echoes it
  Vector6d joint_position_rad = Vector6d::Zero();
  double speed_scale = 1.0;                   // (0, 1] of the joint speed limits
  bool hold = false;                          // stop where the arm is (the targets are ignored)
};

// TURNTABLE_COMMAND: turn to an angle (not wrapped).
struct TurntableCommand {
  int64_t seq = 0;
  double angle_rad = 0;
  double speed_scale = 1.0;
};

// DEPTH_FRAME, decoded: planar depth in metres (0 or non-finite: no return), row-major.
struct DepthFrame {
  int64_t utime = 0;        // exposure (middle), rig clock, microseconds
  int64_t exposure_start_utime = 0;  // rig clock, microseconds
  int32_t exposure_us = 0;  // exposure duration, microseconds
  std::string camera_id;    // the camera's serial / id
  int64_t seq = -1;         // the camera's frame number
  int64_t trigger_seq = -1; // the DEPTH_TRIGGER it answers
  CameraIntrinsics intrinsics;
  DepthRange range;
  std::vector<float> depth_m;  // pinhole: resampled when the frame came through a lens
  LensDistortion distortion;   // the lens the frame said it was taken through
  std::optional<ColourImage> colour;  // the colour image taken with it, when the camera has one
};

}  // namespace pbnbv
