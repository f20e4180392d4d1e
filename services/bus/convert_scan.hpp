#pragma once
// Conversions between the scan sequence's messages (MOVE_REQUEST, MOVE_RESULT, CAPTURE_REQUEST,
// CLOUD; the coordinator's REGISTERED_CLOUD, VOXEL_MAP, ELLIPSOIDS, PLAN_REQUEST, VIEW_PLAN,
// SCAN_STATUS) and the plain types of core/scan/messages.hpp, with the validation every receiver
// applies: each from_msg throws std::invalid_argument naming the message and the field.
// Array lengths need no check: lcm-gen's decoder sizes every array by its count field.
#include <Eigen/Geometry>
#include <algorithm>
#include <climits>
#include <string>
#include <vector>

#include "bus/convert.hpp"
#include "bus/convert_kinds.hpp"
#include "core/base/format.hpp"
#include "core/io/file_checks.hpp"
#include "core/scan/messages.hpp"
#include "pbnbv/capture_request_t.hpp"
#include "pbnbv/ellipsoid_set_t.hpp"
#include "pbnbv/mesh_request_t.hpp"
#include "pbnbv/mesh_result_t.hpp"
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
  move_request_t m{};
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
  m.turntable_choice = static_cast<int8_t>(r.turntable_choice);
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
  r.turntable_choice = turntable_choice_from_msg(m.turntable_choice, "MOVE_REQUEST turntable_choice");
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
  m.route = r.route;
  m.path_s = r.path_s;
  m.contacts = r.contacts;
  m.contact = r.contact;
  m.within_tolerance_utime = r.within_tolerance_utime;
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
  r.route = m.route;
  if (!(m.path_s >= 0 && m.path_s < 1e6)) {
    throw std::invalid_argument("MOVE_RESULT path_s = " + std::to_string(m.path_s) + " is not a time in [0, 1e6) s");
  }
  r.path_s = m.path_s;
  contacts_from_msg(m.contacts, m.contact, "MOVE_RESULT contacts", "MOVE_RESULT contact");
  r.contacts = m.contacts;
  r.contact = m.contact;
  r.within_tolerance_utime = m.within_tolerance_utime;
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
  point_cloud_t m{};
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
  m.ground_points = c.ground_points;
  m.ground_z_m = c.ground_z_m;
  for (int i = 0; i < 3; ++i) m.ground_abc[i] = c.ground_abc[i];
  m.ground_sigma_m = c.ground_sigma_m;
  m.num_points = static_cast<int32_t>(c.points.size());
  m.points_m.resize(c.points.size());
  for (std::size_t i = 0; i < c.points.size(); ++i) m.points_m[i] = {c.points[i].x(), c.points[i].y(), c.points[i].z()};
  m.num_normals = static_cast<int32_t>(c.normals.size());
  m.normals.resize(c.normals.size());
  for (std::size_t i = 0; i < c.normals.size(); ++i) m.normals[i] = {c.normals[i].x(), c.normals[i].y(), c.normals[i].z()};
  m.num_colours = static_cast<int32_t>(c.colours.size());
  m.colours.resize(c.colours.size());
  for (std::size_t i = 0; i < c.colours.size(); ++i) {
    m.colours[i] = {c.colours[i][0], c.colours[i][1], c.colours[i][2]};
  }
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
  // The turntable top's plane: used only with readings behind it, then finite, within the 5
  // degrees of tilt the camera service fits and a plausible height and scatter.
  if (m.ground_points < 0 || m.ground_points > m.num_valid_pixels) {
    throw std::invalid_argument("CLOUD ground_points = " + std::to_string(m.ground_points) + " is not in [0, num_valid_pixels = " +
                                std::to_string(m.num_valid_pixels) + "]");
  }
  if (m.ground_points > 0) {
    const Eigen::Vector3d abc(m.ground_abc[0], m.ground_abc[1], m.ground_abc[2]);
    if (!abc.allFinite() || std::hypot(abc.x(), abc.y()) > 0.1 || !(std::abs(m.ground_z_m) < 10) ||
        !(std::abs(abc.z() - m.ground_z_m) < 1) || !(m.ground_sigma_m >= 0 && m.ground_sigma_m < 1)) {
      throw std::invalid_argument("CLOUD ground plane (ground_abc, ground_z_m, ground_sigma_m) is not a turntable top: "
                                  "a slope over 0.1, a height 1 m off its place or more than 10 m out, or a scatter "
                                  "outside [0, 1) m");
    }
    c.ground_points = m.ground_points;
    c.ground_z_m = m.ground_z_m;
    c.ground_abc = abc;
    c.ground_sigma_m = m.ground_sigma_m;
  }
  c.points.reserve(m.points_m.size());
  for (std::size_t i = 0; i < m.points_m.size(); ++i) {
    const Eigen::Vector3f p(m.points_m[i][0], m.points_m[i][1], m.points_m[i][2]);
    if (!p.allFinite()) throw std::invalid_argument("CLOUD points_m[" + std::to_string(i) + "] is not finite");
    c.points.push_back(p);
  }
  // Normals: none, or one per point, each a unit vector or zero (none found there).
  if (!m.normals.empty() && m.normals.size() != m.points_m.size()) {
    throw std::invalid_argument("CLOUD num_normals = " + std::to_string(m.normals.size()) + ": neither 0 nor num_points (" +
                                std::to_string(m.points_m.size()) + ")");
  }
  c.normals.reserve(m.normals.size());
  for (std::size_t i = 0; i < m.normals.size(); ++i) {
    const Eigen::Vector3f n(m.normals[i][0], m.normals[i][1], m.normals[i][2]);
    const float norm = n.norm();
    if (!(norm == 0.0f || std::abs(norm - 1.0f) < 1e-3f)) {
      throw std::invalid_argument("CLOUD normals[" + std::to_string(i) + "] is neither a unit vector nor zero (length " +
                                  std::to_string(norm) + ")");
    }
    c.normals.push_back(n);
  }
  // Colours: none, or one per point.
  if (!m.colours.empty() && m.colours.size() != m.points_m.size()) {
    throw std::invalid_argument("CLOUD num_colours = " + std::to_string(m.colours.size()) + ": neither 0 nor num_points (" +
                                std::to_string(m.points_m.size()) + ")");
  }
  c.colours.reserve(m.colours.size());
  for (const auto& rgb : m.colours) {
    c.colours.push_back({rgb[0], rgb[1], rgb[2]});
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
  r.flagged = m.flagged;
  r.reason = m.reason;
  r.constraint = m.constraint;
  r.correction = from_msg(m.correction, "REGISTERED_CLOUD correction");
  r.translation_m = m.translation_m;
  r.rotation_deg = m.rotation_deg;
  r.overlap = m.overlap;
  r.rmse_m = m.rmse_m;
  r.icp_translation_m = m.icp_translation_m;
  r.icp_rotation_deg = m.icp_rotation_deg;
  r.prior_sigmas = m.prior_sigmas;
  r.iterations = m.iterations;
  r.model_points = m.model_points;
  r.register_s = m.register_s;
  // The files it names are the view's own in the scan's folder, or none: a reader of scan.json
  // opens them, so no other path is taken from the wire.
  const std::string frame = frame_file_of(m.iteration);
  if (!m.frame_file.empty() && m.frame_file != frame) {
    throw std::invalid_argument("REGISTERED_CLOUD frame_file '" + shown(m.frame_file) + "' is neither '' nor '" + frame + "'");
  }
  const std::string depth = depth_file_of(m.iteration);
  if (!m.depth_file.empty() && m.depth_file != depth) {
    throw std::invalid_argument("REGISTERED_CLOUD depth_file '" + shown(m.depth_file) + "' is neither '' nor '" + depth + "'");
  }
  r.frame_file = m.frame_file;
  r.depth_file = m.depth_file;
  if (m.normals != registered_cloud_t::kNormalsDepthImage && m.normals != registered_cloud_t::kNormalsNeighbours) {
    throw std::invalid_argument("REGISTERED_CLOUD normals = " + std::to_string(m.normals) +
                                " is neither kNormalsDepthImage (0) nor kNormalsNeighbours (1)");
  }
  r.normals_from_depth = m.normals == registered_cloud_t::kNormalsDepthImage;
  if (m.new_points >= 0) {
    if (m.frame_points < m.new_points || m.model_points_before < 0) {
      throw std::invalid_argument("REGISTERED_CLOUD new surface: new_points " + std::to_string(m.new_points) + ", frame_points " +
                                  std::to_string(m.frame_points) + ", model_points_before " +
                                  std::to_string(m.model_points_before) + " (need 0 <= new <= frame, model >= 0)");
    }
    require_range(m.new_surface_radius_m, 1e-6, 1.0, "REGISTERED_CLOUD new_surface_radius_m");
    r.new_surface = NewSurface{m.frame_points, m.new_points, m.model_points_before, m.new_surface_radius_m};
  } else if (m.new_points != -1) {
    throw std::invalid_argument("REGISTERED_CLOUD new_points = " + std::to_string(m.new_points) + ": -1 (not merged) or a count");
  }
  require_range(m.accumulate_s, 0.0, 3600.0, "REGISTERED_CLOUD accumulate_s");
  r.accumulate_s = m.accumulate_s;
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
  plan_request_t m{};
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
  m.turntable_choice = static_cast<int8_t>(r.turntable_choice);
  m.seconds_per_point = r.seconds_per_point;
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

// ---- The scan's mesh -------------------------------------------------------------------------

inline mesh_request_t to_msg(const MeshRequest& r) {
  mesh_request_t m;
  m.utime = 0;
  m.scan_id = r.scan_id;
  m.request_id = r.request_id;
  m.num_views = static_cast<int32_t>(r.views.size());
  // The message counts views from 1 (as scan.json and the files: view 1's frame is view_001.ply);
  // MeshRequest keeps them 0-based.
  for (const int v : r.views) m.views.push_back(v + 1);
  m.width = r.camera.width;
  m.height = r.camera.height;
  m.fx = r.camera.fx;
  m.fy = r.camera.fy;
  m.cx = r.camera.cx;
  m.cy = r.camera.cy;
  m.point_spacing_m = r.point_spacing_m;
  return m;
}

// The message's views (counted from 1) 0-based in the MeshRequest. Throws naming the field when a
// view is outside 1..max_views or out of order, the camera is not one, or the spacing is outside
// [0, 0.05] m.
inline MeshRequest from_msg(const mesh_request_t& m, int max_views) {
  MeshRequest r;
  r.scan_id = m.scan_id;
  r.request_id = m.request_id;
  if (m.views.empty() || static_cast<int>(m.views.size()) > max_views) {
    throw std::invalid_argument("MESH_REQUEST num_views = " + std::to_string(m.views.size()) + " is outside 1.." +
                                std::to_string(max_views));
  }
  for (std::size_t i = 0; i < m.views.size(); ++i) {
    if (m.views[i] < 1 || m.views[i] > max_views || (i > 0 && m.views[i] <= m.views[i - 1])) {
      throw std::invalid_argument("MESH_REQUEST views[" + std::to_string(i) + "] = " + std::to_string(m.views[i]) +
                                  ": the views are 1.." + std::to_string(max_views) + ", ascending");
    }
    r.views.push_back(m.views[i] - 1);
  }
  r.camera = CameraIntrinsics{m.width, m.height, m.fx, m.fy, m.cx, m.cy};
  try {
    r.camera.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("MESH_REQUEST camera: ") + e.what());
  }
  require_range(m.point_spacing_m, 0.0, 0.05, "MESH_REQUEST point_spacing_m");
  r.point_spacing_m = m.point_spacing_m;
  return r;
}

inline mesh_result_t to_msg(const MeshResult& r) {
  const MeshSummary& s = r.mesh;
  auto count = [](std::size_t n) { return static_cast<int32_t>(std::min<std::size_t>(n, INT32_MAX)); };
  mesh_result_t m;
  m.utime = 0;
  m.scan_id = r.scan_id;
  m.request_id = r.request_id;
  m.status = r.ok ? mesh_result_t::kOk : mesh_result_t::kFailed;
  m.message = r.message;
  m.method = s.tsdf ? mesh_result_t::kTsdf : mesh_result_t::kPoisson;
  m.with_stl = s.files.size() > 2;
  m.frames = count(s.frames);
  m.points = count(s.points);
  m.vertices = count(s.vertices);
  m.triangles = count(s.triangles);
  m.watertight = s.watertight;
  m.boundary_loops = count(s.boundary_loops);
  m.boundary_edges = count(s.boundary_edges);
  m.non_manifold_edges = count(s.non_manifold_edges);
  m.hole_boundary_length_m = s.hole_boundary_length_m;
  m.area_m2 = s.area_m2;
  m.volume_m3 = s.volume_m3.value_or(0.0);
  m.small_fragments_removed_triangles = count(s.small_fragments_removed_triangles);
  m.holes_filled = count(s.holes_filled);
  m.fill_holes_m = s.fill_holes_m;
  m.seconds = s.seconds;
  m.voxel_m = s.voxel_m;
  m.truncation_m = s.truncation_m;
  m.image_scale = s.image_scale;
  m.voxels = static_cast<int64_t>(s.voxels);
  m.poisson_depth = s.poisson_depth;
  return m;
}

// Throws naming the field when the status or method is not one of its constants, a count is
// negative, or a figure is not finite or out of its range.
inline MeshResult from_msg(const mesh_result_t& m) {
  MeshResult r;
  r.scan_id = m.scan_id;
  r.request_id = m.request_id;
  if (m.status != mesh_result_t::kOk && m.status != mesh_result_t::kFailed) {
    throw std::invalid_argument("MESH_RESULT status = " + std::to_string(m.status) + " is neither kOk (0) nor kFailed (1)");
  }
  r.ok = m.status == mesh_result_t::kOk;
  r.message = m.message;
  if (!r.ok) return r;
  if (m.method != mesh_result_t::kTsdf && m.method != mesh_result_t::kPoisson) {
    throw std::invalid_argument("MESH_RESULT method = " + std::to_string(m.method) + " is neither kTsdf (0) nor kPoisson (1)");
  }
  auto count = [](int64_t n, const char* what) {
    if (n < 0) throw std::invalid_argument(std::string("MESH_RESULT ") + what + " = " + std::to_string(n) + " is negative");
    return static_cast<std::size_t>(n);
  };
  MeshSummary& s = r.mesh;
  s.tsdf = m.method == mesh_result_t::kTsdf;
  s.files = {"mesh.ply", "mesh.obj"};
  if (m.with_stl) s.files.push_back("mesh.stl");
  s.frames = count(m.frames, "frames");
  s.points = count(m.points, "points");
  s.vertices = count(m.vertices, "vertices");
  s.triangles = count(m.triangles, "triangles");
  s.watertight = m.watertight;
  s.boundary_loops = count(m.boundary_loops, "boundary_loops");
  s.boundary_edges = count(m.boundary_edges, "boundary_edges");
  s.non_manifold_edges = count(m.non_manifold_edges, "non_manifold_edges");
  require_range(m.hole_boundary_length_m, 0.0, 1e3, "MESH_RESULT hole_boundary_length_m");
  s.hole_boundary_length_m = m.hole_boundary_length_m;
  require_range(m.area_m2, 0.0, 1e3, "MESH_RESULT area_m2");
  s.area_m2 = m.area_m2;
  if (m.watertight) {
    require_range(m.volume_m3, -1e3, 1e3, "MESH_RESULT volume_m3");
    s.volume_m3 = m.volume_m3;
  }
  s.small_fragments_removed_triangles = count(m.small_fragments_removed_triangles, "small_fragments_removed_triangles");
  s.holes_filled = count(m.holes_filled, "holes_filled");
  require_range(m.fill_holes_m, 0.0, 10.0, "MESH_RESULT fill_holes_m");
  s.fill_holes_m = m.fill_holes_m;
  require_range(m.seconds, 0.0, 1e6, "MESH_RESULT seconds");
  s.seconds = m.seconds;
  if (s.tsdf) {
    require_range(m.voxel_m, 0.0, 1.0, "MESH_RESULT voxel_m");
    require_range(m.truncation_m, 0.0, 10.0, "MESH_RESULT truncation_m");
    s.voxel_m = m.voxel_m;
    s.truncation_m = m.truncation_m;
    if (m.image_scale < 1) throw std::invalid_argument("MESH_RESULT image_scale = " + std::to_string(m.image_scale) + " is below 1");
    s.image_scale = m.image_scale;
    s.voxels = count(m.voxels, "voxels");
  } else {
    if (m.poisson_depth < 1 || m.poisson_depth > 16) {
      throw std::invalid_argument("MESH_RESULT poisson_depth = " + std::to_string(m.poisson_depth) + " is outside 1..16");
    }
    s.poisson_depth = m.poisson_depth;
  }
  return r;
}

}  // namespace pbnbv::bus
