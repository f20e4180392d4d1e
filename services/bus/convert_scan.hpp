#pragma once
// Conversions between the scan sequence's messages (MOVE_REQUEST, MOVE_RESULT, CAPTURE_REQUEST,
// CLOUD) and the plain types of core/scan/messages.hpp, with the validation every receiver
// applies: each from_msg throws std::invalid_argument naming the message and the field.
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "bus/convert.hpp"
#include "core/scan/messages.hpp"
#include "pbnbv/capture_request_t.hpp"
#include "pbnbv/move_request_t.hpp"
#include "pbnbv/move_result_t.hpp"
#include "pbnbv/point_cloud_t.hpp"

namespace pbnbv::bus {

// An object-frame box as the messages carry it: min and max corners, min == max for "no box".
inline void box_to_arrays(const Eigen::AlignedBox3d& box, double min_m[3], double max_m[3]) {
  for (int k = 0; k < 3; ++k) {
    min_m[k] = box.isEmpty() ? 0.0 : box.min()[k];
    max_m[k] = box.isEmpty() ? 0.0 : box.max()[k];
  }
}

// Throws naming `what` when a corner is not finite, outside [-limit_m, limit_m], or min > max.
inline Eigen::AlignedBox3d box_from_arrays(const double min_m[3], const double max_m[3], double limit_m,
                                           const std::string& what) {
  Eigen::Vector3d lo, hi;
  for (int k = 0; k < 3; ++k) {
    require_range(min_m[k], -limit_m, limit_m, what + "_min_m[" + std::to_string(k) + "]");
    require_range(max_m[k], min_m[k], limit_m, what + "_max_m[" + std::to_string(k) + "]");
    lo[k] = min_m[k];
    hi[k] = max_m[k];
  }
  if (lo == hi) return Eigen::AlignedBox3d();  // no box
  return Eigen::AlignedBox3d(lo, hi);
}

inline move_request_t to_msg(const MoveRequest& r) {
  move_request_t m;
  m.utime = 0;
  m.scan_id = r.scan_id;
  m.iteration = r.iteration;
  m.request_id = r.request_id;
  m.object_T_camera = to_msg(r.object_T_camera);
  m.object_z_m = r.object_z_m;
  box_to_arrays(r.keepout, m.keepout_min_m, m.keepout_max_m);
  m.speed_scale = r.speed_scale;
  m.timeout_s = r.timeout_s;
  m.plan_only = r.plan_only;
  return m;
}

inline MoveRequest from_msg(const move_request_t& m) {
  MoveRequest r;
  r.scan_id = m.scan_id;
  r.iteration = m.iteration;
  r.request_id = m.request_id;
  r.object_T_camera = from_msg(m.object_T_camera, "MOVE_REQUEST object_T_camera");
  require_range(m.object_z_m, -1.0, 2.0, "MOVE_REQUEST object_z_m");
  r.object_z_m = m.object_z_m;
  r.keepout = box_from_arrays(m.keepout_min_m, m.keepout_max_m, 5.0, "MOVE_REQUEST keepout");
  require_range(m.speed_scale, 1e-3, 1.0, "MOVE_REQUEST speed_scale");
  r.speed_scale = m.speed_scale;
  require_range(m.timeout_s, 0.1, 3600.0, "MOVE_REQUEST timeout_s");
  r.timeout_s = m.timeout_s;
  r.plan_only = m.plan_only;
  return r;
}

inline move_result_t to_msg(const MoveResult& r) {
  move_result_t m;
  m.utime = 0;
  m.scan_id = r.scan_id;
  m.iteration = r.iteration;
  m.request_id = r.request_id;
  m.status = static_cast<int8_t>(r.status);
  m.reason = r.reason;
  m.requested_object_T_camera = to_msg(r.requested_object_T_camera);
  m.reached_object_T_camera = to_msg(r.reached_object_T_camera);
  m.position_error_m = r.position_error_m;
  m.angle_error_rad = r.angle_error_rad;
  m.num_joints = 6;
  m.joint_target_rad = to_std(r.joint_target_rad);
  m.joint_position_rad = to_std(r.joint_position_rad);
  m.turntable_target_rad = r.turntable_target_rad;
  m.turntable_angle_rad = r.turntable_angle_rad;
  m.plan_s = r.plan_s;
  m.move_s = r.move_s;
  m.settle_s = r.settle_s;
  m.rig_motion_s = r.rig_motion_s;
  m.settled_utime = r.settled_utime;
  return m;
}

inline MoveResult from_msg(const move_result_t& m) {
  MoveResult r;
  r.scan_id = m.scan_id;
  r.iteration = m.iteration;
  r.request_id = m.request_id;
  if (m.status < move_result_t::kReached || m.status > move_result_t::kBusy) {
    throw std::invalid_argument("MOVE_RESULT status = " + std::to_string(m.status) + " is not one of its constants (0..5)");
  }
  r.status = static_cast<MoveStatus>(m.status);
  r.reason = m.reason;
  r.requested_object_T_camera = from_msg(m.requested_object_T_camera, "MOVE_RESULT requested_object_T_camera");
  r.reached_object_T_camera = from_msg(m.reached_object_T_camera, "MOVE_RESULT reached_object_T_camera");
  r.position_error_m = m.position_error_m;
  r.angle_error_rad = m.angle_error_rad;
  r.joint_target_rad = to_vector6(m.joint_target_rad, "MOVE_RESULT joint_target_rad");
  r.joint_position_rad = to_vector6(m.joint_position_rad, "MOVE_RESULT joint_position_rad");
  r.turntable_target_rad = m.turntable_target_rad;
  r.turntable_angle_rad = m.turntable_angle_rad;
  r.plan_s = m.plan_s;
  r.move_s = m.move_s;
  r.settle_s = m.settle_s;
  r.rig_motion_s = m.rig_motion_s;
  r.settled_utime = m.settled_utime;
  return r;
}

inline capture_request_t to_msg(const CaptureRequest& r) {
  capture_request_t m;
  m.utime = 0;
  m.scan_id = r.scan_id;
  m.iteration = r.iteration;
  m.request_id = r.request_id;
  m.not_before_utime = r.not_before_utime;
  m.object_z_m = r.object_z_m;
  box_to_arrays(r.crop, m.crop_min_m, m.crop_max_m);
  m.ground_clearance_m = r.ground_clearance_m;
  m.voxel_m = r.voxel_m;
  m.timeout_s = r.timeout_s;
  return m;
}

inline CaptureRequest from_msg(const capture_request_t& m) {
  CaptureRequest r;
  r.scan_id = m.scan_id;
  r.iteration = m.iteration;
  r.request_id = m.request_id;
  r.not_before_utime = m.not_before_utime;
  require_range(m.object_z_m, -1.0, 2.0, "CAPTURE_REQUEST object_z_m");
  r.object_z_m = m.object_z_m;
  r.crop = box_from_arrays(m.crop_min_m, m.crop_max_m, 10.0, "CAPTURE_REQUEST crop");
  require_range(m.ground_clearance_m, 0.0, 0.5, "CAPTURE_REQUEST ground_clearance_m");
  r.ground_clearance_m = m.ground_clearance_m;
  require_range(m.voxel_m, 0.0, 0.1, "CAPTURE_REQUEST voxel_m");
  r.voxel_m = m.voxel_m;
  require_range(m.timeout_s, 0.1, 600.0, "CAPTURE_REQUEST timeout_s");
  r.timeout_s = m.timeout_s;
  return r;
}

inline point_cloud_t to_msg(const CaptureResult& c) {
  point_cloud_t m;
  m.utime = 0;
  m.scan_id = c.scan_id;
  m.iteration = c.iteration;
  m.request_id = c.request_id;
  m.status = c.ok ? point_cloud_t::kOk : point_cloud_t::kFailed;
  m.message = c.message;
  m.frame = "object";
  m.object_T_camera = to_msg(c.object_T_camera);
  m.num_joints = 6;
  m.joint_position_rad = to_std(c.joint_position_rad);
  m.turntable_angle_rad = c.turntable_angle_rad;
  m.depth_frame_seq = c.depth_frame_seq;
  m.depth_frame_utime = c.depth_frame_utime;
  m.num_valid_pixels = c.num_valid_pixels;
  m.num_cropped = c.num_cropped;
  m.voxel_m = c.voxel_m;
  m.capture_s = c.capture_s;
  m.process_s = c.process_s;
  m.num_points = static_cast<int32_t>(c.points.size());
  m.points_m.resize(c.points.size());
  for (std::size_t i = 0; i < c.points.size(); ++i) m.points_m[i] = {c.points[i].x(), c.points[i].y(), c.points[i].z()};
  return m;
}

inline CaptureResult from_msg(const point_cloud_t& m) {
  CaptureResult c;
  c.scan_id = m.scan_id;
  c.iteration = m.iteration;
  c.request_id = m.request_id;
  if (m.status != point_cloud_t::kOk && m.status != point_cloud_t::kFailed) {
    throw std::invalid_argument("CLOUD status = " + std::to_string(m.status) + " is neither kOk (0) nor kFailed (1)");
  }
  c.ok = m.status == point_cloud_t::kOk;
  c.message = m.message;
  c.object_T_camera = from_msg(m.object_T_camera, "CLOUD object_T_camera");
  c.joint_position_rad = to_vector6(m.joint_position_rad, "CLOUD joint_position_rad");
  c.turntable_angle_rad = m.turntable_angle_rad;
  c.depth_frame_seq = m.depth_frame_seq;
  c.depth_frame_utime = m.depth_frame_utime;
  c.num_valid_pixels = m.num_valid_pixels;
  c.num_cropped = m.num_cropped;
  c.voxel_m = m.voxel_m;
  c.capture_s = m.capture_s;
  c.process_s = m.process_s;
  c.points.reserve(m.points_m.size());
  for (std::size_t i = 0; i < m.points_m.size(); ++i) {
    const Eigen::Vector3f p(m.points_m[i][0], m.points_m[i][1], m.points_m[i][2]);
    if (!p.allFinite()) throw std::invalid_argument("CLOUD points_m[" + std::to_string(i) + "] is not finite");
    c.points.push_back(p);
  }
  return c;
}

}  // namespace pbnbv::bus
