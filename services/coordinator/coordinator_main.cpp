// pbnbv-coordinator: the scan coordinator.
//   in:  MOVE_RESULT, CLOUD, REGISTERED_CLOUD, VOXEL_MAP, ELLIPSOIDS, VIEW_PLAN, ARM_STATUS,
//        TURNTABLE_STATUS, HEARTBEAT
//   out: MOVE_REQUEST, CAPTURE_REQUEST, PLAN_REQUEST, SCAN_STATUS, HEARTBEAT
// Runs plan -> move -> settle -> capture -> register -> map -> accumulate for each view: the
// next view comes from the view scorer (planner "pbnbv": PLAN_REQUEST / VIEW_PLAN, with the
// scan's history in the request) or from a fixed ring (planner "ring"). A view the rig cannot
// reach is replaced by the plan's next-best alternatives. Writes the scan's output folder after
// every view (cloud.ply, frames/, plans/, scan.json), says in scan.json why the scan stopped,
// and prints progress.
// Every wait has a deadline; requests are re-sent (idempotent by request_id) when an answer
// is lost.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "bus/bus.hpp"
#include "bus/convert.hpp"
#include "cli/options.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/base/log.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "core/perception/cloud_filter.hpp"
#include "core/scan/scan_settings.hpp"
#include "core/geometry/views.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/capture_request_t.hpp"
#include "pbnbv/ellipsoid_set_t.hpp"
#include "pbnbv/plan_request_t.hpp"
#include "pbnbv/view_plan_t.hpp"
#include "pbnbv/heartbeat_t.hpp"
#include "pbnbv/move_request_t.hpp"
#include "pbnbv/move_result_t.hpp"
#include "pbnbv/point_cloud_t.hpp"
#include "pbnbv/registered_cloud_t.hpp"
#include "pbnbv/voxel_set_t.hpp"
#include "pbnbv/scan_status_t.hpp"
#include "pbnbv/turntable_status_t.hpp"
#include "core/base/format.hpp"
#include "core/base/units.hpp"

using namespace pbnbv;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kResendS = 3.0;          // re-send a request whose answer has not come
constexpr double kAnswerTimeoutS = 60.0;  // registration / mapping answer to a view
constexpr double kPlanTimeoutS = 90.0;    // view scorer's answer (it waits up to 60 s for inputs)

std::string move_status_name(int8_t s) {
  switch (s) {
    case move_result_t::kReached: return "reached";
    case move_result_t::kUnreachable: return "unreachable";
    case move_result_t::kTimedOut: return "timed_out";
    case move_result_t::kRejected: return "rejected";
    case move_result_t::kPlanned: return "planned";
    case move_result_t::kBusy: return "busy";
  }
  return "unknown";
}

json pose_json(const pose_t& p) {
  return {{"position_m", {p.position_m[0], p.position_m[1], p.position_m[2]}},
          {"quat_wxyz", {p.quat_wxyz[0], p.quat_wxyz[1], p.quat_wxyz[2], p.quat_wxyz[3]}}};
}

class Coordinator {
 public:
  Coordinator(bus::Bus& bus, ScanSettings settings, fs::path out)
      : bus_(bus), s_(std::move(settings)), out_(std::move(out)) {
    bus_.subscribe<move_result_t>(channels::kMoveResult, [this](const move_result_t& r) {
      if (r.scan_id == s_.scan_id) move_results_[r.request_id] = r;
    });
    bus_.subscribe<point_cloud_t>(channels::kCloud, [this](const point_cloud_t& c) {
      if (c.scan_id != s_.scan_id) return;
      if (c.num_points != static_cast<int32_t>(c.points_m.size())) {
        throw std::invalid_argument("CLOUD num_points disagrees with its array");
      }
      clouds_[c.request_id] = c;
    });
    bus_.subscribe<registered_cloud_t>(channels::kRegisteredCloud, [this](const registered_cloud_t& r) {
      if (r.scan_id != s_.scan_id) return;
      if (r.cloud.num_points != static_cast<int32_t>(r.cloud.points_m.size())) {
        throw std::invalid_argument("REGISTERED_CLOUD cloud.num_points disagrees with its array");
      }
      registered_[r.request_id] = r;
    });
    bus_.subscribe<voxel_set_t>(channels::kVoxelMap, [this](const voxel_set_t& m) {
      if (m.scan_id == s_.scan_id) maps_[m.iteration] = m;
    });
    bus_.subscribe<ellipsoid_set_t>(channels::kEllipsoids, [this](const ellipsoid_set_t& e) {
      if (e.scan_id != s_.scan_id) return;
      if (e.num_ellipsoids != static_cast<int32_t>(e.ellipsoids.size())) {
        throw std::invalid_argument("ELLIPSOIDS num_ellipsoids disagrees with its array");
      }
      ellipsoids_[e.iteration] = e;
    });
    bus_.subscribe<view_plan_t>(channels::kViewPlan, [this](const view_plan_t& p) {
      if (p.scan_id != s_.scan_id) return;
      if (p.num_alternatives != static_cast<int32_t>(p.alternatives.size()) ||
          p.num_alternatives != static_cast<int32_t>(p.alternative_quality.size())) {
        throw std::invalid_argument("VIEW_PLAN num_alternatives disagrees with its arrays");
      }
      if (p.outcome == view_plan_t::kView) bus::from_msg(p.object_T_camera, "VIEW_PLAN object_T_camera");
      plans_[p.request_id] = p;
    });
    bus_.subscribe<arm_status_t>(channels::kArmStatus, [this](const arm_status_t&) { seen_.insert("ARM_STATUS"); });
    bus_.subscribe<turntable_status_t>(channels::kTurntableStatus, [this](const turntable_status_t&) { seen_.insert("TURNTABLE_STATUS"); });
    bus_.subscribe<heartbeat_t>(channels::kHeartbeat, [this](const heartbeat_t& h) { seen_.insert("heartbeat of " + h.service); });
  }

  // Returns the process exit code.
  int run() {
    t_start_ = bus::now_s();
    fs::create_directories(out_ / "frames");
    report_.clear();
    report_["settings"] = to_json(s_);
    report_["views"] = json::array();
    plan_views();
    status(scan_status_t::kStarting, "waiting for the rig and services");
    if (!wait_ready()) return finish(scan_status_t::kFailed, startup_problem_);

    for (int i = 0; i < s_.views; ++i) {
      if (stop_requested()) return finish(scan_status_t::kStopped, "interrupted");
      iteration_ = i;
      json view = {{"view", i}};
      const double t_view = bus::now_s();

      // Where to go: the ring's view, the first view, or the view scorer's plan and its
      // alternatives.
      std::vector<Pose> options;
      if (s_.planner == PlannerKind::kRing) {
        options = {views_[i]};
      } else if (i == 0) {
        options = {first_view_};
        view["plan"] = {{"planner", "initial view"}};
      } else {
        progress("planning");
        status(scan_status_t::kPlanning, "planning view " + std::to_string(i + 1));
        std::optional<view_plan_t> plan = request_plan(i);
        if (!plan) {
          if (stop_requested()) return finish(scan_status_t::kStopped, "interrupted");
          return finish(scan_status_t::kFailed, "the view scorer did not answer the plan for view " + std::to_string(i + 1));
        }
        view["plan"] = plan_json(*plan);
        if (plan->outcome != view_plan_t::kView) {
          stop_ = {{"reason", plan->reason}, {"after_views", views_done_},
                   {"rule", plan->outcome == view_plan_t::kStop ? "planner" : "planner failed"}};
          report_["planning_stopped"] = view["plan"];
          if (plan->outcome == view_plan_t::kStop) return finish(scan_status_t::kDone, "scan complete: " + plan->reason);
          return finish(scan_status_t::kFailed, "no plan for view " + std::to_string(i + 1) + ": " + plan->reason);
        }
        if (!std::isfinite(first_quality_)) first_quality_ = plan->first_quality;
        options.push_back(bus::from_msg(plan->object_T_camera, "VIEW_PLAN object_T_camera"));
        for (std::size_t a = 0; a < plan->alternatives.size(); ++a) {
          options.push_back(bus::from_msg(plan->alternatives[a], "VIEW_PLAN alternatives"));
        }
        progress("planned: " + std::string(s_.planner == PlannerKind::kPbnbv ? "F " + fixed(plan->view_quality, 2) + " px, "
                                           : s_.planner == PlannerKind::kRaycast ? "gain " + fixed(plan->view_quality, 2) + " voxels, " : "") +
                 std::to_string(plan->num_scored) + " candidates scored");
      }

      // Move, trying the alternatives when the rig cannot reach a view.
      progress("moving");
      status(scan_status_t::kMoving, "moving to view " + std::to_string(i + 1));
      const double t_move = bus::now_s();
      std::optional<move_result_t> moved;
      json attempts = json::array();
      for (std::size_t k = 0; k < options.size(); ++k) {
        moved = move(i, static_cast<int>(k), options[k]);
        if (!moved) break;
        if (moved->status == move_result_t::kReached) {
          view["requested_object_T_camera"] = to_json(options[k]);
          view["option"] = k;
          break;
        }
        attempts.push_back({{"option", k}, {"status", move_status_name(moved->status)}, {"reason", moved->reason}});
        excluded_.push_back(options[k]);
        if (moved->status != move_result_t::kUnreachable) break;
      }
      if (!attempts.empty()) view["failed_moves"] = attempts;
      if (!moved) {
        if (stop_requested()) return finish(scan_status_t::kStopped, "interrupted");
        view["move"] = {{"status", "no_answer"}, {"reason", "no MOVE_RESULT from the motion executor"}};
        record(view);
        return finish(scan_status_t::kFailed, "the motion executor did not answer the move to view " + std::to_string(i + 1));
      }
      view["move"] = {{"status", move_status_name(moved->status)}, {"reason", moved->reason},
                      {"reached_object_T_camera", pose_json(moved->reached_object_T_camera)},
                      {"position_error_m", moved->position_error_m},
                      {"angle_error_deg", moved->angle_error_rad * 180 / kPi},
                      {"joint_target_rad", moved->joint_target_rad},
                      {"joint_position_rad", moved->joint_position_rad},
                      {"turntable_target_rad", moved->turntable_target_rad},
                      {"turntable_angle_rad", moved->turntable_angle_rad}};
      view["time_s"] = {{"plan", moved->plan_s}, {"move", moved->move_s}, {"settle", moved->settle_s},
                        {"rig_motion", moved->rig_motion_s}, {"move_round_trip", bus::now_s() - t_move}};
      if (moved->status != move_result_t::kReached) {
        progress(move_status_name(moved->status) + ": " + moved->reason, true);
        record(view);
        continue;
      }
      if (moved->joint_position_rad.size() == 6) {
        for (int k = 0; k < 6; ++k) joints_[k] = moved->joint_position_rad[k];
      }
      turntable_ = moved->turntable_angle_rad;
      progress("capturing");
      status(scan_status_t::kCapturing, "capturing view " + std::to_string(i + 1));
      const double t_capture = bus::now_s();
      std::optional<point_cloud_t> cloud = capture(i, moved->settled_utime);
      if (!cloud) {
        if (stop_requested()) return finish(scan_status_t::kStopped, "interrupted");
        view["capture"] = {{"status", "no_answer"}};
        record(view);
        return finish(scan_status_t::kFailed, "the camera service did not answer the capture of view " + std::to_string(i + 1));
      }
      view["time_s"]["capture"] = cloud->capture_s;
      view["time_s"]["cloud"] = cloud->process_s;
      view["time_s"]["capture_round_trip"] = bus::now_s() - t_capture;
      view["capture"] = {{"status", cloud->status == point_cloud_t::kOk ? "ok" : "failed"},
                         {"message", cloud->message},
                         {"camera_object_T_camera", pose_json(cloud->object_T_camera)},
                         {"joint_position_rad", cloud->joint_position_rad},
                         {"turntable_angle_rad", cloud->turntable_angle_rad},
                         {"depth_frame_seq", cloud->depth_frame_seq},
                         {"num_valid_pixels", cloud->num_valid_pixels},
                         {"num_cropped", cloud->num_cropped},
                         {"num_points", cloud->num_points}};
      if (cloud->status != point_cloud_t::kOk) {
        progress("capture failed: " + cloud->message, true);
        excluded_.push_back(bus::from_msg(moved->reached_object_T_camera, "MOVE_RESULT reached_object_T_camera"));
        record(view);
        continue;
      }
      status(scan_status_t::kIntegrating, "registering and mapping view " + std::to_string(i + 1));
      progress("registering");
      const double t_reg = bus::now_s();
      if (!spin_until([&] { return registered_.count(i) > 0; }, kAnswerTimeoutS)) {
        if (stop_requested()) return finish(scan_status_t::kStopped, "interrupted");
        record(view);
        return finish(scan_status_t::kFailed, "the registration service did not answer view " + std::to_string(i + 1));
      }
      const registered_cloud_t reg = registered_[i];  // a copy: accumulate() drops the stored one
      view["registration"] = {{"accepted", reg.accepted != 0}, {"refined", reg.refined != 0},
                              {"constraint", reg.constraint}, {"reason", reg.reason},
                              {"correction", pose_json(reg.correction)},
                              {"translation_mm", reg.translation_m * 1e3}, {"rotation_deg", reg.rotation_deg},
                              {"overlap", reg.overlap}, {"rmse_mm", reg.rmse_m * 1e3}, {"iterations", reg.iterations},
                              {"registered_object_T_camera", pose_json(reg.cloud.object_T_camera)},
                              {"kinematic_object_T_camera", pose_json(reg.kinematic_object_T_camera)}};
      view["time_s"]["register"] = reg.register_s;
      view["time_s"]["register_round_trip"] = bus::now_s() - t_reg;
      progress("mapping");
      const double t_map = bus::now_s();
      if (!spin_until([&] { return maps_.count(i) > 0; }, kAnswerTimeoutS)) {
        if (stop_requested()) return finish(scan_status_t::kStopped, "interrupted");
        record(view);
        return finish(scan_status_t::kFailed, "the mapping service did not answer view " + std::to_string(i + 1));
      }
      const voxel_set_t& map = maps_[i];
      latest_map_ = i;
      view["map"] = {{"updated", map.updated != 0}, {"message", map.message}, {"resolution_m", map.resolution_m},
                     {"bbox_min_m", {map.bbox_min_m[0], map.bbox_min_m[1], map.bbox_min_m[2]}},
                     {"bbox_max_m", {map.bbox_max_m[0], map.bbox_max_m[1], map.bbox_max_m[2]}},
                     {"voxels", {{"none", map.num_none}, {"empty", map.num_empty}, {"occupied", map.num_occupied},
                                 {"unknown", map.num_unknown}, {"frontier", map.num_frontier}}}};
      view["time_s"]["map_update"] = map.update_s;
      view["time_s"]["map_round_trip"] = bus::now_s() - t_map;
      if (map.updated) {
        last_map_ = i;
        views_taken_.push_back(bus::from_msg(reg.cloud.object_T_camera, "REGISTERED_CLOUD cloud.object_T_camera"));
      } else {  // not mapped (e.g. registration rejected it): do not plan it again
        excluded_.push_back(bus::from_msg(moved->reached_object_T_camera, "MOVE_RESULT reached_object_T_camera"));
      }
      status(scan_status_t::kIntegrating, "adding view " + std::to_string(i + 1));
      const double t_acc = bus::now_s();
      accumulate(i, reg, view);
      view["time_s"]["accumulate"] = bus::now_s() - t_acc;
      view["time_s"]["view_total"] = bus::now_s() - t_view;
      ++views_done_;
      record(view);
      std::ostringstream os;
      os << "done: " << cloud->num_points << " points, " << accumulated_.size() << " in the model; "
         << (!reg.accepted ? std::string("registration rejected")
             : reg.refined ? "registered (" + fixed(reg.translation_m * 1e3, 2) + " mm, " + fixed(reg.rotation_deg, 2) + " deg)"
                           : std::string("kinematic pose kept")) << ", " << map.num_frontier << " frontier voxels; move "
         << fixed(moved->move_s + moved->settle_s, 2) << " s, capture " << fixed(cloud->capture_s, 2) << " s, register "
         << fixed(reg.register_s, 2) << " s, map " << fixed(map.update_s * 1e3, 2) << " ms";
      if (view.contains("plan") && view["plan"].contains("planner_step_ms")) {
        os << ", plan " << fixed(view["plan"]["planner_step_ms"].get<double>(), 2) << " ms";
      }
      progress(os.str(), true);
    }
    if (views_done_ == 0) return finish(scan_status_t::kFailed, "no view produced a cloud");
    stop_ = {{"reason", "view budget reached (--views " + std::to_string(s_.views) + ")"}, {"after_views", views_done_},
             {"rule", "budget"}};
    return finish(scan_status_t::kDone, "scan complete: " + stop_["reason"].get<std::string>());
  }

 private:
  void plan_views() {
    const Eigen::Vector3d half = s_.normalisation.extent_m / 2.0;
    const double radius = s_.working_distance_m + half.norm();
    if (s_.planner == PlannerKind::kRing) {
      views_ = ring_views(s_.views, radius, s_.ring_elevation_deg * kPi / 180.0,
                          s_.ring_start_azimuth_deg * kPi / 180.0, Eigen::Vector3d::Zero());
      report_["plan"] = {{"planner", "ring"}, {"radius_m", radius}, {"elevation_deg", s_.ring_elevation_deg}};
    } else {
      if (s_.initial_view_m.allFinite()) {
        first_view_ = look_at_z_up(s_.initial_view_m, Eigen::Vector3d::Zero());
      } else {
        first_view_ = ring_views(1, radius, s_.ring_elevation_deg * kPi / 180.0, s_.ring_start_azimuth_deg * kPi / 180.0,
                                 Eigen::Vector3d::Zero())[0];
      }
      report_["plan"] = {{"planner", std::string(name_of(s_.planner))}, {"initial_view", to_json(first_view_)}};
    }
  }

  json plan_json(const view_plan_t& p) {
    json j = {{"planner", p.planner}, {"outcome", p.outcome == view_plan_t::kView ? "view" : p.outcome == view_plan_t::kStop ? "stop" : "failed"},
              {"reason", p.reason}, {"map_of_view", latest_map_},
              {"view_quality_px", p.view_quality}, {"first_quality_px", p.first_quality},
              {"frontier_area_px", p.frontier_area_px}, {"occupied_area_px", p.occupied_area_px},
              {"partition", p.partition}, {"allowed_sectors", p.allowed_sectors}, {"partition_fallback", p.partition_fallback != 0},
              {"sphere", {{"centre_m", {p.sphere_centre_m[0], p.sphere_centre_m[1], p.sphere_centre_m[2]}}, {"radius_m", p.sphere_radius_m}}},
              {"candidates", {{"generated", p.num_candidates}, {"unreachable", p.num_unreachable}, {"excluded", p.num_excluded},
                              {"scored", p.num_scored}}},
              {"alternative_quality_px", p.alternative_quality}};
    double map_s = 0, fit_s = 0;
    if (auto m = maps_.find(latest_map_); m != maps_.end()) map_s = m->second.update_s;
    if (auto e = ellipsoids_.find(latest_map_); e != ellipsoids_.end()) {
      const ellipsoid_set_t& es = e->second;
      fit_s = es.fit_s;
      json list = json::array();
      for (const auto& el : es.ellipsoids) {
        list.push_back({{"class", el.cls == ellipsoid_t::kFrontier ? "frontier" : "occupied"},
                        {"centre_m", {el.centre_m[0], el.centre_m[1], el.centre_m[2]}},
                        {"semi_axes_m", {el.semi_axes_m[0], el.semi_axes_m[1], el.semi_axes_m[2]}},
                        {"quat_wxyz", {el.quat_wxyz[0], el.quat_wxyz[1], el.quat_wxyz[2], el.quat_wxyz[3]}},
                        {"voxels", el.num_voxels}});
      }
      j["ellipsoids"] = {{"occupied_components", es.occupied_components}, {"frontier_components", es.frontier_components},
                         {"list", list}};
    }
    j["time_ms"] = {{"map_update", map_s * 1e3}, {"ellipsoid_fit", fit_s * 1e3}, {"candidates", p.candidates_s * 1e3},
                    {"reachability", p.reachability_s * 1e3}, {"scoring", p.scoring_s * 1e3},
                    {"scorer_wait", p.wait_s * 1e3}, {"view_selection", p.plan_s * 1e3}};
    // The planner step as the paper times it: map update + fitting + view selection.
    j["planner_step_ms"] = (map_s + fit_s + p.plan_s) * 1e3;
    j["figure"] = "plans/" + view_file(p.iteration, "png");  // written by the view scorer just after it answers
    return j;
  }

  std::optional<view_plan_t> request_plan(int i) {
    plan_request_t r{};
    r.scan_id = s_.scan_id;
    r.iteration = i;
    r.request_id = i;
    r.planner = std::string(name_of(s_.planner));
    r.map_iteration = latest_map_;  // the newest map: the view scorer keeps only that one
    for (const auto& v : views_taken_) r.views_done.push_back(bus::to_msg(v));
    r.num_views_done = static_cast<int32_t>(r.views_done.size());
    for (const auto& v : excluded_) r.excluded.push_back(bus::to_msg(v));
    r.num_excluded = static_cast<int32_t>(r.excluded.size());
    r.num_candidates = s_.candidates;
    r.num_parallels = s_.parallels;
    r.num_sectors = s_.sectors;
    r.full_sphere = s_.area == CandidateArea::kFullSphere;
    r.working_distance_m = s_.working_distance_m;
    r.num_alternatives = s_.alternatives;
    r.stop_fraction = s_.stop_fraction;
    r.spread_when_done = s_.when_done == WhenDone::kSpread;
    r.first_quality = first_quality_;
    r.seed = s_.seed + i;
    r.depth_min_m = s_.depth_range.min_m;
    r.depth_max_m = s_.depth_range.max_m;
    r.width_px = s_.camera.width;
    r.height_px = s_.camera.height;
    r.fx = s_.camera.fx;
    r.fy = s_.camera.fy;
    r.cx = s_.camera.cx;
    r.cy = s_.camera.cy;
    r.check_reachability = s_.rig == RigKind::kArm;
    for (int k = 0; k < 6; ++k) r.joint_position_rad[k] = joints_[k];
    r.turntable_angle_rad = turntable_;
    r.object_z_m = s_.object_z_m;
    for (int k = 0; k < 3; ++k) {
      r.keepout_min_m[k] = s_.keepout_min_m[k];
      r.keepout_max_m[k] = s_.keepout_max_m[k];
    }
    fs::create_directories(out_ / "plans");
    r.figure_path = (out_ / "plans" / view_file(i, "png")).string();
    if (last_map_ < 0) {
      view_plan_t none{};
      none.iteration = i;
      none.planner = std::string(name_of(s_.planner));
      none.outcome = view_plan_t::kFailed;
      none.reason = "no view has been mapped yet";
      return none;
    }
    const double deadline = bus::now_s() + kPlanTimeoutS;
    while (bus::now_s() < deadline && !stop_requested()) {
      r.utime = bus::now_utime();
      bus_.publish(channels::kPlanRequest, r);
      if (spin_until([&] { return plans_.count(i) > 0; }, kResendS)) return plans_[i];
    }
    return std::nullopt;
  }

  bool wait_ready() {
    std::set<std::string> need = {"ARM_STATUS", "heartbeat of motion", "heartbeat of camera",
                                  "heartbeat of registration", "heartbeat of mapping"};
    if (s_.rig == RigKind::kArm) need.insert("TURNTABLE_STATUS");
    if (uses_view_scorer(s_.planner)) need.insert("heartbeat of scorer");
    if (uses_ellipsoids(s_.planner)) need.insert("heartbeat of ellipsoids");
    const bool ok = spin_until([&] {
      for (const auto& n : need) if (!seen_.count(n)) return false;
      return true;
    }, s_.startup_timeout_s);
    if (!ok) {
      std::string missing;
      for (const auto& n : need) if (!seen_.count(n)) missing += (missing.empty() ? "" : ", ") + n;
      startup_problem_ = "not ready after " + fixed(s_.startup_timeout_s, 2) + " s: no " + missing;
    }
    return ok;
  }

  bool spin_until(const std::function<bool()>& done, double timeout_s) {
    const double deadline = bus::now_s() + timeout_s;
    while (!stop_requested()) {
      if (done()) return true;
      if (bus::now_s() > deadline) return false;
      bus_.spin_once(20);
      publish_status_periodically();
    }
    return false;
  }

  // Moves to option k of view i (request_id unique per view and option).
  std::optional<move_result_t> move(int i, int k, const Pose& target) {
    const int64_t id = static_cast<int64_t>(i) * 100 + k;
    move_request_t r;
    r.scan_id = s_.scan_id;
    r.iteration = i;
    r.request_id = id;
    r.object_T_camera = bus::to_msg(target);
    r.object_z_m = s_.object_z_m;
    for (int k = 0; k < 3; ++k) {
      r.keepout_min_m[k] = s_.keepout_min_m[k];
      r.keepout_max_m[k] = s_.keepout_max_m[k];
    }
    r.speed_scale = s_.speed_scale;
    r.timeout_s = s_.move_timeout_s;
    r.plan_only = false;
    const double deadline = bus::now_s() + s_.move_timeout_s + 15.0;
    while (bus::now_s() < deadline && !stop_requested()) {
      move_results_.erase(id);
      r.utime = bus::now_utime();
      bus_.publish(channels::kMoveRequest, r);
      if (spin_until([&] { return move_results_.count(id) > 0; }, kResendS)) {
        if (move_results_[id].status != move_result_t::kBusy) return move_results_[id];
      }
    }
    return std::nullopt;
  }

  std::optional<point_cloud_t> capture(int i, int64_t not_before_utime) {
    capture_request_t r;
    r.scan_id = s_.scan_id;
    r.iteration = i;
    r.request_id = i;
    r.not_before_utime = not_before_utime;
    r.object_z_m = s_.object_z_m;
    for (int k = 0; k < 3; ++k) {
      r.crop_min_m[k] = s_.crop_min_m[k];
      r.crop_max_m[k] = s_.crop_max_m[k];
    }
    r.ground_clearance_m = s_.ground_clearance_m;
    r.voxel_m = s_.voxel_m;
    r.timeout_s = s_.capture_timeout_s;
    // The camera service retries the trigger itself (3 tries); re-send only if the whole
    // answer is lost.
    const double per_try = 3 * s_.capture_timeout_s + 5.0;
    for (int attempt = 0; attempt < 3 && !stop_requested(); ++attempt) {
      r.utime = bus::now_utime();
      bus_.publish(channels::kCaptureRequest, r);
      if (spin_until([&] { return clouds_.count(i) > 0; }, per_try)) return clouds_[i];
    }
    return std::nullopt;
  }

  // Writes the view's cloud (registered if accepted) to frames/ and merges accepted views into
  // cloud.ply; a view the registration rejected is kept in frames/ but not merged.
  void accumulate(int i, const registered_cloud_t& r, json& view) {
    PointCloud frame;
    frame.reserve(r.cloud.points_m.size());
    for (const auto& p : r.cloud.points_m) frame.emplace_back(p[0], p[1], p[2]);
    const std::string name = view_file(i, "ply");
    write_ply(frame, (out_ / "frames" / name).string());
    view["frame_file"] = "frames/" + name;
    view["merged"] = r.accepted != 0;
    if (r.accepted) {
      accumulated_.insert(accumulated_.end(), frame.begin(), frame.end());
      accumulated_ = voxel_downsample(accumulated_, s_.voxel_m);
      write_ply(accumulated_, (out_ / "cloud.ply").string());
    }
    clouds_.erase(i);  // on disk now; keep memory flat
    registered_.erase(i);
  }

  void record(const json& view) {
    report_["views"].push_back(view);
    write_report("running", "");
  }

  void write_report(const std::string& state, const std::string& message) {
    report_["status"] = {{"state", state}, {"message", message}, {"views_done", views_done_},
                         {"views_planned", s_.views}, {"elapsed_s", bus::now_s() - t_start_},
                         {"num_points", accumulated_.size()}};
    if (!stop_.is_null()) report_["stop"] = stop_;
    write_json_atomic(report_, (out_ / "scan.json").string());
  }

  int finish(int8_t state, const std::string& message) {
    status(state, message);
    const char* name = state == scan_status_t::kDone ? "done" : state == scan_status_t::kStopped ? "stopped" : "failed";
    write_report(name, message);
    if (::isatty(STDOUT_FILENO)) std::cout << "\r\033[K";  // clear an unfinished progress line
    std::cout << (state == scan_status_t::kDone ? "" : "scan ") << message << ": " << views_done_ << " of "
              << s_.views << " views, " << accumulated_.size() << " points, "
              << fixed(bus::now_s() - t_start_, 2) << " s -> " << (out_ / "scan.json").string() << std::endl;
    return state == scan_status_t::kDone ? 0 : state == scan_status_t::kStopped ? 130 : 1;
  }

  // One line per view on a terminal (the stage overwrites itself), every stage on its own line
  // otherwise (logs, pipes).
  void progress(const std::string& what, bool last = false) {
    static const bool tty = ::isatty(STDOUT_FILENO) != 0;
    const std::string line = "[view " + std::to_string(iteration_ + 1) + "/" + std::to_string(s_.views) + "] " + what;
    if (tty) {
      std::cout << "\r\033[K" << line << (last ? "\n" : "") << std::flush;
    } else {
      std::cout << line << std::endl;
    }
  }

  void status(int8_t state, const std::string& message) {
    state_ = state;
    message_ = message;
    publish_status();
  }

  void publish_status() {
    scan_status_t m;
    m.utime = bus::now_utime();
    m.scan_id = s_.scan_id;
    m.iteration = iteration_;
    m.num_views_planned = s_.views;
    m.num_views_done = views_done_;
    m.state = state_;
    m.message = message_;
    m.elapsed_s = bus::now_s() - t_start_;
    m.num_points = static_cast<int32_t>(accumulated_.size());
    bus_.publish(channels::kScanStatus, m);
    bus_.set_scan(s_.scan_id, iteration_);
    last_status_s_ = bus::now_s();
  }

  void publish_status_periodically() {
    if (bus::now_s() - last_status_s_ >= 1.0) publish_status();
  }

  bus::Bus& bus_;
  ScanSettings s_;
  fs::path out_;
  std::vector<Pose> views_;            // ring planner
  Pose first_view_ = Pose::Identity(); // pbnbv planner
  std::vector<Pose> views_taken_;      // registered camera poses of mapped views
  std::vector<Pose> excluded_;         // views the rig could not reach or capture
  double first_quality_ = std::numeric_limits<double>::quiet_NaN();
  int last_map_ = -1;                  // last view integrated into the map
  int latest_map_ = -1;                // last view the mapping service answered (the current map,
                                       // changed or not by that view)
  double joints_[6] = {0, 0, 0, 0, 0, 0};
  double turntable_ = 0;
  json stop_;
  std::map<int32_t, ellipsoid_set_t> ellipsoids_;
  std::map<int64_t, view_plan_t> plans_;
  std::map<int64_t, move_result_t> move_results_;
  std::map<int64_t, point_cloud_t> clouds_;
  std::map<int64_t, registered_cloud_t> registered_;
  std::map<int32_t, voxel_set_t> maps_;
  std::set<std::string> seen_;
  PointCloud accumulated_;
  json report_;
  std::string startup_problem_;
  int iteration_ = 0;
  int views_done_ = 0;
  int8_t state_ = scan_status_t::kStarting;
  std::string message_;
  double t_start_ = 0;
  double last_status_s_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  set_log_name("coordinator");
  CLI::App app{"pbnbv-coordinator: runs one scan view by view (plan, move, capture, register, map) and writes "
               "its record",
               "pbnbv-coordinator"};
  cli::init(app);
  std::string out, settings_path;
  cli::add_text(app, "out", &out, "the scan's folder (scan.json, cloud.ply, frames/, plans/)", "DIR")->required();
  cli::add_text(app, "settings", &settings_path, "the scan's settings [DIR/settings.json]", "PATH");
  if (const std::optional<int> code = cli::parse(app, argc, argv, std::cout, std::cerr)) return *code;
  install_stop_handlers();
  try {
    if (settings_path.empty()) settings_path = (fs::path(out) / "settings.json").string();
    const ScanSettings settings = scan_settings_from_json(read_json(settings_path));
    bus::Bus bus("coordinator");
    Coordinator coordinator(bus, settings, out);
    return coordinator.run();
  } catch (const std::exception& e) {
    log_error(e.what());
    return 2;
  }
}
