// pbnbv: the command a user runs.
//   pbnbv scan [--object PATH|bunny|teapot|sphere|box] [--size M] [--up z|y] [--planner pbnbv|ring]
//              [--views N] [--rig arm|free] [--out DIR] [...]
//       normalises the object, starts the twin and every service as separate processes
//       (plus lcm-logger), supervises them while the coordinator scans, and stops them all at
//       the end, on Ctrl-C, or when one fails.
//   pbnbv spy    lcm-spy with the project's message types, so every channel decodes.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <thread>

#include "core/base/args.hpp"
#include "core/base/signals.hpp"
#include "core/geometry/mesh.hpp"
#include "core/io/json.hpp"
#include "core/io/mesh_file.hpp"
#include "core/scan/scan_settings.hpp"
#include "eval/bench.hpp"
#include "eval/evaluate.hpp"
#include "eval/objects.hpp"
#include "process/processes.hpp"
#include "core/base/format.hpp"

using namespace pbnbv;
namespace fs = std::filesystem;

namespace {

const char* kUsage =
R"(usage:
  pbnbv scan [options]     twin-in-the-loop scan of an object
  pbnbv bench [options]    every planner on every object in the twin: coverage per
                           view, planner time, report.md, plots (see below)
  pbnbv ablate tmax|beta|initial-view [bench options]
                           the paper's ablations: one benchmark per value, one plot
  pbnbv spy                lcm-spy with every pbnbv channel decoded
  pbnbv help

scan options:
  --object PATH|NAME       mesh file (.obj .stl .off .ply) or a built-in object:
                           bunny, teapot (fetched by ./scripts/setup), sphere, box  [bunny]
  --size M                 shortest bounding-box edge after normalisation, m     [0.3]
  --up z|y                 which axis of the mesh file points up   [y for bunny/teapot, else z]
  --planner NAME           pbnbv: next-best-view planning (PB-NBV); ring: a fixed
                           turntable ring; the benchmark's baselines on PB-NBV's
                           candidates: raycast (ray-casting information gain),
                           random (a random candidate)                          [pbnbv]
  --seed N                 the random planner's seed                              [1]
  --views N                at most this many views                                [10]
  --rig arm|free           arm + turntable, or a free-flying camera (paper setup) [arm]
  --area hemi|full         pbnbv candidates: hemisphere above the object, or the
                           full sphere (the paper's comparison: --rig free --area full) [hemi]
  --candidates N           pbnbv candidate views per plan                         [800]
  --parallels N            parallels the candidates lie on (alpha)                [24]
  --beta N                 global partitioning sectors (1: off)                   [4]
  --tmax N                 most Gaussian components per ellipsoid class (T_max)   [10]
  --stop-fraction X        stop when the best view quality F falls below X times
                           the first planned view's F (0: never; README says why) [0]
  --when-done stop|spread  when the map has nothing left to aim at (no frontier
                           ellipsoid; raycast: no unobserved voxel in view): stop,
                           or spend the remaining views filling the largest gaps
                           between the views taken                             [stop]
  --initial-view x,y,z     first camera position, object frame, m; looks at the origin
                           [ring view at --ring-elevation (arm) / 0 deg (free), azimuth 0]
  --out DIR                output folder                      [out/<object>-<date-time>]
  --working-distance M     camera to the object's bounding sphere, m              [0.6]
  --ring-elevation DEG     ring views / first view: elevation above the object centre [30 arm, 0 free]
  --voxel M                cloud downsampling voxel, m                            [0.002]
  --resolution M           voxel map resolution, m (0.01 suits a real rig)        [0.03]
  --registration on|off    refine every view's pose by ICP against the model  [on arm, off free]
  --speed-scale S          fraction of the joint speed limits, (0, 1]             [1]
  --sim-speed X            twin simulation speed, multiple of real time           [4]
  --noise-sigma K          twin depth noise, std = K * depth (0: off)             [0]
  --dropout P              twin pixel dropout probability (0: off)                [0]
  --hand-eye-error-mm MM --hand-eye-error-deg DEG --turntable-error-deg DEG
  --joint-error-deg DEG --error-seed N
                           twin pose-error model: kinematic poses wrong the way a
                           real rig's are (all 0: off)
  --width --height --fx --fy --cx --cy   depth camera intrinsics    [1280 720 696 696 640 360]
  --depth-min --depth-max M                depth range, m                      [0.1 3.0]
  --no-log                 do not record scan.lcmlog

bench options:
  --objects A,B,...        object names or mesh paths        [the default set, README]
  --object-dir DIR         every .obj/.stl/.off/.ply in DIR instead
  --planners P,...         pbnbv, raycast, random, ring          [pbnbv,raycast,random]
  --rig free|arm --area full|hemi                              [free, full: the paper's]
  --views N --resolution M --candidates N --tmax N --beta N --size M --up z|y
  --initial-view x,y,z --seed N                   as for scan   [10 0.03 800 10 4 0.3]
  --jobs N                 scans at once, each in its own network namespace        [1]
  --no-netns               run the scans on the current LCM bus (one at a time)
  --out DIR                results; a rerun skips the scans already complete there
ablate: the same options (planners default pbnbv), --values V,V,... (initial views
  separated by /)  [tmax 5,10,20,40; beta 1,2,4,8; initial-view
  0.9,0,0/0,0.9,0/0,0,0.9/0,0.63,0.63]
)";

fs::path self_dir() { return fs::read_symlink("/proc/self/exe").parent_path(); }

std::string timestamp() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  localtime_r(&t, &tm);
  char b[32];
  std::strftime(b, sizeof(b), "%Y%m%d-%H%M%S", &tm);
  return b;
}

int scan(int argc, char** argv) {
  Args args(argc, argv, 2);
  ScanSettings s;
  eval::ObjectSpec object = eval::resolve_object(args.str("object", "bunny"));
  const std::string object_name = object.name;
  TriangleMesh& mesh = object.mesh;
  const double size = args.num("size", 0.3, 0.01, 2.0);
  const UpAxis up = args.has("up") ? parse_up_axis(args.str("up")) : object.up;
  s.normalisation = normalise_mesh(mesh, size, up);
  s.normalisation.source_path = object.source;
  s.object_name = object_name;
  s.rig = parse_rig_kind(args.str("rig", "arm"));
  s.rig_model_path = default_rig_path(s.rig);
  s.planner = args.str("planner", "pbnbv");
  if (s.planner != "ring" && s.planner != "pbnbv" && s.planner != "raycast" && s.planner != "random") {
    throw std::invalid_argument("--planner " + s.planner + ": expected pbnbv, raycast, random or ring");
  }
  s.seed = args.integer("seed", 1, 0, int64_t{1} << 62);
  s.views = static_cast<int>(args.integer("views", 10, 1, 1000));
  s.working_distance_m = args.num("working-distance", 0.6, 0.15, 3.0);
  s.ring_elevation_deg = args.num("ring-elevation", s.rig == RigKind::kArm ? 30.0 : 0.0, -89.0, 89.0);
  const std::string area = args.str("area", "hemi");
  if (area != "hemi" && area != "full") throw std::invalid_argument("--area " + area + ": expected hemi or full");
  s.full_sphere = area == "full";
  s.candidates = static_cast<int>(args.integer("candidates", 800, 1, 100000));
  s.parallels = static_cast<int>(args.integer("parallels", 24, 1, 1000));
  if (s.parallels > s.candidates) throw std::invalid_argument("--parallels must not exceed --candidates");
  s.sectors = static_cast<int>(args.integer("beta", 4, 1, 360));
  s.t_max = static_cast<int>(args.integer("tmax", 10, 1, 200));
  s.stop_fraction = args.num("stop-fraction", 0.0, 0.0, 1.0);
  s.when_done = args.str("when-done", "stop");
  if (s.when_done != "stop" && s.when_done != "spread") {
    throw std::invalid_argument("--when-done " + s.when_done + ": expected stop or spread");
  }
  if (args.has("initial-view")) {
    s.initial_view_m = args.vec3("initial-view", Eigen::Vector3d::Zero());
    if (s.initial_view_m.norm() < 0.05) throw std::invalid_argument("--initial-view must be away from the object centre");
  }
  s.voxel_m = args.num("voxel", 0.002, 0.0, 0.05);
  const double resolution = args.num("resolution", 0.03, 0.002, 0.2);
  s.map_resolution_m = resolution;
  // The free rig is the paper's idealised comparison setup (a camera placed exactly, as in the
  // paper's simulation): its kinematic poses are exact, so registration is off by default there.
  const std::string registration = args.str("registration", s.rig == RigKind::kArm ? "on" : "off");
  if (registration != "on" && registration != "off") {
    throw std::invalid_argument("--registration " + registration + ": expected on or off");
  }
  s.speed_scale = args.num("speed-scale", 1.0, 0.01, 1.0);
  s.sim_speed = args.num("sim-speed", 4.0, 0.1, 100.0);
  s.camera.width = static_cast<int>(args.integer("width", 1280, 1, 16384));
  s.camera.height = static_cast<int>(args.integer("height", 720, 1, 16384));
  s.camera.fx = args.num("fx", 696.0, 1.0, 1e5);
  s.camera.fy = args.num("fy", 696.0, 1.0, 1e5);
  s.camera.cx = args.num("cx", s.camera.width / 2.0, 0.0, s.camera.width);
  s.camera.cy = args.num("cy", s.camera.height / 2.0, 0.0, s.camera.height);
  s.camera.validate();
  s.depth_range.min_m = args.num("depth-min", 0.1, 0.001, 10.0);
  s.depth_range.max_m = args.num("depth-max", 3.0, 0.01, 6.5);
  s.depth_range.validate();
  const double noise_sigma = args.num("noise-sigma", 0.0, 0.0, 0.1);
  const double dropout = args.num("dropout", 0.0, 0.0, 1.0);
  const bool record_log = !args.flag("no-log");
  std::vector<std::string> error_args;
  for (const char* name : {"hand-eye-error-mm", "hand-eye-error-deg", "turntable-error-deg", "joint-error-deg", "error-seed"}) {
    if (args.has(name)) {
      error_args.push_back(std::string("--") + name);
      error_args.push_back(args.str(name));
    }
  }
  const fs::path out = fs::absolute(args.str("out", "out/" + object_name + "-" + timestamp()));
  args.reject_unknown();

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
            << " " << s.planner << " views -> " << out.string() << std::endl;

  const fs::path bin = self_dir();
  std::vector<process::Child> children;
  auto add = [&](const std::string& name, std::vector<std::string> argv, bool progress = false) {
    process::Child c;
    c.name = name;
    c.argv = std::move(argv);
    c.log_path = (out / "logs" / (name + ".log")).string();
    c.stdout_to_terminal = progress;
    children.push_back(std::move(c));
  };
  if (record_log) add("lcm-logger", {"/usr/bin/lcm-logger", "-q", "-f", (out / "scan.lcmlog").string()});
  add("twin", {(bin / "pbnbv-twin").string(), "--rig", to_string(s.rig), "--mesh", stl,
               "--object-z", exact(s.object_z_m), "--model-out", (out / "twin_model.xml").string(),
               "--width", std::to_string(s.camera.width), "--height", std::to_string(s.camera.height),
               "--fx", exact(s.camera.fx), "--fy", exact(s.camera.fy), "--cx", exact(s.camera.cx), "--cy", exact(s.camera.cy),
               "--depth-min", exact(s.depth_range.min_m), "--depth-max", exact(s.depth_range.max_m),
               "--noise-sigma", exact(noise_sigma), "--dropout", exact(dropout), "--speed", exact(s.sim_speed),
               "--truth-out", (out / "twin_truth.jsonl").string()});
  children.back().argv.insert(children.back().argv.end(), error_args.begin(), error_args.end());
  add("motion", {(bin / "pbnbv-motion").string(), "--rig", to_string(s.rig)});
  add("camera", {(bin / "pbnbv-camera").string(), "--rig", to_string(s.rig)});
  add("registration", {(bin / "pbnbv-registration").string()});
  if (registration == "off") children.back().argv.push_back("--off");
  // The map's working volume: the cloud's crop box, above the turntable top.
  Eigen::Vector3d volume_min = s.crop_min_m;
  if (s.rig == RigKind::kArm) volume_min.z() = std::max(volume_min.z(), -s.object_z_m + s.ground_clearance_m);
  auto vec = [&](const Eigen::Vector3d& v) { return exact(v.x()) + "," + exact(v.y()) + "," + exact(v.z()); };
  add("mapping", {(bin / "pbnbv-mapping").string(), "--resolution", exact(resolution), "--out", out.string(),
                  "--volume-min", vec(volume_min), "--volume-max", vec(s.crop_max_m)});
  if (s.planner == "pbnbv") add("ellipsoids", {(bin / "pbnbv-ellipsoids").string(), "--tmax", std::to_string(s.t_max)});
  if (s.planner != "ring") add("scorer", {(bin / "pbnbv-scorer").string(), "--rig", to_string(s.rig)});
  add("coordinator", {(bin / "pbnbv-coordinator").string(), "--out", out.string()}, true);

  install_stop_handlers();

  try {
    for (auto& c : children) process::start(c);
  } catch (const std::exception& e) {
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
        std::cout << "planner step (map update + " << (s.planner == "pbnbv" ? "ellipsoids + " : "") << "view selection): median "
                  << t[t.size() / 2] << " ms"
                  << std::endl;
      }
    } catch (const std::exception& x) {
      std::cerr << "warning: coverage not evaluated: " << x.what() << std::endl;
    }
    std::cout << "outputs: " << (out / "cloud.ply").string() << ", " << (out / "frames").string() << "/, "
              << (s.planner != "ring" ? (out / "plans").string() + "/, " : std::string())
              << (out / "scan.json").string() << ", " << (out / "coverage.json").string()
              << (record_log ? ", " + (out / "scan.lcmlog").string() : "") << std::endl;
  } else if (code != 130) {
    std::cerr << "scan failed (exit " << code << "); logs in " << (out / "logs").string() << std::endl;
  }
  return code;
}

int spy(int argc, char** argv) {
  Args args(argc, argv, 2);
  args.reject_unknown();
  const std::string classpath = std::string(PBNBV_LCM_JAR) + ":/usr/share/java/lcm.jar:/usr/share/java/jchart2d.jar";
  if (!fs::exists(PBNBV_LCM_JAR)) {
    throw std::runtime_error(std::string("message jar ") + PBNBV_LCM_JAR + " is missing: build the project first (./scripts/setup)");
  }
  // Debian's lcm-spy script passes -Xincgc, which Java 17 rejects; start the class directly.
  std::vector<std::string> a = {"java", "-Djava.net.preferIPv4Stack=true", "-Xmx512m", "-cp", classpath, "lcm.spy.Spy"};
  std::vector<char*> cargv;
  for (auto& s : a) cargv.push_back(s.data());
  cargv.push_back(nullptr);
  ::execvp("java", cargv.data());
  throw std::runtime_error("cannot run java (install default-jdk-headless: ./scripts/setup)");
}

}  // namespace

int main(int argc, char** argv) {
  const std::string command = argc > 1 ? argv[1] : "help";
  try {
    if (command == "scan") return scan(argc, argv);
    if (command == "spy") return spy(argc, argv);
    if (command == "bench") return eval::bench_command(argc, argv, fs::read_symlink("/proc/self/exe"));
    if (command == "ablate") return eval::ablate_command(argc, argv, fs::read_symlink("/proc/self/exe"));
    if (command == "help" || command == "--help" || command == "-h") {
      std::cout << kUsage;
      return 0;
    }
    std::cerr << "pbnbv: unknown command '" << command << "'\n" << kUsage;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "pbnbv " << command << ": " << e.what() << std::endl;
    return 2;
  }
}
