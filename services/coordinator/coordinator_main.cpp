// pbnbv-coordinator: the scan coordinator.
//   in:  MOVE_RESULT, CLOUD, REGISTERED_CLOUD, VOXEL_MAP, ARM_STATUS, TURNTABLE_STATUS, HEARTBEAT
//   out: MOVE_REQUEST, CAPTURE_REQUEST, SCAN_STATUS, HEARTBEAT
// Runs move -> settle -> capture -> register -> map -> accumulate for each view of the plan,
// writes the scan's output folder after every view (cloud.ply, frames/, scan.json), and prints
// progress.
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

#include "common/bus.hpp"
#include "common/convert.hpp"
#include "core/args.hpp"
#include "core/cloud.hpp"
#include "core/log.hpp"
#include "core/scan_settings.hpp"
#include "core/views.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/capture_request_t.hpp"
#include "pbnbv/heartbeat_t.hpp"
#include "pbnbv/move_request_t.hpp"
#include "pbnbv/move_result_t.hpp"
#include "pbnbv/point_cloud_t.hpp"
#include "pbnbv/registered_cloud_t.hpp"
#include "pbnbv/voxel_set_t.hpp"
#include "pbnbv/scan_status_t.hpp"
#include "pbnbv/turntable_status_t.hpp"

using namespace pbnbv;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kResendS = 3.0;          // re-send a request whose answer has not come
constexpr double kAnswerTimeoutS = 60.0;  // registration / mapping answer to a view

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

    for (int i = 0; i < static_cast<int>(views_.size()); ++i) {
      if (bus::stop_requested()) return finish(scan_status_t::kStopped, "interrupted");
      iteration_ = i;
      json view = {{"view", i}, {"requested_object_T_camera", to_json(views_[i])}};
      const double t_view = bus::now_s();
      progress("moving");
      status(scan_status_t::kMoving, "moving to view " + std::to_string(i + 1));
      const double t_move = bus::now_s();
      std::optional<move_result_t> moved = move(i);
      if (!moved) {
        if (bus::stop_requested()) return finish(scan_status_t::kStopped, "interrupted");
        view["move"] = {{"status", "no_answer"}, {"reason", "no MOVE_RESULT from the motion executor"}};
        record(view);
        return finish(scan_status_t::kFailed, "the motion executor did not answer the move to view " + std::to_string(i + 1));
      }
      view["move"] = {{"status", move_status_name(moved->status)}, {"reason", moved->reason},
                      {"reached_object_T_camera", pose_json(moved->reached_object_T_camera)},
                      {"position_error_m", moved->position_error_m},
                      {"angle_error_deg", moved->angle_error_rad * 180 / M_PI},
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
      progress("capturing");
      status(scan_status_t::kCapturing, "capturing view " + std::to_string(i + 1));
      const double t_capture = bus::now_s();
      std::optional<point_cloud_t> cloud = capture(i, moved->settled_utime);
      if (!cloud) {
        if (bus::stop_requested()) return finish(scan_status_t::kStopped, "interrupted");
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
        record(view);
        continue;
      }
      status(scan_status_t::kIntegrating, "registering and mapping view " + std::to_string(i + 1));
      progress("registering");
      const double t_reg = bus::now_s();
      if (!spin_until([&] { return registered_.count(i) > 0; }, kAnswerTimeoutS)) {
        if (bus::stop_requested()) return finish(scan_status_t::kStopped, "interrupted");
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
        if (bus::stop_requested()) return finish(scan_status_t::kStopped, "interrupted");
        record(view);
        return finish(scan_status_t::kFailed, "the mapping service did not answer view " + std::to_string(i + 1));
      }
      const voxel_set_t& map = maps_[i];
      view["map"] = {{"updated", map.updated != 0}, {"message", map.message}, {"resolution_m", map.resolution_m},
                     {"bbox_min_m", {map.bbox_min_m[0], map.bbox_min_m[1], map.bbox_min_m[2]}},
                     {"bbox_max_m", {map.bbox_max_m[0], map.bbox_max_m[1], map.bbox_max_m[2]}},
                     {"voxels", {{"none", map.num_none}, {"empty", map.num_empty}, {"occupied", map.num_occupied},
                                 {"unknown", map.num_unknown}, {"frontier", map.num_frontier}}}};
      view["time_s"]["map_update"] = map.update_s;
      view["time_s"]["map_round_trip"] = bus::now_s() - t_map;
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
             : reg.refined ? "registered (" + fixed(reg.translation_m * 1e3) + " mm, " + fixed(reg.rotation_deg) + " deg)"
                           : std::string("kinematic pose kept")) << ", " << map.num_frontier << " frontier voxels; move "
         << fixed(moved->move_s + moved->settle_s) << " s, capture " << fixed(cloud->capture_s) << " s, register "
         << fixed(reg.register_s) << " s, map " << fixed(map.update_s * 1e3) << " ms";
      progress(os.str(), true);
    }
    if (views_done_ == 0) return finish(scan_status_t::kFailed, "no view produced a cloud");
    return finish(scan_status_t::kDone, "scan complete");
  }

 private:
  static std::string fixed(double x) {
    char b[32];
    std::snprintf(b, sizeof(b), "%.2f", x);
    return b;
  }

  void plan_views() {
    if (s_.planner != "ring") throw std::invalid_argument("planner '" + s_.planner + "' is not available (ring)");
    const Eigen::Vector3d half = s_.normalisation.extent_m / 2.0;
    const double radius = s_.working_distance_m + half.norm();
    views_ = ring_views(s_.views, radius, s_.ring_elevation_deg * M_PI / 180.0,
                        s_.ring_start_azimuth_deg * M_PI / 180.0, Eigen::Vector3d::Zero());
    report_["plan"] = {{"planner", "ring"}, {"radius_m", radius}, {"elevation_deg", s_.ring_elevation_deg}};
  }

  bool wait_ready() {
    std::set<std::string> need = {"ARM_STATUS", "heartbeat of motion", "heartbeat of camera",
                                  "heartbeat of registration", "heartbeat of mapping"};
    if (s_.rig == RigKind::kArm) need.insert("TURNTABLE_STATUS");
    const bool ok = spin_until([&] {
      for (const auto& n : need) if (!seen_.count(n)) return false;
      return true;
    }, s_.startup_timeout_s);
    if (!ok) {
      std::string missing;
      for (const auto& n : need) if (!seen_.count(n)) missing += (missing.empty() ? "" : ", ") + n;
      startup_problem_ = "not ready after " + fixed(s_.startup_timeout_s) + " s: no " + missing;
    }
    return ok;
  }

  bool spin_until(const std::function<bool()>& done, double timeout_s) {
    const double deadline = bus::now_s() + timeout_s;
    while (!bus::stop_requested()) {
      if (done()) return true;
      if (bus::now_s() > deadline) return false;
      bus_.spin_once(20);
      publish_status_periodically();
    }
    return false;
  }

  std::optional<move_result_t> move(int i) {
    move_request_t r;
    r.scan_id = s_.scan_id;
    r.iteration = i;
    r.request_id = i;
    r.object_T_camera = bus::to_msg(views_[i]);
    r.object_z_m = s_.object_z_m;
    for (int k = 0; k < 3; ++k) {
      r.keepout_min_m[k] = s_.keepout_min_m[k];
      r.keepout_max_m[k] = s_.keepout_max_m[k];
    }
    r.speed_scale = s_.speed_scale;
    r.timeout_s = s_.move_timeout_s;
    r.plan_only = false;
    const double deadline = bus::now_s() + s_.move_timeout_s + 15.0;
    while (bus::now_s() < deadline && !bus::stop_requested()) {
      move_results_.erase(i);
      r.utime = bus::now_utime();
      bus_.publish(channels::kMoveRequest, r);
      if (spin_until([&] { return move_results_.count(i) > 0; }, kResendS)) {
        if (move_results_[i].status != move_result_t::kBusy) return move_results_[i];
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
    for (int attempt = 0; attempt < 3 && !bus::stop_requested(); ++attempt) {
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
    char name[32];
    std::snprintf(name, sizeof(name), "view_%03d.ply", i);
    write_ply(frame, (out_ / "frames" / name).string());
    view["frame_file"] = std::string("frames/") + name;
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
                         {"views_planned", views_.size()}, {"elapsed_s", bus::now_s() - t_start_},
                         {"num_points", accumulated_.size()}};
    write_json_atomic(report_, (out_ / "scan.json").string());
  }

  int finish(int8_t state, const std::string& message) {
    status(state, message);
    const char* name = state == scan_status_t::kDone ? "done" : state == scan_status_t::kStopped ? "stopped" : "failed";
    write_report(name, message);
    if (::isatty(STDOUT_FILENO)) std::cout << "\r\033[K";  // clear an unfinished progress line
    std::cout << (state == scan_status_t::kDone ? "" : "scan ") << message << ": " << views_done_ << " of "
              << views_.size() << " views, " << accumulated_.size() << " points, "
              << fixed(bus::now_s() - t_start_) << " s -> " << (out_ / "scan.json").string() << std::endl;
    return state == scan_status_t::kDone ? 0 : state == scan_status_t::kStopped ? 130 : 1;
  }

  // One line per view on a terminal (the stage overwrites itself), every stage on its own line
  // otherwise (logs, pipes).
  void progress(const std::string& what, bool last = false) {
    static const bool tty = ::isatty(STDOUT_FILENO) != 0;
    const std::string line = "[view " + std::to_string(iteration_ + 1) + "/" + std::to_string(views_.size()) + "] " + what;
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
    m.num_views_planned = static_cast<int32_t>(views_.size());
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
  std::vector<Pose> views_;
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
  bus::install_stop_handlers();
  try {
    Args args(argc, argv);
    const fs::path out = args.str("out");
    const ScanSettings settings = scan_settings_from_json(read_json(args.str("settings", (out / "settings.json").string())));
    args.reject_unknown();
    bus::Bus bus("coordinator");
    Coordinator coordinator(bus, settings, out);
    return coordinator.run();
  } catch (const std::exception& e) {
    log_error(e.what());
    std::cerr << "usage: pbnbv-coordinator --out DIR [--settings DIR/settings.json]\n";
    return 2;
  }
}
