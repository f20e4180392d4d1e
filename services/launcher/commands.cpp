// `pbnbv bench`, `ablate` and `spy` (commands.hpp).
#include <unistd.h>

#include <algorithm>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>


#include "bus/bus.hpp"
#include "core/base/install_paths.hpp"
#include "core/io/json.hpp"
#include "core/rig/urdf_import.hpp"
#include "core/io/cloud_file.hpp"
#include "core/scan/scan_file.hpp"
#include "core/scan/scan_record.hpp"
#include "core/scan/scan_settings.hpp"
#include "core/surface/scan_mesh.hpp"
#include "launcher/commands.hpp"
#include "launcher/supervise.hpp"
#include "rigcheck/rig_check.hpp"

namespace fs = std::filesystem;

namespace pbnbv::launcher {

int run_sweep(const eval::Sweep& sweep, const fs::path& self) {
  const std::vector<eval::BenchResult> results = eval::run_sweep(sweep, self, std::cout, ::isatty(STDOUT_FILENO) == 1);
  std::cout << "\n" << read_text((sweep.out / "sweep.md").string()) << std::endl;
  std::cout << "outputs: " << (sweep.out / "sweep.json").string() << ", " << (sweep.out / "sweep.md").string()
            << ", sweep.png; each combination's summary.json, report.md, plots and scans in " << sweep.out.string()
            << "/<combination>/" << std::endl;
  int failed = 0;
  for (const eval::BenchResult& r : results) {
    for (const auto& p : r.planners) failed += p.failed;
  }
  if (failed > 0) {
    std::cerr << "pbnbv bench: " << failed << " scans did not complete (see each combination's summary.json and logs/); "
              << "run the command again to retry them" << std::endl;
    return 1;
  }
  return 0;
}

int run_bench(const eval::BenchSpec& spec, const fs::path& self) {
  const eval::BenchResult r = eval::run_bench(spec, self, std::cout, ::isatty(STDOUT_FILENO) == 1);
  std::cout << "\n" << read_text((spec.out / "report.md").string()) << std::endl;
  int failed = 0;
  for (const auto& p : r.planners) failed += p.failed;
  std::cout << "outputs: " << (spec.out / "summary.json").string() << ", " << (spec.out / "report.md").string()
            << ", coverage.png, time.png"
            << (std::find(spec.planners.begin(), spec.planners.end(), PlannerKind::kOracle) != spec.planners.end()
                    ? ", gap.png"
                    : "")
            << "; scans in " << spec.out.string() << "/<planner>/<object>/"
            << (spec.first_views > 1 ? " and <object>-fv<k>/ (first view k)" : "") << std::endl;
  if (failed > 0) {
    std::cerr << "pbnbv bench: " << failed << " scans did not complete (see summary.json and logs/); run the command "
              << "again to retry them" << std::endl;
    return 1;
  }
  return 0;
}

int run_ablate(const AblateOptions& o, const fs::path& self) {
  eval::run_ablation(std::string(name_of(o.parameter)), o.runs, o.out, self, std::cout, ::isatty(STDOUT_FILENO) == 1);
  std::cout << "\n" << read_text((o.out / "ablation.md").string()) << std::endl;
  return 0;
}

int run_spy() {
  const std::string installed = installed_share_path("pbnbv_lcmtypes.jar");
  const std::string jar = installed.empty() ? std::string(PBNBV_LCM_JAR) : installed;
  const std::string classpath = jar + ":/usr/share/java/lcm.jar:/usr/share/java/jchart2d.jar";
  if (!fs::exists(jar)) {
    throw std::runtime_error("message jar " + jar + " is missing: build the project first (./scripts/setup)");
  }
  // Debian's lcm-spy script passes -Xincgc, which Java 17 rejects; start the class directly.
  std::vector<std::string> a = {"java", "-Djava.net.preferIPv4Stack=true", "-Xmx512m", "-cp", classpath, "lcm.spy.Spy"};
  std::vector<char*> cargv;
  for (auto& s : a) cargv.push_back(s.data());
  cargv.push_back(nullptr);
  ::execvp("java", cargv.data());
  throw std::runtime_error("cannot run java (install default-jdk-headless: ./scripts/setup)");
}

int run_stop(const StopOptions& o) {
  bus::Bus bus("stop");
  send_stop(bus, o.scan_id, o.reason);
  std::cout << "pbnbv stop: STOP sent to " << (o.scan_id.empty() ? std::string("every scan") : "scan " + o.scan_id)
            << " on " << bus::lcm_url() << std::endl;
  return 0;
}

int run_import_urdf(const ImportUrdfOptions& o) {
  const ImportedArm arm = import_urdf(o.urdf, o.out);
  std::string joints;
  for (const auto& j : arm.hinge_joints) joints += (joints.empty() ? "" : ", ") + j;
  std::cout << "pbnbv import-urdf: " << o.out << ": " << arm.bodies.size() << " bodies, " << arm.hinge_joints.size()
            << " hinge joints (" << joints << ")" << std::endl;
  if (!arm.other_joints.empty()) {
    std::cerr << "warning: " << arm.other_joints.size() << " joints that are not hinges (a rig's arm has only hinges)"
              << std::endl;
  }
  if (arm.hinge_joints.size() != 6) {
    std::cerr << "warning: a rig's arm has 6 hinge joints from its base to the flange; this one has "
              << arm.hinge_joints.size() << std::endl;
  }
  std::cout << "next: put its bodies under the \"base\" body of a copy of models/rig_arm.xml, name the last body "
               "\"flange\", keep \"camera_optical\" under it, set the <custom> limits and home; then pbnbv rig-check "
               "and pbnbv scan --external-rig --dry-run (docs/real-rig.md, 'Bring your own rig')"
            << std::endl;
  return 0;
}

int run_rig_check(const RigCheckOptions& o) {
  const RigModel rig = load_rig(o.rig_model);
  bus::Bus bus("rig-check");
  std::cout << "pbnbv rig-check: the drivers on " << bus::lcm_url() << " against " << o.rig_model
            << (o.passive ? " (passive: nothing is commanded to move)" : "") << std::endl;
  const rigcheck::PreflightResult r =
      o.passive ? rigcheck::preflight(bus, rig, o.deadline_s) : rigcheck::rig_check(bus, rig, o.deadline_s);
  std::cout << rigcheck::format_table(r.lines);
  int failed = 0;
  for (const auto& l : r.lines) failed += l.passed ? 0 : 1;
  if (failed > 0) {
    std::cout << "pbnbv rig-check: FAILED, " << failed << " of " << r.lines.size() << " checks" << std::endl;
    return 1;
  }
  std::cout << "pbnbv rig-check: passed, " << r.lines.size() << " checks" << std::endl;
  return 0;
}

int run_mesh(const MeshOptions& o) {
  const fs::path dir(o.dir);
  // The frames scan.json names as merged, with the camera and point spacing the scan had.
  const RecordedScan scan = read_scan_record(dir);
  SurfaceSettings s = o.surface;
  s.camera = scan.settings.camera;
  s.point_spacing_m = scan.settings.voxel_m;
  std::vector<SurfaceFrame> frames;
  for (const MergedFrame& f : merged_frames(scan, dir)) {
    CloudExtras extras;
    PointCloud points = read_ply(f.file.string(), extras);
    frames.push_back({std::move(points), f.object_T_camera, std::move(extras.colours)});
  }
  const MeshSummary mesh = mesh_scan(dir, frames, s, o.stl, o.units);
  write_scan_mesh(dir, mesh);
  const nlohmann::json m = to_json(mesh);
  std::cout << "pbnbv mesh: " << (dir / "mesh.ply").string() << " (and mesh.obj" << (o.stl ? ", mesh.stl" : "")
            << (o.units == LengthUnit::kMillimetre ? " in millimetres" : "") << "): " << m["method"].get<std::string>()
            << ", " << m["vertices"] << " vertices, " << m["triangles"] << " triangles, "
            << (m["watertight"].get<bool>() ? std::string("watertight")
                                            : std::to_string(m["boundary_loops"].get<std::size_t>()) + " boundary loops (" +
                                                  std::to_string(m["hole_boundary_length_m"].get<double>()) + " m)")
            << ", " << m["seconds"].get<double>() << " s; recorded in " << (dir / "scan.json").string() << " (\"mesh\")"
            << std::endl;
  return 0;
}

}  // namespace pbnbv::launcher
