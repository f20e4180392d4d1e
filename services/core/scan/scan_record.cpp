#include "core/scan/scan_record.hpp"

#include <cmath>
#include <limits>


#include "core/base/format.hpp"
#include "core/base/version.hpp"
#include "core/base/units.hpp"
#include "core/io/json.hpp"
#include "core/scan/scan_file.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv {

namespace {

// A 6-vector as a JSON array.
json to_json6(const Vector6d& q) { return std::vector<double>(q.data(), q.data() + 6); }

// scan.json's "move" of a view that got its MOVE_RESULT.
json move_json(const MoveResult& m) {
  return {{"status", to_string(m.status)},
          {"reason", m.reason},
          {"reached_object_T_camera", to_json(m.reached_object_T_camera)},
          {"position_error_m", m.position_error_m},
          {"angle_error_deg", rad_to_deg(m.angle_error_rad)},
          {"joint_target_rad", to_json6(m.joint_target_rad)},
          {"joint_position_rad", to_json6(m.joint_position_rad)},
          {"turntable_target_rad", m.turntable_target_rad},
          {"turntable_angle_rad", m.turntable_angle_rad},
          {"route", m.route},
          {"request_id", m.request_id},
          {"contacts", m.contacts},
          {"contact", m.contact}};
}

// scan.json's "capture" of a view that got its CLOUD.
json capture_json(const CaptureResult& c, std::size_t num_points) {
  return {{"status", c.ok ? "ok" : "failed"},
          {"request_id", c.request_id},
          {"message", c.message},
          {"camera_object_T_camera", to_json(c.object_T_camera)},
          {"joint_position_rad", to_json6(c.joint_position_rad)},
          {"turntable_angle_rad", c.turntable_angle_rad},
          {"depth_frame_seq", c.depth_frame_seq},
          {"num_valid_pixels", c.num_valid_pixels},
          {"num_cropped", c.num_cropped},
          {"num_points", num_points}};
}

// scan.json's "registration": the registration service's verdict, in mm and degrees.
json registration_json(const RegisteredCloud& r) {
  return {{"accepted", r.accepted},
          {"refined", r.refined},
          {"flagged", r.flagged},
          {"constraint", r.constraint},
          {"reason", r.reason},
          {"correction", to_json(r.correction)},
          {"translation_mm", r.translation_m * 1e3},
          {"rotation_deg", r.rotation_deg},
          {"overlap", r.overlap},
          {"rmse_mm", r.rmse_m * 1e3},
          {"icp_translation_mm", r.icp_translation_m * 1e3},
          {"icp_rotation_deg", r.icp_rotation_deg},
          {"prior_sigmas", r.prior_sigmas},
          {"iterations", r.iterations},
          {"registered_object_T_camera", to_json(r.cloud.object_T_camera)},
          {"kinematic_object_T_camera", to_json(r.kinematic_object_T_camera)}};
}

// scan.json's "map": the voxel map after the view, as counts per state inside B.
json map_json(const VoxelMapSummary& m) {
  return {{"updated", m.updated},
          {"message", m.message},
          {"resolution_m", m.resolution_m},
          {"bbox_min_m", to_json(m.bbox_min_m)},
          {"bbox_max_m", to_json(m.bbox_max_m)},
          {"voxels",
           {{"none", m.num_none},
            {"empty", m.num_empty},
            {"occupied", m.num_occupied},
            {"unknown", m.num_unknown},
            {"frontier", m.num_frontier}}}};
}

// The ellipsoids a plan was made from.
json ellipsoids_json(const EllipsoidSetSummary& es) {
  json list = json::array();
  for (const auto& e : es.ellipsoids) {
    list.push_back({{"class", e.frontier ? "frontier" : "occupied"},
                    {"centre_m", to_json(e.centre_m)},
                    {"semi_axes_m", to_json(e.semi_axes_m)},
                    {"quat_wxyz", e.quat_wxyz},
                    {"voxels", e.num_voxels}});
  }
  return {{"occupied_components", es.occupied_components}, {"frontier_components", es.frontier_components}, {"list", list}};
}

}  // namespace

json rig_time_json(const RigTime& t) {
  // NaN (not measured) is written as null.
  return {{"motion", t.motion_s}, {"settle", t.settle_s}, {"capture", t.capture_s}, {"compute", t.compute_s},
          {"total", t.total_s()}};
}

RigTimeSum sum_rig_time(const std::vector<ViewRecord>& views) {
  RigTimeSum s;
  for (const ViewRecord& v : views) {
    if (!v.rig_time) continue;
    ++s.views;
    if (!v.rig_time->complete()) ++s.views_incomplete;
    for (auto part : {&RigTime::motion_s, &RigTime::settle_s, &RigTime::capture_s, &RigTime::compute_s}) {
      if (std::isfinite((*v.rig_time).*part)) s.sum.*part += (*v.rig_time).*part;
    }
  }
  return s;
}

std::string rig_time_summary(const RigTimeSum& rig) {
  if (rig.views == 0) return "";
  std::string text = "; rig time " + rig_time_text(rig.sum);
  if (rig.views_incomplete > 0) {
    text += " (" + std::to_string(rig.views_incomplete) + (rig.views_incomplete == 1 ? " view" : " views") +
            " not measured in full)";
  }
  return text;
}

std::vector<double> rig_time_at_frames(const std::vector<ViewRecord>& views) {
  if (sum_rig_time(views).views == 0) return {};
  std::vector<double> out;
  double t = 0;
  for (const ViewRecord& v : views) {
    t += v.rig_time ? v.rig_time->total_s() : RigTime::kUnset;
    if (v.registration && !v.registration->frame_file.empty()) out.push_back(t);
  }
  return out;
}

double planner_step_ms(const PlanRecord& p) {
  const double fit_s = p.ellipsoids ? p.ellipsoids->fit_s : 0.0;
  return (p.map_update_s + fit_s + p.plan.plan_s) * 1e3;
}

double planner_critical_ms(const PlanRecord& p) {
  const ViewPlan& v = p.plan;
  if (!(v.wait_s > 0) || v.wait_s + 1e-9 < v.reachability_s) return std::numeric_limits<double>::quiet_NaN();
  return (p.map_update_s + v.wait_s + v.plan_s - v.reachability_s) * 1e3;
}

json to_json(const PlanRecord& r) {
  const ViewPlan& p = r.plan;
  json j = {{"planner", name_of(p.planner)},
            {"outcome", to_string(p.outcome)},
            {"reason", p.reason},
            {"ranking", name_of(p.ranking)},
            {"map_of_view", r.map_of_view + 1},  // counted from 1 as "view" (0: not known)
            {"view_quality_px", p.view_quality},
            {"first_quality_px", p.first_quality},
            {"frontier_area_px", p.frontier_area_px},
            {"occupied_area_px", p.occupied_area_px},
            {"partition", p.partition},
            {"allowed_sectors", p.allowed_sectors},
            {"partition_fallback", p.partition_fallback},
            {"sphere", {{"centre_m", to_json(p.sphere_centre_m)}, {"radius_m", p.sphere_radius_m}}},
            {"candidates",
             {{"generated", p.num_candidates},
              {"unreachable", p.num_unreachable},
              {"excluded", p.num_excluded},
              {"scored", p.num_scored}}},
            {"alternative_quality_px", p.alternative_quality}};
  if (p.outcome == PlanOutcome::kView) j["object_T_camera"] = to_json(p.object_T_camera);  // the chosen view
  if (r.ellipsoids) j["ellipsoids"] = ellipsoids_json(*r.ellipsoids);
  const double fit_s = r.ellipsoids ? r.ellipsoids->fit_s : 0.0;
  j["time_ms"] = {{"map_update", r.map_update_s * 1e3}, {"ellipsoid_fit", fit_s * 1e3},
                  {"candidates", p.candidates_s * 1e3}, {"reachability", p.reachability_s * 1e3},
                  {"scoring", p.scoring_s * 1e3},      {"scorer_wait", p.wait_s * 1e3},
                  {"view_selection", p.plan_s * 1e3}};
  j["planner_step_ms"] = planner_step_ms(r);
  if (const double c = planner_critical_ms(r); std::isfinite(c)) j["planner_critical_ms"] = c;
  j["figure"] = "plans/" + view_file(p.iteration, "png");  // written by the view scorer just after it answers
  return j;
}

json to_json(const ViewRecord& v) {
  json view = {{"view", v.view + 1}};  // counted from 1 in the file (format 2), as view_001 is the first
  if (v.initial_view) {
    view["plan"] = {{"planner", "initial view"}};
  } else if (v.plan) {
    view["plan"] = to_json(*v.plan);
  }
  if (v.option) {
    view["requested_object_T_camera"] = to_json(v.requested_object_T_camera);
    view["option"] = *v.option;
  }
  if (!v.failed_moves.empty()) {
    json attempts = json::array();
    for (const auto& f : v.failed_moves) {
      attempts.push_back({{"option", f.option},
                          {"status", to_string(f.status)},
                          {"reason", f.reason},
                          {"object_T_camera", to_json(f.object_T_camera)},
                          {"request_id", f.request_id},
                          {"contacts", f.contacts},
                          {"contact", f.contact}});
    }
    view["failed_moves"] = attempts;
  }
  if (v.move_unanswered) {
    view["move"] = {{"status", "no_answer"}, {"reason", "no MOVE_RESULT from the motion executor"}};
  } else if (v.move) {
    view["move"] = move_json(*v.move);
    view["time_s"] = {{"plan", v.move->plan_s}, {"move", v.move->move_s}, {"settle", v.move->settle_s},
                      {"rig_motion", v.move->rig_motion_s}, {"path_model", v.move->path_s},
                      {"move_round_trip", v.move_round_trip_s}};
  }
  if (v.capture_unanswered) {
    view["capture"] = {{"status", "no_answer"}};
  } else if (v.capture) {
    view["time_s"]["capture"] = v.capture->capture_s;
    view["time_s"]["cloud"] = v.capture->process_s;
    view["time_s"]["capture_round_trip"] = v.capture_round_trip_s;
    view["capture"] = capture_json(*v.capture, v.capture_points);
  }
  if (v.registration) {
    view["registration"] = registration_json(*v.registration);
    view["time_s"]["register"] = v.registration->register_s;
    view["time_s"]["register_round_trip"] = v.register_round_trip_s;
  }
  if (v.map) {
    view["map"] = map_json(*v.map);
    view["time_s"]["map_update"] = v.map->update_s;
    view["time_s"]["map_round_trip"] = v.map_round_trip_s;
  }
  if (v.registration) {
    // What the registration service wrote for the view (its folder) and added to the model.
    const RegisteredCloud& r = *v.registration;
    if (!r.frame_file.empty()) {
      view["frame_file"] = r.frame_file;
      // The pose the frame's points were placed with (the registered one when accepted): the
      // camera_pose comment of the frame's PLY header.
      view["camera_pose"] = to_json(r.cloud.object_T_camera);
      view["camera_pose"]["frame"] = "object";
      view["camera_pose"]["of"] = "the camera's optical frame (x right, y down, z forward)";
      view["normals"] = r.normals_from_depth ? "depth image" : "neighbours";
    }
    if (!r.depth_file.empty()) view["depth_file"] = r.depth_file;
    view["merged"] = r.accepted;
    if (r.new_surface) view["new_surface"] = to_json(*r.new_surface);
    view["time_s"]["accumulate"] = r.accumulate_s;
  }
  if (v.map) view["time_s"]["view_total"] = v.view_total_s;
  if (v.rig_time) view["rig_time_s"] = rig_time_json(*v.rig_time);
  return view;
}

json to_json(const MeshSummary& m) {
  json j = {{"file", m.files.empty() ? std::string() : m.files.front()},
            {"also", m.files.size() > 1 ? std::vector<std::string>(m.files.begin() + 1, m.files.end()) : std::vector<std::string>{}},
            {"method", m.tsdf ? "tsdf" : "poisson"},
            {"frames", m.frames},
            {"points", m.points},
            {"vertices", m.vertices},
            {"triangles", m.triangles},
            {"watertight", m.watertight},
            {"boundary_loops", m.boundary_loops},
            {"boundary_edges", m.boundary_edges},
            {"non_manifold_edges", m.non_manifold_edges},
            {"hole_boundary_length_m", m.hole_boundary_length_m},
            {"area_m2", m.area_m2},
            {"volume_m3", m.volume_m3 ? json(*m.volume_m3) : json(nullptr)},
            {"small_fragments_removed_triangles", m.small_fragments_removed_triangles},
            {"holes_filled", m.holes_filled},
            {"fill_holes_m", m.fill_holes_m},
            {"seconds", m.seconds}};
  if (m.tsdf) {
    j["settings"] = {{"voxel_m", m.voxel_m}, {"truncation_m", m.truncation_m}, {"image_scale", m.image_scale}, {"voxels", m.voxels}};
  } else {
    j["settings"] = {{"poisson_depth", m.poisson_depth}};
  }
  return j;
}

json to_json(const ScanStop& s) {
  json j = {{"reason", s.reason}, {"after_views", s.after_views}, {"rule", s.rule}};
  if (!s.figures.is_null()) j["figures"] = s.figures;
  return j;
}

std::vector<RigContactRecord> rig_contacts(const std::vector<ViewRecord>& views) {
  std::vector<RigContactRecord> out;
  for (const ViewRecord& v : views) {
    for (const FailedMove& f : v.failed_moves) {
      if (f.contacts > 0) out.push_back({v.view, f.request_id, f.contacts, f.contact});
    }
    if (v.move && v.move->status == MoveStatus::kReached && v.move->contacts > 0) {
      out.push_back({v.view, v.move->request_id, v.move->contacts, v.move->contact});
    }
  }
  return out;
}

int64_t rig_contact_events(const std::vector<RigContactRecord>& contacts) {
  int64_t n = 0;
  for (const RigContactRecord& c : contacts) n += c.contacts;
  return n;
}

std::string to_string(const RigContactRecord& c) {
  return "view " + std::to_string(c.view + 1) + " (request " + std::to_string(c.request_id) +
         (c.contacts > 1 ? ", " + std::to_string(c.contacts) + " contacts" : "") + "): " + c.contact;
}

std::optional<ScanStop> rule_stop(const ScanSettings& s, const std::vector<ViewRecord>& views, int views_done) {
  if (s.stop_rule == StopRule::kOff) return std::nullopt;
  const std::vector<ViewGain> gains = view_gains(views);
  const std::vector<double> figures = new_percents(gains);
  std::optional<SurfaceStopDecision> d;
  nlohmann::json used;
  if (s.stop_rule == StopRule::kSeconds) {
    d = seconds_stop(gains, s.seconds_rule);
    used = to_json(s.seconds_rule);
    nlohmann::json seconds = nlohmann::json::array();
    for (const ViewGain& g : gains) seconds.push_back(std::isfinite(g.rig_s) ? nlohmann::json(g.rig_s) : nlohmann::json());
    used["rig_s_by_view"] = seconds;  // motion, settle and capture of each view
  } else {
    d = surface_stop(figures, s.surface_rule);
    used = to_json(s.surface_rule);
  }
  if (!d) return std::nullopt;
  used["radius_m"] = s.stop_radius_m;
  used["last_percent_of_model"] = d->last_percent;
  used["percent_of_model_by_view"] = figures;
  return ScanStop{d->reason, views_done, std::string(name_of(s.stop_rule)), used};
}

std::vector<ViewGain> view_gains(const std::vector<ViewRecord>& views) {
  std::vector<ViewGain> out;
  for (const ViewRecord& v : views) {
    if (!v.registration || v.registration->frame_file.empty()) continue;  // never captured or registered
    const RegisteredCloud& r = *v.registration;
    ViewGain g;
    if (r.accepted && r.new_surface) g.new_percent = r.new_surface->percent_of_model();
    if (v.rig_time) g.rig_s = v.rig_time->motion_s + v.rig_time->settle_s + v.rig_time->capture_s;
    out.push_back(g);
  }
  return out;
}

std::vector<double> new_surface_figures(const std::vector<ViewRecord>& views) { return new_percents(view_gains(views)); }

ScanRecord::ScanRecord(fs::path out, const ScanSettings& settings) : out_(std::move(out)) {
  fs::create_directories(out_);
  record_.pbnbv_version = std::string(pbnbv_version());
  record_.settings = settings;
  record_.status.views_planned = settings.views;
}

void ScanRecord::set_ring_plan(double radius_m, double elevation_deg) {
  record_.plan = ScanPlanHeader{"ring", radius_m, elevation_deg, Pose::Identity()};
}

void ScanRecord::set_next_best_view_plan(const std::string& planner, const Pose& initial_view) {
  record_.plan = ScanPlanHeader{planner, 0, 0, initial_view};
}

void ScanRecord::set_mesh(const MeshSummary& mesh) {
  record_.mesh = mesh;
  record_.mesh_error.clear();
}

void ScanRecord::set_no_mesh(const std::string& why) {
  record_.mesh.reset();
  record_.mesh_error = why.empty() ? std::string("no mesh") : why;
}

void ScanRecord::add_view(const ViewRecord& v, int views_done, double elapsed_s) {
  record_.views.push_back(v);
  write("running", "", views_done, elapsed_s);
}

void ScanRecord::continue_from_folder(const std::string& scan_id) {
  const fs::path path = out_ / "scan.json";
  if (!fs::exists(path)) throw std::invalid_argument("cannot resume: " + path.string() + " does not exist");
  const json before = read_scan_json(path);
  if (!before.contains("settings") || !before["settings"].is_object() || before["settings"].value("scan_id", "") != scan_id) {
    throw std::invalid_argument("cannot resume: " + path.string() + " is not a record of scan " + scan_id);
  }
  RecordedScan r = recorded_scan_from_json(before, path.string());
  record_.views = std::move(r.views);
  record_.plan = std::move(r.plan);
  const int views_planned = record_.status.views_planned;
  record_.status = r.status;
  record_.status.views_planned = views_planned;
}

void ScanRecord::set_stop(const ScanStop& stop) { record_.stop = stop; }

void ScanRecord::set_compute_wait(std::size_t index, double compute_s) {
  if (index >= record_.views.size() || !record_.views[index].rig_time) return;
  record_.views[index].rig_time->compute_s = compute_s;
}

void ScanRecord::set_planning_stopped(const PlanRecord& p) { record_.planning_stopped = p; }

void ScanRecord::set_replay_of(const std::string& recorded, int views) {
  record_.replay_of = recorded;
  record_.status.views_planned = views;
}

void ScanRecord::write(const std::string& state, const std::string& message, int views_done, double elapsed_s) {
  ScanStatusRecord& s = record_.status;
  s.state = state;
  s.message = message;
  s.views_done = views_done;
  s.elapsed_s = elapsed_s;
  write_json_atomic(to_json(record_), (out_ / "scan.json").string());
}

}  // namespace pbnbv
