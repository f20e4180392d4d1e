// `pbnbv scan` (commands.hpp).
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <ctime>
#include <iostream>
#include <thread>

#include "core/base/format.hpp"
#include "core/base/signals.hpp"
#include "core/geometry/mesh.hpp"
#include "core/io/json.hpp"
#include "core/io/mesh_file.hpp"
#include "eval/evaluate.hpp"
#include "eval/objects.hpp"
#include "launcher/commands.hpp"
#include "process/processes.hpp"

namespace fs = std::filesystem;

namespace pbnbv::launcher {

namespace {

// The local date and time as 20250131-142501 (folder names and scan ids).
std::string timestamp() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  localtime_r(&t, &tm);
  char b[32];
  std::strftime(b, sizeof(b), "%Y%m%d-%H%M%S", &tm);
  return b;
}

}  // namespace

int run_scan(const ScanOptions& o, const fs::path& bin) {
  ScanSettings s = o.settings;
  eval::ObjectSpec object = eval::resolve_object(o.object);
  const std::string object_name = object.name;
  TriangleMesh& mesh = object.mesh;
  s.normalisation = normalise_mesh(mesh, o.size_m, o.up.value_or(object.up));
  s.normalisation.source_path = object.source;
  s.object_name = object_name;
  const fs::path out = fs::absolute(o.out.empty() ? "out/" + object_name + "-" + timestamp() : o.out);

  // The object rests on the turntable (arm rig) or floats at the origin (free rig).
  place_object(s);
  s.scan_id = object_name + "-" + timestamp();

  fs::create_directories(out / "logs");
  const std::string stl = (out / "object.stl").string();
  write_stl_binary(mesh, stl);
  write_obj(mesh, (out / "object.obj").string());
  write_json_atomic(to_json(s), (out / "settings.json").string());

  std::cout << "pbnbv scan: " << object_name << " (" << s.normalisation.num_triangles << " triangles, "
            << s.normalisation.extent_m.x() << " x " << s.normalisation.extent_m.y() << " x "
            << s.normalisation.extent_m.z() << " m) on the " << to_string(s.rig) << " rig, " << s.views
            << " " << name_of(s.planner) << " views -> " << out.string() << std::endl;

  std::vector<process::Child> children;
  auto add = [&](const std::string& name, std::vector<std::string> argv, bool progress = false) {
    process::Child c;
    c.name = name;
    c.argv = std::move(argv);
    c.log_path = (out / "logs" / (name + ".log")).string();
    c.stdout_to_terminal = progress;
    children.push_back(std::move(c));
  };
  if (o.record_log) add("lcm-logger", {"/usr/bin/lcm-logger", "-q", "-f", (out / "scan.lcmlog").string()});
  add("twin", {(bin / "pbnbv-twin").string(), "--rig", to_string(s.rig), "--mesh", stl,
               "--object-z", exact(s.object_z_m), "--model-out", (out / "twin_model.xml").string(),
               "--width", std::to_string(s.camera.width), "--height", std::to_string(s.camera.height),
               "--fx", exact(s.camera.fx), "--fy", exact(s.camera.fy), "--cx", exact(s.camera.cx), "--cy", exact(s.camera.cy),
               "--depth-min", exact(s.depth_range.min_m), "--depth-max", exact(s.depth_range.max_m),
               "--noise-sigma", exact(o.noise_sigma), "--dropout", exact(o.dropout), "--speed", exact(s.sim_speed),
               "--hand-eye-error-mm", exact(o.hand_eye_error_mm), "--hand-eye-error-deg", exact(o.hand_eye_error_deg),
               "--turntable-error-deg", exact(o.turntable_error_deg), "--joint-error-deg", exact(o.joint_error_deg),
               "--error-seed", std::to_string(o.error_seed), "--truth-out", (out / "twin_truth.jsonl").string()});
  add("motion", {(bin / "pbnbv-motion").string(), "--rig", to_string(s.rig)});
  add("camera", {(bin / "pbnbv-camera").string(), "--rig", to_string(s.rig)});
  add("registration", {(bin / "pbnbv-registration").string()});
  if (!o.registration) children.back().argv.push_back("--off");
  // The map's working volume: the cloud's crop box, above the turntable top.
  Eigen::Vector3d volume_min = s.crop_min_m;
  if (s.rig == RigKind::kArm) volume_min.z() = std::max(volume_min.z(), -s.object_z_m + s.ground_clearance_m);
  auto vec = [&](const Eigen::Vector3d& v) { return exact(v.x()) + "," + exact(v.y()) + "," + exact(v.z()); };
  add("mapping", {(bin / "pbnbv-mapping").string(), "--resolution", exact(s.map_resolution_m), "--out", out.string(),
                  "--volume-min", vec(volume_min), "--volume-max", vec(s.crop_max_m)});
  if (uses_ellipsoids(s.planner)) add("ellipsoids", {(bin / "pbnbv-ellipsoids").string(), "--tmax", std::to_string(s.t_max)});
  if (uses_view_scorer(s.planner)) add("scorer", {(bin / "pbnbv-scorer").string(), "--rig", to_string(s.rig)});
  add("coordinator", {(bin / "pbnbv-coordinator").string(), "--out", out.string()}, true);

  install_stop_handlers();

  try {
    for (auto& c : children) process::start(c);
  } catch (const std::exception&) {
    process::stop_all(children, 5.0);
    throw;
  }
  process::Child* coordinator = &children.back();
  int code = 0;
  bool done = false;
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
      if (c == coordinator) {
        code = c->exit_code;
        done = true;
      } else if (!done) {
        std::cerr << "error: " << c->name << " stopped unexpectedly (exit status " << c->exit_code
                  << "); the end of " << c->log_path << ":\n" << process::tail_lines(c->log_path, 8)
                  << "stopping every process" << std::endl;
        code = 1;
        done = true;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  process::stop_all(children, 5.0);
  // How every process ended (0 = clean exit), for the user and for the tests.
  nlohmann::json procs = nlohmann::json::array();
  for (const auto& c : children) procs.push_back({{"name", c.name}, {"exit_code", c.exit_code}});
  write_json_atomic(procs, (out / "processes.json").string());
  for (const auto& c : children) {
    if (c.exit_code != 0 && code == 0) {
      std::cerr << "warning: " << c.name << " exited with status " << c.exit_code << " (log: " << c.log_path << ")" << std::endl;
    }
  }
  if (code == 0) {
    // Against the ground truth the twin rendered: coverage after every view.
    try {
      const CoverageParams cp;
      const eval::ScanEvaluation e = eval::evaluate_scan(out, cp);
      write_json_atomic(eval::to_json(e, cp), (out / "coverage.json").string());
      std::string line;
      for (double c : e.coverage_by_view) line += " " + fixed(c, 1);
      std::cout << "coverage after each view (%, ground truth):" << line << std::endl;
      if (!e.planner_ms.empty()) {
        std::vector<double> t = e.planner_ms;
        std::sort(t.begin(), t.end());
        std::cout << "planner step (map update + " << (uses_ellipsoids(s.planner) ? "ellipsoids + " : "") << "view selection): median "
                  << t[t.size() / 2] << " ms"
                  << std::endl;
      }
    } catch (const std::exception& x) {
      std::cerr << "warning: coverage not evaluated: " << x.what() << std::endl;
    }
    std::cout << "outputs: " << (out / "cloud.ply").string() << ", " << (out / "frames").string() << "/, "
              << (uses_view_scorer(s.planner) ? (out / "plans").string() + "/, " : std::string())
              << (out / "scan.json").string() << ", " << (out / "coverage.json").string()
              << (o.record_log ? ", " + (out / "scan.lcmlog").string() : "") << std::endl;
  } else if (code != 130) {
    std::cerr << "scan failed (exit " << code << "); logs in " << (out / "logs").string() << std::endl;
  }
  return code;
}

}  // namespace pbnbv::launcher
