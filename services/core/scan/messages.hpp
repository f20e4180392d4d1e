#pragma once
// The requests and answers of a scan's sequence as plain data: what the coordinator asks of the
// motion executor and the camera service, and what they answer. The bus translates them to and
// from the LCM messages of the same names (bus/convert_scan.hpp); the sequencing classes of this
// library work on these alone, so they are tested without a bus.
#include <Eigen/Geometry>
#include <cstdint>
#include <string>

#include "core/base/pose.hpp"
#include "core/geometry/point_cloud.hpp"

namespace pbnbv {

// MOVE_REQUEST: bring the camera to a pose (object frame).
struct MoveRequest {
  std::string scan_id;
  int iteration = 0;
  int64_t request_id = 0;
  Pose object_T_camera = Pose::Identity();
  double object_z_m = 0;                // object frame origin above the turntable top, m
  Eigen::AlignedBox3d keepout;          // object-frame box the rig must not enter (empty: none)
  double speed_scale = 1.0;             // (0, 1]: fraction of the joint speed limits
  double timeout_s = 60.0;              // not settled after this long: timed out
  bool plan_only = false;               // only check reachability
};

enum class MoveStatus : int8_t { kReached = 0, kUnreachable = 1, kTimedOut = 2, kRejected = 3, kPlanned = 4, kBusy = 5 };
const char* to_string(MoveStatus s);  // "reached", "unreachable", "timed_out", ...

// MOVE_RESULT: what became of a MoveRequest.
struct MoveResult {
  std::string scan_id;
  int iteration = 0;
  int64_t request_id = 0;
  MoveStatus status = MoveStatus::kRejected;
  std::string reason;                          // empty when reached
  Pose requested_object_T_camera = Pose::Identity();
  Pose reached_object_T_camera = Pose::Identity();  // forward kinematics of the readings at settle
  double position_error_m = 0;
  double angle_error_rad = 0;
  Vector6d joint_target_rad = Vector6d::Zero();
  Vector6d joint_position_rad = Vector6d::Zero();
  double turntable_target_rad = 0;
  double turntable_angle_rad = 0;
  double plan_s = 0, move_s = 0, settle_s = 0, rig_motion_s = 0;  // see move_result_t
  int64_t settled_utime = 0;                   // rig clock at settle, microseconds
};

// CAPTURE_REQUEST: one frame at the current pose, as an object-frame cloud.
struct CaptureRequest {
  std::string scan_id;
  int iteration = 0;
  int64_t request_id = 0;
  int64_t not_before_utime = 0;          // rig clock: only a frame exposed at or after this
  double object_z_m = 0;
  Eigen::AlignedBox3d crop;              // working volume, object frame
  double ground_clearance_m = 0;
  double voxel_m = 0;
  double timeout_s = 10.0;               // per trigger
};

// CLOUD: the answer to a CaptureRequest.
struct CaptureResult {
  std::string scan_id;
  int iteration = 0;
  int64_t request_id = 0;
  bool ok = false;
  std::string message;                     // what happened (why not, when !ok)
  Pose object_T_camera = Pose::Identity(); // the pose the points were placed with
  Vector6d joint_position_rad = Vector6d::Zero();
  double turntable_angle_rad = 0;
  int64_t depth_frame_seq = -1;
  int64_t depth_frame_utime = 0;
  int num_valid_pixels = 0;
  int num_cropped = 0;
  double voxel_m = 0;
  double capture_s = 0, process_s = 0;
  PointCloud points;                       // object frame, m
};

}  // namespace pbnbv
