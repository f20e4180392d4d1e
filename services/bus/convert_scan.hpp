#pragma once
// Conversions between the scan sequence's messages (MOVE_REQUEST, MOVE_RESULT, CAPTURE_REQUEST,
// CLOUD; the coordinator's REGISTERED_CLOUD, VOXEL_MAP, ELLIPSOIDS, PLAN_REQUEST, VIEW_PLAN,
// SCAN_STATUS) and the plain types of core/scan/messages.hpp, with the validation every receiver
// applies: each from_msg throws std::invalid_argument naming the message and the field.
// Array lengths need no check: lcm-gen's decoder sizes every array by its count field.
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "bus/convert.hpp"
#include "bus/convert_kinds.hpp"
#include "core/scan/messages.hpp"
#include "pbnbv/capture_request_t.hpp"
#include "pbnbv/ellipsoid_set_t.hpp"
#include "pbnbv/move_request_t.hpp"
#include "pbnbv/move_result_t.hpp"
#include "pbnbv/plan_request_t.hpp"
#include "pbnbv/point_cloud_t.hpp"
#include "pbnbv/registered_cloud_t.hpp"
#include "pbnbv/scan_status_t.hpp"
#include "pbnbv/view_plan_t.hpp"
#include "pbnbv/voxel_set_t.hpp"

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
  if (m.status < move_result_t::kReached || m.status > move_result_t::kRigSilent) {
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

// ---- The coordinator's other messages -------------------------------------------------------

// A REGISTERED_CLOUD as the coordinator takes it; its cloud is checked as a CLOUD is, and an
// error names both ("REGISTERED_CLOUD cloud: CLOUD points_m[3] is not finite").
inline RegisteredCloud from_msg(const registered_cloud_t& m) {
  RegisteredCloud r;
  r.scan_id = m.scan_id;
  r.iteration = m.iteration;
  r.request_id = m.request_id;
  try {
    r.cloud = from_msg(m.cloud);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("REGISTERED_CLOUD cloud: ") + e.what());
  }
  r.kinematic_object_T_camera = from_msg(m.kinematic_object_T_camera, "REGISTERED_CLOUD kinematic_object_T_camera");
  r.accepted = m.accepted;
  r.refined = m.refined;
  r.reason = m.reason;
  r.constraint = m.constraint;
  r.correction = from_msg(m.correction, "REGISTERED_CLOUD correction");
  r.translation_m = m.translation_m;
  r.rotation_deg = m.rotation_deg;
  r.overlap = m.overlap;
  r.rmse_m = m.rmse_m;
  r.iterations = m.iterations;
  r.model_points = m.model_points;
  r.register_s = m.register_s;
  return r;
}

// A VOXEL_MAP as the coordinator records it: the counts and box, not the voxels. Throws naming
// the field when a count is negative or a box corner is not finite.
inline VoxelMapSummary from_msg(const voxel_set_t& m) {
  VoxelMapSummary v;
  v.scan_id = m.scan_id;
  v.iteration = m.iteration;
  v.request_id = m.request_id;
  v.updated = m.updated;
  v.message = m.message;
  v.resolution_m = m.resolution_m;
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(m.bbox_min_m[k]) || !std::isfinite(m.bbox_max_m[k])) {
      throw std::invalid_argument("VOXEL_MAP bbox corner " + std::to_string(k) + " is not finite");
    }
    v.bbox_min_m[k] = m.bbox_min_m[k];
    v.bbox_max_m[k] = m.bbox_max_m[k];
  }
  const std::pair<const char*, int32_t> counts[] = {{"num_none", m.num_none},         {"num_empty", m.num_empty},
                                                    {"num_occupied", m.num_occupied}, {"num_unknown", m.num_unknown},
                                                    {"num_frontier", m.num_frontier}};
  for (const auto& [name, n] : counts) {
    if (n < 0) throw std::invalid_argument(std::string("VOXEL_MAP ") + name + " = " + std::to_string(n) + " is negative");
  }
  v.num_none = m.num_none;
  v.num_empty = m.num_empty;
  v.num_occupied = m.num_occupied;
  v.num_unknown = m.num_unknown;
  v.num_frontier = m.num_frontier;
  v.update_s = m.update_s;
  return v;
}

// An ELLIPSOIDS message as the coordinator records it. Throws naming the ellipsoid whose class
// is neither kOccupied nor kFrontier.
inline EllipsoidSetSummary from_msg(const ellipsoid_set_t& m) {
  EllipsoidSetSummary s;
  s.scan_id = m.scan_id;
  s.iteration = m.iteration;
  s.request_id = m.request_id;
  s.occupied_components = m.occupied_components;
  s.frontier_components = m.frontier_components;
  s.fit_s = m.fit_s;
  s.ellipsoids.reserve(m.ellipsoids.size());
  for (std::size_t i = 0; i < m.ellipsoids.size(); ++i) {
    const ellipsoid_t& e = m.ellipsoids[i];
    if (e.cls != ellipsoid_t::kOccupied && e.cls != ellipsoid_t::kFrontier) {
      throw std::invalid_argument("ELLIPSOIDS ellipsoids[" + std::to_string(i) + "].cls = " + std::to_string(e.cls) +
                                  " is neither kOccupied (0) nor kFrontier (1)");
    }
    EllipsoidSummary o;
    o.frontier = e.cls == ellipsoid_t::kFrontier;
    for (int k = 0; k < 3; ++k) {
      o.centre_m[k] = e.centre_m[k];
      o.semi_axes_m[k] = e.semi_axes_m[k];
    }
    for (int k = 0; k < 4; ++k) o.quat_wxyz[k] = e.quat_wxyz[k];
    o.num_voxels = e.num_voxels;
    s.ellipsoids.push_back(o);
  }
  return s;
}

inline plan_request_t to_msg(const PlanRequest& r) {
  plan_request_t m;
  m.utime = 0;
  m.scan_id = r.scan_id;
  m.iteration = r.iteration;
  m.request_id = r.request_id;
  m.planner = planner_to_msg(r.planner);
  m.seed = r.seed;
  m.map_iteration = r.map_iteration;
  m.map_request_id = r.map_request_id;
  for (const Pose& v : r.views_done) m.views_done.push_back(to_msg(v));
  m.num_views_done = static_cast<int32_t>(m.views_done.size());
  for (const Pose& v : r.excluded) m.excluded.push_back(to_msg(v));
  m.num_excluded = static_cast<int32_t>(m.excluded.size());
  m.num_candidates = r.num_candidates;
  m.num_parallels = r.num_parallels;
  m.num_sectors = r.num_sectors;
  m.full_sphere = r.area == CandidateArea::kFullSphere;
  m.working_distance_m = r.working_distance_m;
  m.num_alternatives = r.num_alternatives;
  m.stop_fraction = r.stop_fraction;
  m.spread_when_done = r.when_done == WhenDone::kSpread;
  m.first_quality = r.first_quality;
  m.depth_min_m = r.depth_range.min_m;
  m.depth_max_m = r.depth_range.max_m;
  m.width_px = r.camera.width;
  m.height_px = r.camera.height;
  m.fx = r.camera.fx;
  m.fy = r.camera.fy;
  m.cx = r.camera.cx;
  m.cy = r.camera.cy;
  m.check_reachability = r.check_reachability;
  for (int k = 0; k < 6; ++k) m.joint_position_rad[k] = r.joint_position_rad[k];
  m.turntable_angle_rad = r.turntable_angle_rad;
  m.object_z_m = r.object_z_m;
  box_to_arrays(r.keepout, m.keepout_min_m, m.keepout_max_m);
  return m;
}

// A VIEW_PLAN as the coordinator takes it. Throws naming the field for an outcome outside its
// constants, and (outcome kView) for a chosen or alternative pose that is not a pose.
inline ViewPlan from_msg(const view_plan_t& m) {
  ViewPlan p;
  p.scan_id = m.scan_id;
  p.iteration = m.iteration;
  p.request_id = m.request_id;
  p.planner = planner_from_msg(m.planner, "VIEW_PLAN planner");
  if (m.outcome < view_plan_t::kView || m.outcome > view_plan_t::kFailed) {
    throw std::invalid_argument("VIEW_PLAN outcome = " + std::to_string(m.outcome) + " is not one of its constants (0..2)");
  }
  p.outcome = static_cast<PlanOutcome>(m.outcome);
  p.reason = m.reason;
  p.ranking = ranking_from_msg(m.ranking, "VIEW_PLAN ranking");
  if (p.outcome == PlanOutcome::kView) {  // the poses of a stop or a failure are not filled
    p.object_T_camera = from_msg(m.object_T_camera, "VIEW_PLAN object_T_camera");
    for (std::size_t a = 0; a < m.alternatives.size(); ++a) {
      p.alternatives.push_back(from_msg(m.alternatives[a], "VIEW_PLAN alternatives[" + std::to_string(a) + "]"));
    }
  }
  p.view_quality = m.view_quality;
  p.first_quality = m.first_quality;
  p.frontier_area_px = m.frontier_area_px;
  p.occupied_area_px = m.occupied_area_px;
  p.partition = m.partition;
  p.allowed_sectors.assign(m.allowed_sectors.begin(), m.allowed_sectors.end());
  p.partition_fallback = m.partition_fallback;
  p.sphere_centre_m = Eigen::Vector3d(m.sphere_centre_m[0], m.sphere_centre_m[1], m.sphere_centre_m[2]);
  p.sphere_radius_m = m.sphere_radius_m;
  p.num_candidates = m.num_candidates;
  p.num_unreachable = m.num_unreachable;
  p.num_excluded = m.num_excluded;
  p.num_scored = m.num_scored;
  p.num_frontier_ellipsoids = m.num_frontier_ellipsoids;
  p.num_occupied_ellipsoids = m.num_occupied_ellipsoids;
  p.candidates_s = m.candidates_s;
  p.reachability_s = m.reachability_s;
  p.scoring_s = m.scoring_s;
  p.wait_s = m.wait_s;
  p.plan_s = m.plan_s;
  p.alternative_quality = m.alternative_quality;
  return p;
}

inline scan_status_t to_msg(const ScanStatus& s) {
  scan_status_t m;
  m.utime = 0;
  m.scan_id = s.scan_id;
  m.iteration = s.iteration;
  m.num_views_planned = s.num_views_planned;
  m.num_views_done = s.num_views_done;
  m.state = static_cast<int8_t>(s.state);
  m.message = s.message;
  m.elapsed_s = s.elapsed_s;
  m.num_points = s.num_points;
  return m;
}

}  // namespace pbnbv::bus
