// `pbnbv scan` (commands.hpp).
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cctype>
#include <ctime>
#include <iostream>
#include <map>
#include <thread>

#include "bus/bus.hpp"
#include "bus/log_audit.hpp"
#include "bus/scan_log_views.hpp"
#include "bus/rig_log.hpp"
#include "pbnbv/heartbeat_t.hpp"
#include "core/base/format.hpp"
#include "core/base/signals.hpp"
#include "core/geometry/mesh.hpp"
#include "core/io/json.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/mesh_file.hpp"
#include "core/surface/mesh_topology.hpp"
#include "core/scan/scan_file.hpp"
#include "eval/bench.hpp"
#include "eval/evaluate.hpp"
#include "eval/objects.hpp"
#include "launcher/commands.hpp"
#include "launcher/external_rig.hpp"
#include "launcher/scan_processes.hpp"
#include "pbnbv/stop_request_t.hpp"
#include "launcher/supervise.hpp"
#include "process/processes.hpp"

namespace fs = std::filesystem;

namespace pbnbv::launcher {

namespace {

// processes.json: the launcher and every process it started, with PIDs and restarts (written at start, so
// what runs can be found and stopped even if the launcher is gone) and, once stopped, how each
// ended (exit_code: exit status, or 128 + signal; null while running).
// How the launcher watches a process: restarts so far, when it was (re)started, when its
// heartbeat was last heard (-1: not yet since the start).
struct Watch {
  int restarts = 0;
  double started_s = 0;
  double heard_s = -1;
};
constexpr int kMaxRestarts = 3;
constexpr double kSilentS = 10.0;
constexpr double kFirstHeartbeatS = 90.0;

nlohmann::json processes_json(const std::string& scan_id, const std::vector<process::Child>& children,
                              const std::map<std::string, Watch>& watch = {}) {
  nlohmann::json procs = nlohmann::json::array();
  for (const auto& c : children) {
    const auto w = watch.find(c.name);
    procs.push_back({{"name", c.name},
                     {"restarts", w == watch.end() ? 0 : w->second.restarts},
                     {"pid", c.pid},
                     {"argv", c.argv},
                     {"log", c.log_path},
                     {"running", c.running},
                     {"exit_code", c.running || c.pid < 0 ? nlohmann::json(nullptr) : nlohmann::json(c.exit_code)}});
  }
  return {{"scan_id", scan_id}, {"launcher_pid", static_cast<int>(::getpid())}, {"processes", procs}};
}

// Writes processes.json, the record of what runs; a failure to write it (a full disk) is said and
// does not stop the scan: the coordinator's scan.json says what became of the scan.
void record_processes(const fs::path& out, const nlohmann::json& procs) {
  try {
    write_json_atomic(procs, (out / "processes.json").string());
  } catch (const std::exception& e) {
    std::cerr << "warning: " << e.what() << std::endl;
  }
}

// How a process ended, for people: "exit status 3", "killed by signal 9 (SIGKILL)".
std::string how_it_ended(int exit_code) {
  if (exit_code > 128) {
    const int sig = exit_code - 128;
    const char* name = sigabbrev_np(sig);
    return "killed by signal " + std::to_string(sig) + (name ? std::string(" (SIG") + name + ")" : "");
  }
  return "exit status " + std::to_string(exit_code);
}

// scan.json always ends in a final state: when the coordinator could not write it (it died, or
// was stopped because another process died), the launcher does, naming the cause.
void finish_record(const fs::path& out, const std::string& state, const std::string& cause) {
  // The coordinator died holding its disk reserve: free it, so the record fits on a full disk.
  std::error_code ignored;
  fs::remove(out / "state" / "coordinator.reserve", ignored);
  try {
    write_scan_state(out, state, cause);
  } catch (const std::exception& e) {
    std::cerr << "error: the scan " << state << " (" << cause << ") and this cannot be recorded: " << e.what() << std::endl;
  }
}

// Says whether scan.lcmlog holds every DEPTH_FRAME, CLOUD, REGISTERED_CLOUD and VOXEL_MAP of the
// views scan.json recorded.
void audit_log(const fs::path& out, const std::string& scan_id) {
  try {
    const std::vector<std::string> files = bus::scan_log_files(out.string());  // scan.lcmlog, .NN after restarts
    const bus::LogContents log = bus::read_scan_logs(files, scan_id);
    const RecordedScan scan = read_scan_record(out);
    const std::vector<std::string> missing = bus::missing_from_log(log, bus::view_messages(scan));
    const std::size_t views = scan.views.size();
    if (missing.empty()) {
      std::cout << "scan.lcmlog" << (files.size() > 1 ? " (" + std::to_string(files.size()) + " files)" : "") << ": "
                << log.events << " messages, every depth frame, cloud, registered cloud and map of the "
                << views << " views" << std::endl;
      return;
    }
    std::string list;
    for (std::size_t i = 0; i < missing.size() && i < 8; ++i) list += "\n    " + missing[i];
    std::cerr << "warning: scan.lcmlog lacks " << missing.size() << " of the scan's messages (lost by lcm-logger):" << list
              << (missing.size() > 8 ? "\n    ..." : "") << std::endl;
  } catch (const std::exception& e) {
    std::cerr << "warning: scan.lcmlog not checked: " << e.what() << std::endl;
  }
}

// The kernel's cap on a socket's receive buffer: LCM asks for 8 MB (a depth frame is 1.8 MB of
// UDP fragments); a smaller cap loses fragments under load.
void warn_small_receive_buffer() {
  std::ifstream in("/proc/sys/net/core/rmem_max");
  long bytes = 0;
  if (!(in >> bytes) || bytes >= 8 * 1024 * 1024) return;
  std::cerr << "warning: the kernel caps UDP receive buffers at " << bytes / 1024
            << " kB (net.core.rmem_max); depth frames may be lost and re-requested. As root: "
               "sysctl -w net.core.rmem_max=67108864 (README, 'Networking')"
            << std::endl;
}

// What a process gets when the launcher dies (PR_SET_PDEATHSIG): SIGTERM for the two that write
// their record on the way out (the coordinator's scan.json, lcm-logger's log), SIGKILL for the rest.
int death_signal_of(const std::string& name) { return name == "lcm-logger" || name == "coordinator" ? SIGTERM : SIGKILL; }

// A process started again for the same scan (a restart, a resume) continues it: the coordinator
// from scan.json (--resume), lcm-logger into the next free scan.lcmlog.NN (-i), each log appended.
// Idempotent: an argument already there (an earlier restart) is not added twice.
void continue_scan(process::Child& c) {
  const auto has = [&](const char* arg) { return std::find(c.argv.begin(), c.argv.end(), arg) != c.argv.end(); };
  if (c.name == "coordinator" && !has("--resume")) c.argv.push_back("--resume");
  if (c.name == "lcm-logger" && !has("-i")) c.argv.insert(c.argv.begin() + 1, "-i");
  c.append_log = true;
}

// Stops every process, lcm-logger last: it writes what it has queued only while it runs, and under
// load it is seconds behind the bus (the twin's statuses at sim speed 20 are 4,000 messages/s),
// so it is stopped once the others are and its file has stopped growing (0.3 s unchanged, at most
// kLoggerDrainS); stopped with the rest, it lost the last view's frame, cloud and map.
constexpr double kLoggerDrainS = 3.0;
void stop_logger_last(std::vector<process::Child>& children, const fs::path& out) {
  const auto logger = std::find_if(children.begin(), children.end(), [](const process::Child& c) {
    return c.name == "lcm-logger" && c.running;
  });
  if (logger == children.end()) return process::stop_all(children, 5.0);
  std::vector<process::Child> rest;
  for (auto& c : children) {
    if (&c != &*logger) rest.push_back(c);
  }
  process::stop_all(rest, 5.0);
  const auto log_size = [&] {
    const std::vector<std::string> files = bus::scan_log_files(out.string());
    std::error_code ec;
    return files.empty() ? std::uintmax_t{0} : fs::file_size(files.back(), ec);
  };
  std::uintmax_t size = log_size();
  int unchanged = 0;
  for (const double end = bus::now_s() + kLoggerDrainS; unchanged < 3 && bus::now_s() < end;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const std::uintmax_t now = log_size();
    unchanged = now == size ? unchanged + 1 : 0;
    size = now;
  }
  std::vector<process::Child> last = {*logger};
  process::stop_all(last, 5.0);
  std::size_t k = 0;
  for (auto& c : children) c = &c == &*logger ? last.front() : rest[k++];
}

}  // namespace

void send_stop(bus::Bus& bus, const std::string& scan_id, const std::string& reason) {
  stop_request_t stop;
  stop.scan_id = scan_id;
  stop.reason = reason;
  for (int i = 0; i < 3; ++i) {
    stop.utime = bus::now_utime();
    bus.publish(channels::kStop, stop);
    bus.spin_once(100);
  }
}

// The local date and time as 20250131-142501 (folder names and scan ids).
std::string timestamp() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  localtime_r(&t, &tm);
  char b[32];
  std::strftime(b, sizeof(b), "%Y%m%d-%H%M%S", &tm);
  return b;
}

// A scan's folder: created if missing; one that holds anything is refused (a new scan would mix
// its files with the old run's) unless `overwrite`, which empties it first.
void prepare_out(const fs::path& out, bool overwrite) {
  if (fs::exists(out) && !fs::is_directory(out)) {
    throw std::invalid_argument("--out " + out.string() + " is a file, not a folder");
  }
  if (fs::exists(out) && !fs::is_empty(out)) {
    if (!overwrite) {
      std::string some;
      int n = 0;
      for (const auto& e : fs::directory_iterator(out)) {
        if (n++ < 4) some += (some.empty() ? "" : ", ") + e.path().filename().string();
      }
      throw std::invalid_argument("--out " + out.string() + " is not empty (" + some + (n > 4 ? ", ..." : "") +
                                  "): give a new folder, or --overwrite to delete what it holds");
    }
    for (const auto& e : fs::directory_iterator(out)) fs::remove_all(e.path());
  }
  fs::create_directories(out / "logs");
}

process::Child scan_process(const std::string& name, std::vector<std::string> argv, const ScanSettings& s,
                            const fs::path& out, bool progress) {
  process::Child c;
  c.name = name;
  c.argv = std::move(argv);
  if (name != "lcm-logger" && name != "coordinator") c.argv.insert(c.argv.end(), {"--scan", s.scan_id});
  c.death_signal = death_signal_of(name);
  c.log_path = (out / "logs" / (name + ".log")).string();
  c.stdout_to_terminal = progress;
  return c;
}

void add_services(std::vector<process::Child>& children, const ScanSettings& s, const fs::path& out, const fs::path& bin,
                  bool registration, const std::vector<std::string>& coordinator_extra, bool on_rig_host,
                  LengthUnit mesh_units) {
  auto add = [&](const std::string& name, std::vector<std::string> argv, bool progress = false) {
    children.push_back(scan_process(name, std::move(argv), s, out, progress));
  };
  if (!on_rig_host) {  // else they run on the rig's computer (pbnbv rig-host)
    add("motion", {(bin / "pbnbv-motion").string(), "--model", s.rig_model_path});
    add("camera", {(bin / "pbnbv-camera").string(), "--model", s.rig_model_path});
    if (!s.depth_filter) children.back().argv.push_back("--no-depth-filter");
  }
  // The model (cloud.ply) at the scan's cloud voxel, its new surface at the stop rule's radius.
  add("registration", {(bin / "pbnbv-registration").string(), "--out", out.string(), "--model-voxel", exact(s.voxel_m),
                       "--new-surface-radius", exact(s.stop_radius_m), "--pose-sigma-mm", exact(s.pose_sigma_m * 1e3),
                       "--pose-sigma-deg", exact(s.pose_sigma_deg), "--icp-voxel", exact(s.icp_voxel_m), "--map-pose",
                       std::string(name_of(s.map_pose))});
  if (!registration) children.back().argv.push_back("--off");
  if (mesh_units != LengthUnit::kMetre) children.back().argv.insert(children.back().argv.end(), {"--units", unit_symbol(mesh_units)});
  // The map's working volume: the cloud's crop box, above the turntable top.
  Eigen::Vector3d volume_min = s.crop_min_m;
  if (s.rig == RigKind::kArm) volume_min.z() = std::max(volume_min.z(), -s.object_z_m + s.ground_clearance_m);
  auto vec = [&](const Eigen::Vector3d& v) { return exact(v.x()) + "," + exact(v.y()) + "," + exact(v.z()); };
  add("mapping", {(bin / "pbnbv-mapping").string(), "--resolution", exact(s.map_resolution_m), "--out", out.string(),
                  "--volume-min", vec(volume_min), "--volume-max", vec(s.crop_max_m), "--frontier-empty",
                  std::string(name_of(frontier_empty(s.planner))), "--map-pose", std::string(name_of(s.map_pose))});
  if (!s.depth_filter) children.back().argv.push_back("--no-depth-filter");
  if (uses_ellipsoids(s.planner)) add("ellipsoids", {(bin / "pbnbv-ellipsoids").string(), "--tmax", std::to_string(s.t_max)});
  // The scorer draws each plan into out/plans/ (its own --out: no path comes from the bus).
  if (uses_view_scorer(s.planner)) {
    add("scorer", {(bin / "pbnbv-scorer").string(), "--model", s.rig_model_path, "--out", out.string()});
  }
  if (uses_truth(s.planner)) {
    // The oracle chooses by the true surface: the twin's object, written to the scan folder.
    const fs::path truth = out / "object.stl";
    if (!fs::exists(truth)) {
      throw std::invalid_argument("--planner oracle needs the object's true mesh (" + truth.string() +
                                  ", written for a twin scan): it is the benchmark's yardstick, not a planner for an "
                                  "unknown object");
    }
    children.back().argv.insert(children.back().argv.end(), {"--truth-mesh", truth.string()});
  }
  std::vector<std::string> coordinator = {(bin / "pbnbv-coordinator").string(), "--out", out.string()};
  coordinator.insert(coordinator.end(), coordinator_extra.begin(), coordinator_extra.end());
  add("coordinator", coordinator, true);
}

namespace {

// The per-vertex colours of an object's mesh file (PLY red green blue), or none.
std::vector<Rgb> object_colours(const eval::ObjectSpec& object) {
  std::string ext = fs::path(object.source).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".ply" || !fs::is_regular_file(object.source)) return {};
  return read_ply_colours(object.source, object.mesh.vertices.size());
}

// What an object of radius `radius_m` about the turntable axis, from `bottom_z_m` to `top_z_m`
// (object frame, object_z_m above the platter), would strike turning on the rig's turntable, and
// the largest factor by which it could be scaled (about the platter's centre, standing on it) to
// turn clear (bisection; 0: nothing clears).
struct TurningCheck {
  std::vector<std::string> parts;
  double clear_scale = 1;
};
TurningCheck turning_check(const RigModel& rig, double radius_m, double bottom_z_m, double top_z_m, double object_z_m) {
  ReachabilityChecker checker(rig);
  const auto hit = [&](double k) { return checker.turning_collisions(k * radius_m, k * bottom_z_m, k * top_z_m, k * object_z_m); };
  TurningCheck c;
  c.parts = hit(1.0);
  if (c.parts.empty()) return c;
  double clear = 0, strikes = 1;
  for (int i = 0; i < 30; ++i) {
    const double k = 0.5 * (clear + strikes);
    (hit(k).empty() ? clear : strikes) = k;
  }
  c.clear_scale = clear;
  return c;
}

// Refuses, before anything starts, an object that turned on the turntable would strike the rig's
// fixed parts (an object too wide for the rig jams against the pedestal): the cylinder about the
// turntable axis through the mesh's farthest vertex, as tall as the object stands. Names the parts,
// the object's reach and the largest --size that turns clear.
void check_object_turns_clear(const TriangleMesh& mesh, const ScanSettings& s, const std::string& what) {
  if (s.rig != RigKind::kArm || mesh.vertices.empty()) return;
  double radius = 0, bottom = mesh.vertices[0].z(), top = bottom;
  for (const Eigen::Vector3d& v : mesh.vertices) {
    radius = std::max(radius, std::hypot(v.x(), v.y()));
    bottom = std::min(bottom, v.z());
    top = std::max(top, v.z());
  }
  const RigModel rig = load_rig(s.rig_model_path);
  const TurningCheck c = turning_check(rig, radius, bottom, top, s.object_z_m);
  if (c.parts.empty()) return;
  const double size = s.normalisation.extent_m.minCoeff();
  const double fits = std::floor(100 * c.clear_scale * size) / 100;
  throw std::invalid_argument(fmt::format(
      "{}, turned on the turntable, would strike the rig's {} ({}): it reaches {:.3f} m from the turntable axis (its "
      "farthest point) and stands {:.3f} m tall; {}",
      what, fmt::join(c.parts, ", "), rig.model_path, radius, top - bottom,
      fits >= 0.01 ? fmt::format("at --size {:.2f} or less (now {:.2f}) it turns clear", fits, size)
                   : std::string("nothing of this shape turns clear: check the rig file")));
}

// The same for an external rig's working volume, turned: its cylinder, or the one through the
// box's corners.
void check_working_volume_turns_clear(const RigModel& rig, const ScanSettings& s) {
  const WorkingVolume& v = *s.working_volume;
  const Eigen::AlignedBox3d b = v.bounds();
  const double radius = v.shape == WorkingVolume::Shape::kCylinder
                            ? v.radius_m
                            : std::hypot(std::max(-b.min().x(), b.max().x()), std::max(-b.min().y(), b.max().y()));
  const TurningCheck c = turning_check(rig, radius, b.min().z(), b.max().z(), s.object_z_m);
  if (c.parts.empty()) return;
  throw std::invalid_argument(fmt::format(
      "the working volume {}, turned on the turntable, would strike the rig's {} ({}): an object filling it would "
      "jam; give a smaller --working-volume or pbnbv_working_volume in the rig file ({:.0f} % of it turns clear)",
      v.to_text(), fmt::join(c.parts, ", "), rig.model_path, 100 * c.clear_scale));
}

}  // namespace

int resume_scan(const fs::path& dir, const fs::path& bin);
int run_external_scan(const ScanOptions& o, const fs::path& bin);

int run_scan(const ScanOptions& o, const fs::path& bin) {
  if (!o.resume.empty()) return resume_scan(o.resume, bin);
  if (o.external_rig) return run_external_scan(o, bin);
  ScanSettings s = o.settings;
  eval::ObjectSpec object = eval::resolve_object(o.object);
  const std::string object_name = object.name;
  TriangleMesh& mesh = object.mesh;
  s.normalisation = normalise_mesh(mesh, o.size_m, o.up.value_or(object.up));
  s.normalisation.source_path = object.source;
  check_object_limits(mesh, s.normalisation, "the object '" + object.source + "'", true);
  s.object_name = object_name;
  s.scan_id = new_scan_id(object_name);
  // By default a new folder named after the object, the time and the scan id's last 4 digits
  // (two scans started in the same second do not share it).
  const fs::path out = fs::absolute(
      o.out.empty() ? "out/" + object_name + "-" + timestamp() + "-" + s.scan_id.substr(s.scan_id.size() - 4) : o.out);

  // The object rests on the turntable (arm rig) or floats at the origin (free rig).
  place_object(s);
  check_object_turns_clear(mesh, s, "the object '" + object.source + "'");

  prepare_out(out, o.overwrite);
  const std::string stl = (out / "object.stl").string();
  write_stl_binary(mesh, stl);
  write_obj(mesh, (out / "object.obj").string());
  // A mesh with vertex colours (PLY) is also written with them, for the twin to draw it in them.
  if (const std::vector<Rgb> colours = object_colours(object); !colours.empty()) {
    write_mesh_ply(mesh, vertex_normals(mesh), (out / "object.ply").string(), colours);
  }
  const LaunchSettings launch = launch_settings_of(o);
  write_scan_settings(s, launch, out);

  std::cout << "pbnbv scan: " << object_name << " (" << s.normalisation.num_triangles << " triangles, "
            << s.normalisation.extent_m.x() << " x " << s.normalisation.extent_m.y() << " x "
            << s.normalisation.extent_m.z() << " m) on the " << to_string(s.rig) << " rig, " << s.views
            << " " << name_of(s.planner) << " views -> " << out.string() << " (scan " << s.scan_id << ")" << std::endl;
  warn_small_receive_buffer();

  std::vector<process::Child> children = scan_processes(s, launch, out, bin);
  return supervise(children, s, out, launch.record_log, true, launch.surface_metrics);
}

// An external-rig scan: the drivers are checked (nothing moves), the first views planned and their
// reachability checked, then every process but a twin is started; the object is unknown.
int run_external_scan(const ScanOptions& o, const fs::path& bin) {
  ScanSettings s = o.settings;
  const RigModel rig = load_rig(s.rig_model_path);
  s.object_name = "unknown";
  s.scan_id = new_scan_id("scan");
  place_object(s);  // in the working volume
  check_working_volume_turns_clear(rig, s);
  std::cout << "pbnbv scan: an unknown object in the working volume " << s.working_volume->to_text() << " of the rig "
            << rig.model_path << " (" << rig.arm_name << "), drivers outside; waiting for them on " << bus::lcm_url()
            << std::endl;
  rigcheck::PreflightResult seen;
  {
    bus::Bus bus("launcher");
    seen = check_drivers(bus, rig, o.driver_timeout_s, std::cout);
  }
  // The camera is the driver's: what the planner scores and the ray-casting baseline casts.
  s.camera = seen.camera;
  s.depth_range = seen.range;
  s.validate();
  const FirstViews first = plan_first_views(s, rig, seen);
  if (o.dry_run) {
    std::cout << "dry run: nothing is commanded\n" << describe(first, rig, seen);
    require_reachable(first, s);
    return 0;
  }
  require_reachable(first, s);

  const fs::path out = fs::absolute(o.out.empty() ? "out/scan-" + timestamp() + "-" + s.scan_id.substr(s.scan_id.size() - 4) : o.out);
  prepare_out(out, o.overwrite);
  const LaunchSettings launch = launch_settings_of(o);
  write_scan_settings(s, launch, out);
  std::cout << "scanning: " << s.views << " " << name_of(s.planner) << " views -> " << out.string() << " (scan "
            << s.scan_id << ")" << std::endl;
  warn_small_receive_buffer();
  std::vector<process::Child> children = scan_processes(s, launch, out, bin);
  return supervise(children, s, out, launch.record_log, false);
}

namespace {

// After a scan of the twin: coverage after every view and (`surface_metrics`) the surface metrics
// against the ground truth it rendered, printed and written to coverage.json (a warning when they
// cannot be).
void evaluate_against_truth(const ScanSettings& s, const fs::path& out, bool surface_metrics) {
  try {
    const CoverageParams cp;
    const eval::ScanEvaluation e = surface_metrics ? eval::evaluate_scan(out, cp) : eval::evaluate_coverage(out, cp);
    write_json_atomic(eval::to_json(e, cp), (out / "coverage.json").string());
    std::string line;
    for (double c : e.coverage_by_view) line += " " + fixed(c, 1);
    std::cout << "coverage after each view (%, ground truth):" << line << std::endl;
    for (const auto& [name, m] : {std::pair{"cloud.ply", &e.cloud_metrics}, std::pair{"mesh.ply", &e.mesh_metrics}}) {
      if (!*m) continue;
      std::cout << name << " against the true mesh: accuracy mean " << fixed((*m)->accuracy.mean_m * 1e3, 2) << " mm, median "
                << fixed((*m)->accuracy.median_m * 1e3, 2) << " mm; F-score " << fixed((*m)->f_score, 3) << " within "
                << fixed((*m)->threshold_m * 1e3, 1) << " mm (precision " << fixed((*m)->precision, 3) << ", recall "
                << fixed((*m)->recall, 3) << ")" << std::endl;
    }
    if (!e.mesh_error.empty()) std::cerr << "warning: mesh.ply not evaluated: " << e.mesh_error << std::endl;
    if (e.hand_eye) {
      const eval::HandEyeCheck& c = *e.hand_eye;
      std::cout << "camera mount estimated over " << c.views << " views: " << fixed(c.estimate_mm, 2) << " mm, "
                << fixed(c.estimate_deg, 3) << " deg off the rig file (sigma " << fixed(c.sigma_mm, 2) << " mm, "
                << fixed(c.sigma_deg, 3) << " deg); the twin's true error " << fixed(c.true_mm, 2) << " mm, "
                << fixed(c.true_deg, 3) << " deg: the estimate " << fixed(c.error_mm, 2) << " mm, " << fixed(c.error_deg, 3)
                << " deg from it (hand_eye.json)" << std::endl;
    }
    if (!e.planner_ms.empty()) {
      // The plan as the scan waited for it (map update + the view scorer's answer; the ellipsoid fit
      // and the reachability check run side by side), and the paper's figure: its parts one after
      // the other.
      using eval::median_of;
      const std::string parts = std::string("map update + ") + (uses_ellipsoids(s.planner) ? "ellipsoids + " : "") + "view selection";
      if (e.planner_critical_ms.empty()) {
        std::cout << "planner step (" << parts << "): median " << fixed(median_of(e.planner_ms), 1) << " ms" << std::endl;
      } else {
        std::cout << "planning: median " << fixed(median_of(e.planner_critical_ms), 1) << " ms a view as the scan waited for it, "
                  << fixed(median_of(e.planner_ms), 1) << " ms its parts summed (" << parts << ")" << std::endl;
      }
    }
  } catch (const std::exception& x) {
    std::cerr << "warning: coverage not evaluated: " << x.what() << std::endl;
  }
}

// The end of a scan: the rig left stopped where it is when the scan failed, the logger stopped
// last, processes.json with how every process ended, scan.json's state when the coordinator
// could not say it, and the log's audit.
void wind_down(bus::Bus& bus, std::vector<process::Child>& children, const ScanSettings& s, const fs::path& out, int code,
               const std::string& cause, const std::map<std::string, Watch>& watch, bool record_log) {
  if (code != 0) {
    // Leave the rig stopped where it is: the motion executor halts it on STOP (three times: UDP may
    // lose one); a rig whose motion executor is gone is held by the launcher itself.
    send_stop(bus, s.scan_id, cause.empty() ? (code == 130 ? "interrupted" : "the scan failed") : cause);
    const auto motion = std::find_if(children.begin(), children.end(), [](const process::Child& c) { return c.name == "motion"; });
    if (s.external_rig && (motion == children.end() || !motion->running) && !s.scan_id.empty()) hold_rig(bus, s.scan_id);
  }
  stop_logger_last(children, out);
  // How every process ended (0 = clean exit), for the user and for the tests.
  record_processes(out, processes_json(s.scan_id, children, watch));
  if (!cause.empty()) {
    finish_record(out, "failed", cause);
  } else if (code != 0 && code != 1 && code != 130) {  // the coordinator itself died
    finish_record(out, "failed", "the coordinator stopped unexpectedly (" + how_it_ended(code) + "); see logs/coordinator.log");
  }
  for (const auto& c : children) {
    if (c.exit_code != 0 && code == 0) {
      std::cerr << "warning: " << c.name << " exited with status " << c.exit_code << " (log: " << c.log_path << ")" << std::endl;
    }
  }
  if (record_log && fs::exists(out / "scan.json")) audit_log(out, s.scan_id);
}

// The rig's contacts during the scan's moves (scan.json's rig_contacts), when there were any:
// "2 rig contacts: view 3 (request 17): link_6 / platter, ...; view 5 (...): ...".
void report_rig_contacts(const fs::path& out) {
  if (!fs::exists(out / "scan.json")) return;
  try {
    const std::vector<RigContactRecord> contacts = rig_contacts(read_scan_record(out).views);
    if (contacts.empty()) return;
    std::string line;
    for (const RigContactRecord& c : contacts) line += (line.empty() ? "" : "; ") + to_string(c);
    const int64_t n = rig_contact_events(contacts);
    std::cerr << "warning: " << n << " rig contact" << (n == 1 ? "" : "s") << ": " << line << std::endl;
  } catch (const std::exception& e) {
    std::cerr << "warning: the rig's contacts not read: " << e.what() << std::endl;
  }
}

// What the user reads at the end: the outputs (with the evaluation of a twin scan), or where the
// logs of a failed scan are; and any contact of the rig.
void report_outcome(int code, const ScanSettings& s, const fs::path& out, bool record_log, bool evaluate,
                    bool surface_metrics) {
  report_rig_contacts(out);
  if (code == 0) {
    if (evaluate) evaluate_against_truth(s, out, surface_metrics);
    std::cout << "outputs: " << (out / "cloud.ply").string() << ", " << (out / "frames").string() << "/, "
              << (fs::exists(out / "mesh.ply") ? (out / "mesh.ply").string() + " (.obj), " : std::string())
              << (uses_view_scorer(s.planner) ? (out / "plans").string() + "/, " : std::string())
              << (out / "scan.json").string() << (evaluate ? ", " + (out / "coverage.json").string() : std::string())
              << (record_log ? ", " + (out / "scan.lcmlog").string() : "")
              << (s.external_rig && !evaluate ? " (no coverage: the object is unknown)" : "") << std::endl;
  } else if (code != 130) {
    std::cerr << "scan failed (exit " << code << "); logs in " << (out / "logs").string() << std::endl;
  }
}

}  // namespace

int supervise(std::vector<process::Child>& children, const ScanSettings& s, const fs::path& out, bool record_log,
              bool evaluate, bool surface_metrics) {
  install_stop_handlers();

  try {
    for (auto& c : children) process::start(c);
  } catch (const std::exception&) {
    process::stop_all(children, 5.0);
    throw;
  }
  record_processes(out, processes_json(s.scan_id, children));
  process::Child* coordinator = &children.back();
  std::string cause;  // why the scan ended early, when the coordinator could not say
  int code = 0;
  bool done = false;

  // Supervision: a service that dies (a signal, or an exit other than 2 = bad start) is started
  // again, at most kMaxRestarts times each; one that sends no heartbeat for kSilentS is killed and
  // started again the same way. The restarted service continues from the scan's folder and the
  // coordinator's re-sent requests; lcm-logger goes on in scan.lcmlog.NN.
  std::map<std::string, Watch> watch;
  for (const auto& c : children) watch[c.name] = Watch{0, bus::now_s(), -1};
  bus::Bus bus("launcher");
  bus.serve_scan(s.scan_id);
  bus.subscribe<heartbeat_t>(channels::kHeartbeat, [&](const heartbeat_t& h) {
    for (const auto& c : children) {
      if (c.name == h.service && c.pid == h.pid) watch[c.name].heard_s = bus::now_s();
    }
  });
  auto restart = [&](process::Child& c, const std::string& why) {
    Watch& w = watch[c.name];
    ++w.restarts;
    std::cerr << "\n" << c.name << " " << why << ": starting it again (restart " << w.restarts << " of " << kMaxRestarts
              << ")" << std::endl;
    continue_scan(c);
    process::start(c);
    w.started_s = bus::now_s();
    w.heard_s = -1;
    record_processes(out, processes_json(s.scan_id, children, watch));
  };
  while (!done) {
    if (stop_requested()) {
      std::cout << "\ninterrupted: stopping every process" << std::endl;
      // The coordinator writes what it has (scan.json with state "stopped") before exiting.
      ::kill(coordinator->pid, SIGINT);
      for (int i = 0; i < 250 && coordinator->running; ++i) {
        process::reap(children);
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
      code = 130;
      break;
    }
    for (process::Child* c : process::reap(children)) {
      if (c == coordinator && c->exit_code > 128 && c->exit_code != 130 && watch[c->name].restarts < kMaxRestarts) {
        // Killed (not stopped by the user, not failed on its own terms): it goes on from scan.json.
        restart(*c, "stopped unexpectedly (" + how_it_ended(c->exit_code) + ")");
      } else if (c == coordinator) {
        code = c->exit_code;
        done = true;
      } else if (!done && c->exit_code != 2 && watch[c->name].restarts < kMaxRestarts) {
        restart(*c, "stopped unexpectedly (" + how_it_ended(c->exit_code) + ")");
      } else if (!done) {
        const std::string after =
            watch[c->name].restarts > 0 ? ", after " + std::to_string(watch[c->name].restarts) + " restarts" : "";
        cause = c->name + " stopped unexpectedly (" + how_it_ended(c->exit_code) + after + "); see logs/" + c->name + ".log";
        std::cerr << "error: " << c->name << " stopped unexpectedly (" << how_it_ended(c->exit_code) << after << "); the end of "
                  << c->log_path << ":\n" << process::tail_lines(c->log_path, 8) << "stopping every process"
                  << std::endl;
        code = 1;
        done = true;
      }
    }
    // A hung service: silent for kSilentS (kFirstHeartbeatS after a start: the twin loads its mesh).
    const double now = bus::now_s();
    for (auto& c : children) {
      if (done || !c.running || &c == coordinator || c.name == "lcm-logger") continue;
      const Watch& w = watch[c.name];
      const double silent = w.heard_s < 0 ? now - w.started_s : now - w.heard_s;
      if (silent > (w.heard_s < 0 ? kFirstHeartbeatS : kSilentS)) {
        std::cerr << "\n" << c.name << " sent no heartbeat for " << fixed(silent, 1) << " s: killing it" << std::endl;
        ::kill(c.pid, SIGKILL);  // reaped above on the next turn, then started again
        watch[c.name].heard_s = now;  // not twice
      }
    }
    bus.spin_once(20);
  }
  wind_down(bus, children, s, out, code, cause, watch, record_log);
  report_outcome(code, s, out, record_log, evaluate, surface_metrics);
  return code;
}

int run_rig_host(const RigHostOptions& o, const fs::path& bin) {
  install_stop_handlers();
  const fs::path logs = fs::absolute(o.logs);
  fs::create_directories(logs);
  std::vector<process::Child> children;
  for (const char* name : {"motion", "camera"}) {
    process::Child c;
    c.name = name;
    c.argv = {(bin / ("pbnbv-" + std::string(name))).string(), "--model", o.rig_model};
    c.log_path = (logs / (c.name + ".log")).string();
    c.append_log = true;
    children.push_back(std::move(c));
  }
  for (auto& c : children) process::start(c);
  std::cout << "pbnbv rig-host: motion executor and camera service for " << o.rig_model << " on " << bus::lcm_url()
            << ", logs in " << logs.string() << " (Ctrl-C stops them)" << std::endl;
  std::map<std::string, int> restarts;
  int code = 0;
  while (!stop_requested() && code == 0) {
    for (process::Child* c : process::reap(children)) {
      if (++restarts[c->name] > kMaxRestarts) {
        std::cerr << "error: " << c->name << " stopped (" << how_it_ended(c->exit_code) << ") " << kMaxRestarts
                  << " times; the end of " << c->log_path << ":\n" << process::tail_lines(c->log_path, 8);
        code = 1;
        break;
      }
      std::cerr << c->name << " stopped (" << how_it_ended(c->exit_code) << "): starting it again" << std::endl;
      process::start(*c);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  process::stop_all(children, 5.0);
  return code;  // stopped by the user: the normal end of a host
}

// Whether `pid` still runs a program of this scan (its command line names the scan's folder).
bool still_running(int pid, const fs::path& out) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/cmdline");
  const std::string cmdline((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return !cmdline.empty() && cmdline.find(out.string()) != std::string::npos;
}

// The scan's processes are built again from settings.json and the executables in `bin`, with the
// folder being resumed as their folder (a copied folder is resumed into the copy); processes.json
// is read only for the PIDs of a launcher's processes that may still run.
int resume_scan(const fs::path& dir, const fs::path& bin) {
  fs::path out = fs::absolute(dir).lexically_normal();
  if (out.filename().empty()) out = out.parent_path();  // "DIR/": the folder itself
  // A complete scan (of any version: `pbnbv bench` reruns over its folders) starts nothing.
  if (fs::is_regular_file(out / "settings.json") && fs::is_regular_file(out / "scan.json")) {
    if (recorded_state(out) == "done") {
      std::cout << "pbnbv scan: " << out.string() << " holds a complete scan: nothing to resume" << std::endl;
      return 0;
    }
  }
  const Resumable r = read_resumable(out);
  const ScanSettings& s = r.settings;
  if (fs::exists(out / "processes.json")) {
    const nlohmann::json procs = read_json((out / "processes.json").string());
    for (const auto& p : procs.value("processes", nlohmann::json::array())) {
      if (!p.is_object() || !p.contains("pid") || !p["pid"].is_number_integer()) continue;
      const int64_t pid = p["pid"].get<int64_t>();
      if (pid > 0 && pid < (int64_t{1} << 22) && still_running(static_cast<int>(pid), out)) {
        throw std::invalid_argument("--resume " + out.string() + ": its " + p.value("name", std::string("process")) +
                                    " (pid " + std::to_string(pid) + ") is still running");
      }
    }
  }
  std::vector<process::Child> children = scan_processes(s, r.launch, out, bin);
  for (auto& c : children) continue_scan(c);
  std::cout << "pbnbv scan: resuming " << s.scan_id << " in " << out.string()
            << (r.rerooted.empty() ? "" : " (" + r.rerooted + ")") << std::endl;
  return supervise(children, s, out, r.launch.record_log, !s.external_rig, r.launch.surface_metrics);
}

}  // namespace pbnbv::launcher
