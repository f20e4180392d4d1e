// scan.json read back into the types ScanRecord writes it from (scan_record.hpp): every section
// of a view, the plan, the stop, the mesh and the status, each field checked as it is read; an
// error names the file, the view and the field.
#include <cmath>
#include <cstdio>
#include <type_traits>
#include <stdexcept>
#include <tuple>

#include "core/base/format.hpp"
#include "core/base/units.hpp"
#include "core/io/json.hpp"
#include "core/io/json_fields.hpp"
#include "core/scan/scan_file.hpp"
#include "core/scan/scan_record.hpp"

using nlohmann::json;
namespace fs = std::filesystem;

namespace pbnbv {

namespace {

// The record read field by field (core/io/json_fields.hpp).
using Fields = JsonFields;

// One of an enum's names as to_string writes them.
template <class E, std::size_t N>
E enum_named(const Fields& f, const char* key, const std::array<E, N>& values) {
  const std::string s = f.text(key);
  for (E e : values) {
    if (s == to_string(e)) return e;
  }
  f.fail(key, "'" + s + "' is not one of its names");
}

constexpr std::array<MoveStatus, 7> kMoveStatuses = {MoveStatus::kReached, MoveStatus::kUnreachable, MoveStatus::kTimedOut,
                                                    MoveStatus::kRejected, MoveStatus::kPlanned,     MoveStatus::kBusy,
                                                    MoveStatus::kRigSilent};
constexpr std::array<PlanOutcome, 3> kOutcomes = {PlanOutcome::kView, PlanOutcome::kStop, PlanOutcome::kFailed};

// A move's request id and the contacts the rig reported during it (written since 0.12.0 records
// rig contacts; an earlier record has none: 0 contacts, request 0). The text only with a contact
// counted.
void move_contacts_from(const Fields& m, int64_t* request_id, int32_t* contacts, std::string* contact) {
  if (!m.has("contacts")) return;
  *request_id = m.integer("request_id", 0, int64_t{1} << 62);
  *contacts = static_cast<int32_t>(m.integer("contacts", -1, INT32_MAX));
  *contact = m.text("contact");
  if (*contacts <= 0 && !contact->empty()) m.fail("contact", "is given with contacts " + std::to_string(*contacts));
  if (*contacts > 0 && contact->empty()) m.fail("contact", "is empty with contacts " + std::to_string(*contacts));
}

MoveResult move_from(const Fields& m, const Fields* time) {
  MoveResult r;
  r.status = enum_named(m, "status", kMoveStatuses);
  r.reason = m.text("reason");
  r.reached_object_T_camera = m.pose("reached_object_T_camera");
  r.position_error_m = m.number("position_error_m");
  r.angle_error_rad = deg_to_rad(m.number("angle_error_deg"));
  r.joint_target_rad = m.vector6("joint_target_rad");
  r.joint_position_rad = m.vector6("joint_position_rad");
  r.turntable_target_rad = m.number("turntable_target_rad");
  r.turntable_angle_rad = m.number("turntable_angle_rad");
  if (m.has("route")) r.route = m.text("route");  // pbnbv 0.13.0 on
  move_contacts_from(m, &r.request_id, &r.contacts, &r.contact);
  if (time) {
    r.plan_s = time->number("plan");
    r.move_s = time->number("move");
    r.settle_s = time->number("settle");
    r.rig_motion_s = time->number("rig_motion");
    if (time->has("path_model")) r.path_s = time->number("path_model");
  }
  return r;
}

CaptureResult capture_from(const Fields& c, const Fields& time) {
  CaptureResult r;
  r.ok = c.text("status") == "ok";
  if (!r.ok && c.text("status") != "failed") c.fail("status", "is neither 'ok' nor 'failed'");
  r.request_id = c.integer("request_id", 0, int64_t{1} << 62);
  r.message = c.text("message");
  r.object_T_camera = c.pose("camera_object_T_camera");
  r.joint_position_rad = c.vector6("joint_position_rad");
  r.turntable_angle_rad = c.number("turntable_angle_rad");
  r.depth_frame_seq = c.integer("depth_frame_seq", -1, INT64_MAX);
  r.num_valid_pixels = c.count("num_valid_pixels");
  r.num_cropped = c.count("num_cropped");
  r.capture_s = time.number("capture");
  r.process_s = time.number("cloud");
  return r;
}

RegisteredCloud registration_from(const Fields& g, const Fields& view, const Fields& time) {
  RegisteredCloud r;
  r.accepted = g.flag("accepted");
  r.refined = g.flag("refined");
  r.constraint = g.number("constraint");
  r.reason = g.text("reason");
  r.correction = g.pose("correction");
  r.translation_m = g.number("translation_mm") * 1e-3;
  r.rotation_deg = g.number("rotation_deg");
  r.overlap = g.number("overlap");
  r.rmse_m = g.number("rmse_mm") * 1e-3;
  if (g.has("flagged")) {  // written since pbnbv 0.11 (older records: nothing was flagged)
    r.flagged = g.flag("flagged");
    r.icp_translation_m = g.number("icp_translation_mm") * 1e-3;
    r.icp_rotation_deg = g.number("icp_rotation_deg");
    r.prior_sigmas = g.number("prior_sigmas");
  }
  r.iterations = g.count("iterations");
  r.cloud.object_T_camera = g.pose("registered_object_T_camera");
  r.kinematic_object_T_camera = g.pose("kinematic_object_T_camera");
  r.register_s = time.number("register");
  // What the registration service wrote for the view.
  if (view.has("frame_file")) {
    r.frame_file = view.text("frame_file");
    r.normals_from_depth = view.text("normals") == "depth image";
  }
  if (view.has("depth_file")) r.depth_file = view.text("depth_file");
  if (view.has("new_surface")) {
    const Fields n = view.object("new_surface");
    r.new_surface = NewSurface{n.count("frame_points"), n.count("new_points"), n.count("model_points"), n.number("radius_m")};
  }
  if (time.has("accumulate")) r.accumulate_s = time.number("accumulate");
  return r;
}

VoxelMapSummary map_from(const Fields& m, const Fields& time) {
  VoxelMapSummary r;
  r.updated = m.flag("updated");
  r.message = m.text("message");
  r.resolution_m = m.number("resolution_m");
  r.bbox_min_m = m.vector3("bbox_min_m");
  r.bbox_max_m = m.vector3("bbox_max_m");
  const Fields v = m.object("voxels");
  r.num_none = v.count("none");
  r.num_empty = v.count("empty");
  r.num_occupied = v.count("occupied");
  r.num_unknown = v.count("unknown");
  r.num_frontier = v.count("frontier");
  r.update_s = time.number("map_update");
  return r;
}

EllipsoidSetSummary ellipsoids_from(const Fields& e, double fit_s) {
  EllipsoidSetSummary r;
  r.occupied_components = e.count("occupied_components");
  r.frontier_components = e.count("frontier_components");
  r.fit_s = fit_s;
  const json& list = e.at("list");
  if (!list.is_array()) e.fail("list", "is not a list");
  for (std::size_t k = 0; k < list.size(); ++k) {
    const Fields x(list[k], e.where() + " list[" + std::to_string(k) + "]");
    EllipsoidSummary s;
    s.frontier = x.text("class") == "frontier";
    s.centre_m = x.vector3("centre_m");
    s.semi_axes_m = x.vector3("semi_axes_m");
    const json& q = x.at("quat_wxyz");
    if (!q.is_array() || q.size() != 4) x.fail("quat_wxyz", "is not 4 numbers");
    const std::vector<double> quat = x.list<double>("quat_wxyz");
    for (std::size_t i = 0; i < 4; ++i) s.quat_wxyz[i] = quat[i];
    s.num_voxels = x.count("voxels");
    r.ellipsoids.push_back(s);
  }
  return r;
}

// A "rig_time_s" (a view's or the scan's): each part a duration in seconds or null (not known),
// the total their sum, or null when a part is.
RigTime rig_time_from(const Fields& t) {
  RigTime r;
  const auto part = [&t](const char* key) {
    const double x = t.number(key);
    if (!std::isnan(x) && !(std::isfinite(x) && x >= 0 && x < 1e9)) t.fail(key, "is not a duration in seconds (0..1e9) nor null");
    return x;
  };
  r.motion_s = part("motion");
  r.settle_s = part("settle");
  r.capture_s = part("capture");
  r.compute_s = part("compute");
  const double total = t.number("total");
  const double sum = r.motion_s + r.settle_s + r.capture_s + r.compute_s;
  if (std::isnan(sum) != std::isnan(total) || (!std::isnan(sum) && std::abs(total - sum) > 1e-9 * std::max(1.0, sum))) {
    t.fail("total", "is " + (std::isnan(total) ? std::string("null") : fmt::format("{}", total)) +
                        ", not motion + settle + capture + compute = " +
                        (std::isnan(sum) ? std::string("null (a part is null)") : fmt::format("{}", sum)));
  }
  return r;
}

}  // namespace

PlanRecord plan_record_from_json(const json& j, const std::string& where) {
  const Fields f(j, where);
  PlanRecord r;
  ViewPlan& p = r.plan;
  p.planner = parse_name<PlannerKind>(f.text("planner"));
  p.outcome = enum_named(f, "outcome", kOutcomes);
  p.reason = f.text("reason");
  p.ranking = parse_name<Ranking>(f.text("ranking"));
  r.map_of_view = static_cast<int>(f.integer("map_of_view", 0, kViews.max)) - 1;  // from 1 as "view"; 0: not known
  p.view_quality = f.number("view_quality_px");
  p.first_quality = f.number("first_quality_px");
  p.frontier_area_px = f.number("frontier_area_px");
  p.occupied_area_px = f.number("occupied_area_px");
  p.partition = static_cast<int>(f.integer("partition", -1, 1000));
  p.allowed_sectors = f.list<int>("allowed_sectors");
  p.partition_fallback = f.flag("partition_fallback");
  const Fields sphere = f.object("sphere");
  p.sphere_centre_m = sphere.vector3("centre_m");
  p.sphere_radius_m = sphere.number("radius_m");
  const Fields c = f.object("candidates");
  p.num_candidates = c.count("generated");
  p.num_unreachable = c.count("unreachable");
  p.num_excluded = c.count("excluded");
  p.num_scored = c.count("scored");
  p.alternative_quality = f.list<double>("alternative_quality_px");
  if (p.outcome == PlanOutcome::kView) p.object_T_camera = f.pose("object_T_camera");
  const Fields t = f.object("time_ms");
  r.map_update_s = t.number("map_update") * 1e-3;
  p.candidates_s = t.number("candidates") * 1e-3;
  p.reachability_s = t.number("reachability") * 1e-3;
  p.scoring_s = t.number("scoring") * 1e-3;
  p.wait_s = t.number("scorer_wait") * 1e-3;
  p.plan_s = t.number("view_selection") * 1e-3;
  // The view it plans: its figure is plans/view_NNN.png, NNN that view's number (from 1).
  const std::string figure = f.text("figure");
  int n = 0;
  if (figure.size() > 32 || std::sscanf(figure.c_str(), "plans/view_%d.png", &n) != 1 || n < 1 || n > kViews.max ||
      figure != "plans/" + view_file(n - 1, "png")) {
    f.fail("figure", "'" + figure + "' is not plans/view_NNN.png");
  }
  p.iteration = n - 1;
  if (f.has("ellipsoids")) r.ellipsoids = ellipsoids_from(f.object("ellipsoids"), t.number("ellipsoid_fit") * 1e-3);
  return r;
}

ViewRecord view_record_from_json(const json& j, const std::string& where) {
  const Fields f(j, where);
  ViewRecord v;
  v.view = static_cast<int>(f.integer("view", 1, kViews.max)) - 1;  // counted from 1 in the file (format 2)
  const Fields view(j, where + " view " + std::to_string(v.view + 1));
  const json no_times = json::object();
  const Fields time(f.has("time_s") ? f.at("time_s") : no_times, view.where() + " time_s");
  if (view.has("plan")) {
    const Fields p = view.object("plan");
    if (p.text("planner") == "initial view") {
      v.initial_view = true;
    } else {
      v.plan = plan_record_from_json(view.at("plan"), view.where() + " plan");
    }
  }
  if (view.has("option")) {
    v.option = static_cast<int>(view.integer("option", 0, 1000));
    v.requested_object_T_camera = view.pose("requested_object_T_camera");
  }
  if (view.has("failed_moves")) {
    const json& list = view.at("failed_moves");
    if (!list.is_array()) view.fail("failed_moves", "is not a list");
    for (std::size_t k = 0; k < list.size(); ++k) {
      const Fields m(list[k], view.where() + " failed_moves[" + std::to_string(k) + "]");
      FailedMove failed;
      failed.option = static_cast<int>(m.integer("option", 0, 1000));
      failed.object_T_camera = m.pose("object_T_camera");
      failed.status = enum_named(m, "status", kMoveStatuses);
      failed.reason = m.text("reason");
      move_contacts_from(m, &failed.request_id, &failed.contacts, &failed.contact);
      v.failed_moves.push_back(failed);
    }
  }
  if (view.has("move")) {
    const Fields m = view.object("move");
    if (m.text("status") == "no_answer") {
      v.move_unanswered = true;
    } else {
      v.move = move_from(m, &time);
      v.move_round_trip_s = time.number("move_round_trip");
    }
  }
  if (view.has("capture")) {
    const Fields c = view.object("capture");
    if (c.text("status") == "no_answer") {
      v.capture_unanswered = true;
    } else {
      v.capture = capture_from(c, time);
      v.capture_points = static_cast<std::size_t>(c.integer("num_points", 0, INT32_MAX));
      v.capture_round_trip_s = time.number("capture_round_trip");
    }
  }
  if (view.has("registration")) {
    v.registration = registration_from(view.object("registration"), view, time);
    v.register_round_trip_s = time.number("register_round_trip");
    if (view.has("frame_file")) view_frame_file(j, where);  // the view's own file, or refused
    if (view.has("depth_file") && view.text("depth_file") != depth_file_of(v.view)) {
      view.fail("depth_file", "is not " + depth_file_of(v.view));
    }
  }
  if (view.has("map")) {
    v.map = map_from(view.object("map"), time);
    v.map_round_trip_s = time.number("map_round_trip");
    v.view_total_s = time.number("view_total");
  }
  if (view.has("rig_time_s")) v.rig_time = rig_time_from(view.object("rig_time_s"));  // none in older records
  return v;
}

ScanStop scan_stop_from_json(const json& j, const std::string& where) {
  const Fields f(j, where);
  ScanStop s{f.text("reason"), static_cast<int>(f.integer("after_views", 0, kViews.max)), f.text("rule"), json()};
  if (f.has("figures")) s.figures = f.at("figures");
  return s;
}

MeshSummary mesh_summary_from_json(const json& j, const std::string& where) {
  const Fields f(j, where);
  MeshSummary m;
  const std::string method = f.text("method");
  if (method != "tsdf" && method != "poisson") f.fail("method", "is neither 'tsdf' nor 'poisson'");
  m.tsdf = method == "tsdf";
  m.files = {f.text("file")};
  for (const auto& also : f.list<std::string>("also")) m.files.push_back(also);
  m.frames = static_cast<std::size_t>(f.count("frames"));
  m.points = static_cast<std::size_t>(f.integer("points", 0, INT64_MAX));
  m.vertices = static_cast<std::size_t>(f.integer("vertices", 0, INT64_MAX));
  m.triangles = static_cast<std::size_t>(f.integer("triangles", 0, INT64_MAX));
  m.watertight = f.flag("watertight");
  m.boundary_loops = static_cast<std::size_t>(f.integer("boundary_loops", 0, INT64_MAX));
  m.boundary_edges = static_cast<std::size_t>(f.integer("boundary_edges", 0, INT64_MAX));
  m.non_manifold_edges = static_cast<std::size_t>(f.integer("non_manifold_edges", 0, INT64_MAX));
  m.hole_boundary_length_m = f.number("hole_boundary_length_m");
  m.area_m2 = f.number("area_m2");
  if (f.has("volume_m3")) m.volume_m3 = f.number("volume_m3");
  m.small_fragments_removed_triangles = static_cast<std::size_t>(f.integer("small_fragments_removed_triangles", 0, INT64_MAX));
  m.holes_filled = static_cast<std::size_t>(f.integer("holes_filled", 0, INT64_MAX));
  m.fill_holes_m = f.number("fill_holes_m");
  m.seconds = f.number("seconds");
  const Fields s = f.object("settings");
  if (m.tsdf) {
    m.voxel_m = s.number("voxel_m");
    m.truncation_m = s.number("truncation_m");
    m.image_scale = static_cast<int>(s.integer("image_scale", 1, 1 << 16));
    m.voxels = static_cast<std::size_t>(s.integer("voxels", 0, INT64_MAX));
  } else {
    m.poisson_depth = static_cast<int>(s.integer("poisson_depth", 1, 16));
  }
  return m;
}

RecordedScan recorded_scan_from_json(const json& j, const std::string& where) {
  const Fields f(j, where);
  RecordedScan r;
  r.pbnbv_version = f.text("pbnbv_version");
  try {
    r.settings = scan_settings_from_json(f.at("settings"));
  } catch (const std::exception& e) {
    throw std::invalid_argument(where + " settings: " + e.what());
  }
  if (f.has("plan")) {
    const Fields p = f.object("plan");
    ScanPlanHeader h;
    h.planner = p.text("planner");
    if (h.planner == "ring") {
      h.radius_m = p.number("radius_m");
      h.elevation_deg = p.number("elevation_deg");
    } else {
      h.initial_view = p.pose("initial_view");
    }
    r.plan = h;
  }
  const json& views = f.at("views");
  if (!views.is_array()) f.fail("views", "is not a list");
  for (std::size_t k = 0; k < views.size(); ++k) {
    r.views.push_back(view_record_from_json(views[k], where + " views[" + std::to_string(k) + "]"));
  }
  if (f.has("rig_time_s")) {  // the views' sums (none in older records), checked against them
    const Fields t = f.object("rig_time_s");
    const RigTime written = rig_time_from(t);
    const RigTimeSum sum = sum_rig_time(r.views);
    for (const auto& [key, a, b] : {std::tuple{"motion", written.motion_s, sum.sum.motion_s},
                                    std::tuple{"settle", written.settle_s, sum.sum.settle_s},
                                    std::tuple{"capture", written.capture_s, sum.sum.capture_s},
                                    std::tuple{"compute", written.compute_s, sum.sum.compute_s}}) {
      if (!(std::abs(a - b) <= 1e-6 * std::max(1.0, b))) {
        t.fail(key, fmt::format("is {}, not the views' sum {}", a, b));
      }
    }
    if (t.count("views") != sum.views) t.fail("views", fmt::format("is {}, not the {} views with a rig_time_s", t.count("views"), sum.views));
    if (t.count("views_incomplete") != sum.views_incomplete) {
      t.fail("views_incomplete", fmt::format("is {}, not the {} views with a part null", t.count("views_incomplete"), sum.views_incomplete));
    }
  }
  if (f.has("stop")) r.stop = scan_stop_from_json(f.at("stop"), where + " stop");
  if (f.has("planning_stopped")) r.planning_stopped = plan_record_from_json(f.at("planning_stopped"), where + " planning_stopped");
  if (f.has("replay_of")) r.replay_of = f.text("replay_of");
  if (f.has("mesh")) {
    const Fields m = f.object("mesh");
    if (m.has("error")) {
      r.mesh_error = m.text("error");
    } else {
      r.mesh = mesh_summary_from_json(f.at("mesh"), where + " mesh");
    }
  }
  if (f.has("rig_contacts")) {  // (an earlier record has none) the views' moves with contacts, in order
    const json& list = f.at("rig_contacts");
    if (!list.is_array()) f.fail("rig_contacts", "is not a list");
    const std::vector<RigContactRecord> expected = rig_contacts(r.views);
    for (std::size_t k = 0; k < list.size(); ++k) {
      const Fields c(list[k], where + " rig_contacts[" + std::to_string(k) + "]");
      const RigContactRecord read{static_cast<int>(c.integer("view", 1, kViews.max)) - 1,
                                  c.integer("request_id", 0, int64_t{1} << 62),
                                  static_cast<int32_t>(c.integer("contacts", 1, INT32_MAX)), c.text("contact")};
      if (k >= expected.size() || !(read == expected[k])) {
        c.fail("", k < expected.size()
                       ? "is not what the views record for it (view " + std::to_string(expected[k].view + 1) +
                             ", request " + std::to_string(expected[k].request_id) + ", " +
                             std::to_string(expected[k].contacts) + " contacts, '" + expected[k].contact + "')"
                       : "is one more than the " + std::to_string(expected.size()) + " moves with contacts the views record");
      }
    }
    if (list.size() < expected.size()) {
      f.fail("rig_contacts", "lists " + std::to_string(list.size()) + " moves with contacts, the views have " +
                                 std::to_string(expected.size()));
    }
  }
  const Fields s = f.object("status");
  r.status.state = s.text("state");
  r.status.message = s.text("message");
  r.status.views_done = static_cast<int>(s.integer("views_done", 0, kViews.max));
  r.status.views_planned = static_cast<int>(s.integer("views_planned", 0, kViews.max));
  r.status.elapsed_s = s.number("elapsed_s");
  r.status.num_points = static_cast<std::size_t>(s.integer("num_points", 0, int64_t{1} << 40));
  r.status.next_request_id = s.integer("next_request_id", 0, int64_t{1} << 62);
  r.status.answers_refused = static_cast<int>(s.integer("answers_refused", 0, INT32_MAX));
  return r;
}

RecordedScan read_scan_record(const fs::path& scan_json_or_folder) {
  const fs::path path = fs::is_directory(scan_json_or_folder) ? scan_json_or_folder / "scan.json" : scan_json_or_folder;
  return recorded_scan_from_json(read_scan_json(path), path.string());
}

std::vector<MergedFrame> merged_frames(const RecordedScan& scan, const fs::path& dir) {
  std::vector<MergedFrame> frames;
  for (const ViewRecord& v : scan.views) {
    if (!v.registration || !v.registration->accepted || v.registration->frame_file.empty()) continue;
    frames.push_back({v.view, dir / v.registration->frame_file, v.registration->cloud.object_T_camera});
  }
  if (frames.empty()) throw std::invalid_argument((dir / "scan.json").string() + ": no accepted view to mesh");
  return frames;
}

std::vector<std::vector<Pose>> recorded_attempts(const RecordedScan& scan) {
  std::vector<std::vector<Pose>> attempts;
  for (const ViewRecord& v : scan.views) {
    std::vector<Pose> poses;
    for (const FailedMove& f : v.failed_moves) poses.push_back(f.object_T_camera);
    if (v.option) poses.push_back(v.requested_object_T_camera);
    attempts.push_back(std::move(poses));
  }
  return attempts;
}

void write_scan_mesh(const fs::path& dir, const MeshSummary& mesh) {
  RecordedScan r = read_scan_record(dir);
  r.mesh = mesh;
  r.mesh_error.clear();
  write_json_atomic(to_json(r), (dir / "scan.json").string());
}

json to_json(const RecordedScan& r) {
  json j;
  j["format_version"] = kScanFormatVersion;
  j["pbnbv_version"] = r.pbnbv_version;
  j["settings"] = to_json(r.settings);
  j["views"] = json::array();
  for (const ViewRecord& v : r.views) j["views"].push_back(to_json(v));
  j["rig_contacts"] = json::array();
  for (const RigContactRecord& c : rig_contacts(r.views)) {
    j["rig_contacts"].push_back(
        {{"view", c.view + 1}, {"request_id", c.request_id}, {"contacts", c.contacts}, {"contact", c.contact}});
  }
  if (r.plan && r.plan->planner == "ring") {
    j["plan"] = {{"planner", "ring"}, {"radius_m", r.plan->radius_m}, {"elevation_deg", r.plan->elevation_deg}};
  } else if (r.plan) {
    j["plan"] = {{"planner", r.plan->planner}, {"initial_view", to_json(r.plan->initial_view)}};
  }
  const RigTimeSum rig = sum_rig_time(r.views);
  j["rig_time_s"] = rig_time_json(rig.sum);
  j["rig_time_s"]["views"] = rig.views;
  j["rig_time_s"]["views_incomplete"] = rig.views_incomplete;
  if (r.stop) j["stop"] = to_json(*r.stop);
  if (r.planning_stopped) j["planning_stopped"] = to_json(*r.planning_stopped);
  if (!r.replay_of.empty()) j["replay_of"] = r.replay_of;
  if (r.mesh) j["mesh"] = to_json(*r.mesh);
  if (!r.mesh_error.empty()) j["mesh"] = {{"error", r.mesh_error}};
  const ScanStatusRecord& s = r.status;
  j["status"] = {{"state", s.state},         {"message", s.message},     {"views_done", s.views_done},
                 {"views_planned", s.views_planned}, {"elapsed_s", s.elapsed_s}, {"num_points", s.num_points},
                 {"next_request_id", s.next_request_id}, {"answers_refused", s.answers_refused}};
  return j;
}

}  // namespace pbnbv
