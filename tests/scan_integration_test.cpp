// A whole twin-in-the-loop ring scan: the launcher starts the twin, the motion executor, the
// camera service, the coordinator and lcm-logger as separate processes on a real LCM bus in
// a private network namespace. The merged cloud must lie on the true surface of the object
// (the normalised mesh the twin rendered), which holds only if the rendered depth, the
// kinematics, the hand-eye transform and every frame convention agree.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <sys/wait.h>
#include <thread>
#include <filesystem>
#include <array>
#include <fstream>
#include <sstream>
#include <nlohmann/json.hpp>

#include "core/geometry/point_cloud.hpp"
#include "core/geometry/mesh.hpp"
#include "scan_checks.hpp"
#include "test_util.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "core/io/mesh_file.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;

namespace {

// Runs a scan and checks what every scan must satisfy; returns the output folder.
fs::path scan_and_check(const std::string& name, const std::string& options, int views) {
  const fs::path out = fresh_dir(name);
  const std::string cmd = netns_run() + " " + bin_dir() + "/pbnbv scan " + options + " --views " +
                          std::to_string(views) + " --stop-rule off --sim-speed 20 --out " + out.string();
  const CommandResult r = run_command(cmd);
  EXPECT_EQ(r.exit_code, 0) << cmd << "\n" << r.output;
  // Outputs.
  EXPECT_TRUE(fs::exists(out / "cloud.ply")) << r.output;
  EXPECT_TRUE(fs::exists(out / "scan.lcmlog"));
  EXPECT_GT(fs::file_size(out / "scan.lcmlog"), 1000000u) << "the log should hold the depth frames";
  for (int i = 0; i < views; ++i) {
    char frame[64];
    std::snprintf(frame, sizeof(frame), "frames/view_%03d.ply", i + 1);  // files count views from 1
    EXPECT_TRUE(fs::exists(out / frame)) << frame;
  }
  // scan.json: every view reached, with the per-view record.
  const auto scan = read_json_file(out / "scan.json");
  EXPECT_EQ(scan["status"]["state"], "done");
  EXPECT_EQ(scan["views"].size(), static_cast<std::size_t>(views));
  // The twin counted no contact of the arm or the camera with anything in any move.
  EXPECT_EQ(scan["rig_contacts"], nlohmann::json::array()) << scan["rig_contacts"].dump(2);
  for (const auto& v : scan["views"]) {
    EXPECT_EQ(v["move"]["status"], "reached") << v.dump(2);
    EXPECT_EQ(v["move"]["contacts"], 0) << v.dump(2);
    EXPECT_LT(v["move"]["position_error_m"].get<double>(), 1e-3) << v.dump(2);
    EXPECT_LT(v["move"]["angle_error_deg"].get<double>(), 0.1) << v.dump(2);
    EXPECT_EQ(v["capture"]["status"], "ok");
    EXPECT_GT(v["capture"]["num_points"].get<int>(), 1000);
    for (const char* stage : {"plan", "move", "settle", "capture", "cloud", "accumulate"}) {
      EXPECT_TRUE(v["time_s"].contains(stage)) << stage;
    }
  }
  // Rig time (docs/scan.md): every view's parts measured, none negative, the total their sum; on
  // the arm every view moves the rig (the first from where it stood); the scan's figures are
  // the views' sums, and the closing line says them.
  const bool arm = options.find("--rig arm") != std::string::npos;
  double motion = 0, total = 0;
  for (const auto& v : scan["views"]) {
    const auto& t = v["rig_time_s"];
    double parts = 0;
    for (const char* part : {"motion", "settle", "capture", "compute"}) {
      EXPECT_TRUE(t[part].is_number()) << part << " " << v.dump(2);
      if (!t[part].is_number()) continue;
      EXPECT_GE(t[part].get<double>(), 0.0) << part;
      parts += t[part].get<double>();
    }
    EXPECT_NEAR(t["total"].get<double>(), parts, 1e-9);
    if (arm) EXPECT_GT(t["motion"].get<double>(), 0.0) << v.dump(2);
    EXPECT_GT(t["compute"].get<double>(), 0.0) << "registration and mapping take time after every capture";
    motion += t["motion"].get<double>();
    total += t["total"].get<double>();
  }
  EXPECT_NEAR(scan["rig_time_s"]["motion"].get<double>(), motion, 1e-9);
  EXPECT_NEAR(scan["rig_time_s"]["total"].get<double>(), total, 1e-9);
  EXPECT_EQ(scan["rig_time_s"]["views"], views);
  EXPECT_EQ(scan["rig_time_s"]["views_incomplete"], 0);
  EXPECT_NE(r.output.find("; rig time "), std::string::npos) << r.output;
  // Every process exited cleanly.
  const auto procs = read_json_file(out / "processes.json");
  for (const auto& p : procs["processes"]) EXPECT_EQ(p["exit_code"], 0) << p.dump();
  return out;
}

}  // namespace

TEST(ScanIntegration, SphereOnTheArmRigLiesOnTheTrueSurface) {
  const fs::path out = scan_and_check("sphere", "--object sphere --rig arm --planner ring", 4);
  const Distances d = cloud_to_mesh(out / "cloud.ply", out / "object.obj");
  std::cout << "sphere, arm rig: " << d.n << " points, median distance " << d.median * 1e3
            << " mm, 95th percentile " << d.p95 * 1e3 << " mm\n";
  EXPECT_GT(d.n, 5000u);
  // Measured 0.008-0.012 mm median, 0.026-0.035 mm p95 (docs/benchmark.md): five times that, so that a
  // regression of the pipeline's accuracy fails here.
  EXPECT_LE(d.median, 0.04e-3);
  EXPECT_LE(d.p95, 0.15e-3);
  // Four views 90 degrees apart see all around: points in every azimuth quadrant.
  const PointCloud cloud = read_ply((out / "cloud.ply").string());
  int quadrant[4] = {0, 0, 0, 0};
  for (const auto& p : cloud) quadrant[(p.x() >= 0 ? 0 : 1) + (p.y() >= 0 ? 0 : 2)]++;
  for (int q = 0; q < 4; ++q) EXPECT_GT(quadrant[q], 500) << "quadrant " << q;
}

// An uncalibrated rig (the camera mount 5 mm / 1 deg off the rig file's, the turntable zero
// 0.5 deg, 0.02 deg joint noise, 0.05 deg backlash): registration fits the mount to the 10 views'
// clouds and turntable tops (against the twin's truth, twin_rig.json: measured 1.8 and 4.1 mm,
// 0.09 and 0.22 deg in two runs; the target is 1 mm / 0.2 deg, not met yet: asserted
// within 5 mm / 0.3 deg, well inside the 5 mm / 1 deg it starts from) and moves the model into the
// object frame, where it lies within 1.5 mm of the true surface (median; measured 0.62 mm, p95 1.6
// mm): the turn about the object the estimate leaves loose moves the surface little.
// Without the estimate docs/benchmark.md measured 7 mm.
TEST(ScanIntegration, AnUncalibratedMountIsEstimatedAcrossTheViews) {
  const fs::path out = scan_and_check("bunny-uncalibrated", "--object bunny --rig arm --planner pbnbv --rig-errors uncalibrated", 10);
  const auto coverage = read_json_file(out / "coverage.json");
  ASSERT_TRUE(coverage["hand_eye"].is_object()) << coverage.dump(2);
  const auto& h = coverage["hand_eye"];
  std::cout << "bunny, uncalibrated arm: the mount estimated over " << h["views"] << " views " << h["error_mm"] << " mm, "
            << h["error_deg"] << " deg from the truth (" << h["true_mm"] << " mm, " << h["true_deg"] << " deg)\n";
  EXPECT_NEAR(h["true_mm"].get<double>(), 5.0, 1e-6);
  EXPECT_LT(h["error_mm"].get<double>(), 5.0);
  EXPECT_LT(h["error_deg"].get<double>(), 0.3);
  const auto hand_eye = read_json_file(out / "hand_eye.json");
  const Pose applied = pose_from_json(hand_eye["applied_object_T_model"], "hand_eye.json applied_object_T_model");
  EXPECT_GT(applied.translation().norm(), 1e-3);  // the model was moved, by millimetres
  const Distances d = cloud_to_mesh(out / "cloud.ply", out / "object.obj");
  std::cout << "  cloud to the true surface: median " << d.median * 1e3 << " mm, p95 " << d.p95 * 1e3 << " mm\n";
  EXPECT_LE(d.median, 1.5e-3);
  EXPECT_LE(d.p95, 4e-3);
}

TEST(ScanIntegration, BoxOnTheArmRigLiesOnTheTrueSurface) {
  const fs::path out = scan_and_check("box", "--object box --rig arm --planner ring", 4);
  const Distances d = cloud_to_mesh(out / "cloud.ply", out / "object.obj");
  std::cout << "box, arm rig: " << d.n << " points, median distance " << d.median * 1e3
            << " mm, 95th percentile " << d.p95 * 1e3 << " mm\n";
  EXPECT_GT(d.n, 5000u);
  // Measured 0.008-0.012 mm median, 0.026-0.035 mm p95 (docs/benchmark.md): five times that, so that a
  // regression of the pipeline's accuracy fails here.
  EXPECT_LE(d.median, 0.04e-3);
  EXPECT_LE(d.p95, 0.15e-3);
}

// A two-coloured object (a PLY with vertex colours: a 10 x 6 x 8 cm box, red for x > 0, blue for
// x < 0) scanned in 3 views: the twin draws it in its colours, the frames carry JPEG colour images,
// and cloud.ply and mesh.ply come out with the colours on the right halves: of the points more than
// 3 mm from the seam (the cloud's voxels there average both sides), at least 99.5 % of the cloud's
// and 99 % of the mesh's vertices (measured 99.81-99.85 % and 99.56-99.62 % with the twin's colour
// image at half the depth image's resolution: the rest lie on the outline, where the colour image's
// coarser pixels and JPEG's half-resolution chroma blur the object into the background, and on the
// mesh's edges beyond the seen surface). colour/view_NNN.jpg holds each view's colour image, its
// camera in depth/view_NNN.json. With --units mm, mesh.obj is in millimetres (mesh.ply stays in
// metres): the same vertices x 1000.
TEST(ScanIntegration, ATwoColouredObjectComesOutInItsColours) {
  const fs::path dir = fresh_dir("two-coloured-object");
  const fs::path ply = dir / "two.ply";
  {
    std::ofstream out(ply);
    std::ostringstream v, f;
    int n = 0, faces = 0;
    const double a = 0.05, b = 0.03, c = 0.04;
    // One box half per colour, each face two triangles counter-clockwise seen from outside; the
    // faces at x = 0 are left out (inside).
    const auto quad = [&](std::array<Eigen::Vector3d, 4> q, const char* rgb) {
      for (const auto& p : q) v << p.x() << " " << p.y() << " " << p.z() << " " << rgb << "\n";
      f << "3 " << n << " " << n + 1 << " " << n + 2 << "\n3 " << n << " " << n + 2 << " " << n + 3 << "\n";
      n += 4;
      faces += 2;
    };
    for (const int side : {1, -1}) {
      const char* rgb = side > 0 ? "220 30 30" : "30 30 220";
      const double x0 = side > 0 ? 0 : -a, x1 = side > 0 ? a : 0;
      quad({Eigen::Vector3d(x0, b, -c), {x0, b, c}, {x1, b, c}, {x1, b, -c}}, rgb);
      quad({Eigen::Vector3d(x0, -b, -c), {x1, -b, -c}, {x1, -b, c}, {x0, -b, c}}, rgb);
      quad({Eigen::Vector3d(x0, -b, c), {x1, -b, c}, {x1, b, c}, {x0, b, c}}, rgb);
      quad({Eigen::Vector3d(x0, -b, -c), {x0, b, -c}, {x1, b, -c}, {x1, -b, -c}}, rgb);
      if (side > 0) {
        quad({Eigen::Vector3d(a, -b, -c), {a, b, -c}, {a, b, c}, {a, -b, c}}, rgb);
      } else {
        quad({Eigen::Vector3d(-a, -b, -c), {-a, -b, c}, {-a, b, c}, {-a, b, -c}}, rgb);
      }
    }
    out << "ply\nformat ascii 1.0\nelement vertex " << n
        << "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
           "property uchar blue\nelement face "
        << faces << "\nproperty list uchar int vertex_indices\nend_header\n"
        << v.str() << f.str();
  }
  const fs::path out =
      scan_and_check("two-coloured-scan", "--object " + ply.string() + " --rig arm --planner ring --units mm", 3);
  EXPECT_TRUE(fs::exists(out / "object.ply"));  // the normalised object with its colours, for the twin
  const auto halves = [](const PointCloud& points, const std::vector<Rgb>& colours, double share, const char* what) {
    ASSERT_EQ(colours.size(), points.size()) << what << " has no colours";
    long red = 0, right = 0, blue = 0, left = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Rgb& c = colours[i];
      if (points[i].x() > 0.003f) {
        ++right;
        red += c[0] > 2 * c[2] ? 1 : 0;
      } else if (points[i].x() < -0.003f) {
        ++left;
        blue += c[2] > 2 * c[0] ? 1 : 0;
      }
    }
    std::cout << what << ": " << red << " of " << right << " points right of the seam red, " << blue << " of " << left
              << " left of it blue\n";
    EXPECT_GT(right, 1000) << what;
    EXPECT_GT(left, 1000) << what;
    EXPECT_GE(static_cast<double>(red), share * static_cast<double>(right)) << what;
    EXPECT_GE(static_cast<double>(blue), share * static_cast<double>(left)) << what;
  };
  CloudExtras extras;
  const PointCloud cloud = read_ply((out / "cloud.ply").string(), extras);
  halves(cloud, extras.colours, 0.995, "cloud.ply");
  CloudExtras mesh_extras;
  const PointCloud vertices = read_ply((out / "mesh.ply").string(), mesh_extras);  // its vertices
  halves(vertices, mesh_extras.colours, 0.99, "mesh.ply");
  // The colour images and their camera.
  EXPECT_TRUE(fs::exists(out / "colour" / "view_001.jpg"));
  const auto depth_json = read_json_file(out / "depth" / "view_001.json");
  ASSERT_TRUE(depth_json.contains("colour")) << depth_json.dump(2);
  EXPECT_EQ(depth_json["colour"]["image"], "../colour/view_001.jpg");
  // The twin's colour sensor: the depth camera at half the resolution (--colour-scale 0.5).
  EXPECT_EQ(2 * depth_json["colour"]["width"].get<int>(), depth_json["width"].get<int>());
  EXPECT_DOUBLE_EQ(2 * depth_json["colour"]["fx"].get<double>(), depth_json["fx"].get<double>());
  // --units mm: mesh.obj says so and is mesh.ply x 1000 (the object is 10 cm across: 50 mm from its centre).
  std::ifstream obj(out / "mesh.obj");
  const std::string text((std::istreambuf_iterator<char>(obj)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("# units millimetres\n"), std::string::npos);
  const TriangleMesh mm = load_mesh((out / "mesh.obj").string());
  Eigen::Vector3d lo_mm, hi_mm, lo_m, hi_m;
  mesh_bounds(mm, lo_mm, hi_mm);
  mesh_bounds(load_mesh((out / "mesh.ply").string()), lo_m, hi_m);
  EXPECT_LT((hi_mm - 1000 * hi_m).norm(), 1e-3) << hi_mm.transpose() << " vs " << hi_m.transpose();
  EXPECT_GT(hi_mm.x(), 40.0);
}

TEST(ScanIntegration, SphereOnTheFreeRigLiesOnTheTrueSurface) {
  const fs::path out = scan_and_check("sphere-free", "--object sphere --rig free --planner ring", 4);
  const Distances d = cloud_to_mesh(out / "cloud.ply", out / "object.obj");
  std::cout << "sphere, free rig: " << d.n << " points, median distance " << d.median * 1e3 << " mm\n";
  EXPECT_GT(d.n, 5000u);
  EXPECT_LE(d.median, 0.04e-3);  // measured 0.008 mm
  // The surface mesh the coordinator made at the end (core/surface): its vertices on the true
  // surface too, and recorded in scan.json.
  const auto scan = read_json_file(out / "scan.json");
  EXPECT_GT(scan["mesh"].value("triangles", 0), 1000) << scan["mesh"].dump();
  const Distances m = cloud_to_mesh(out / "mesh.ply", out / "object.obj");
  std::cout << "sphere, free rig, mesh: " << m.n << " vertices, median distance " << m.median * 1e3 << " mm\n";
  EXPECT_GT(m.n, 1000u);
  EXPECT_LE(m.median, 0.1e-3);  // measured 0.018 mm (TSDF, 2 mm voxels)
}

namespace {

pid_t start_scan(const fs::path& out, const std::string& options) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = netns_run() + " " + bin_dir() + "/pbnbv scan " + options + " --out " + out.string() +
                            " > " + (out.string() + ".stdout") + " 2>&1";
    ::execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

}  // namespace

TEST(ScanIntegration, CtrlCStopsEveryProcessAndKeepsTheScanSoFar) {
  const fs::path out = fresh_dir("interrupt") / "scan";
  const pid_t pid = start_scan(out, "--object sphere --planner ring --views 40 --sim-speed 2 --no-log");
  ASSERT_TRUE(wait_for_views(out, 1, 60)) << "no view recorded";
  ::kill(pid, SIGINT);
  const int code = wait_exit(pid, 30);
  EXPECT_EQ(code, 130);
  const auto scan = read_json_file(out / "scan.json");
  EXPECT_EQ(scan["status"]["state"], "stopped");
  EXPECT_GE(scan["status"]["views_done"].get<int>(), 1);
  EXPECT_LT(scan["status"]["views_done"].get<int>(), 40);
  EXPECT_TRUE(fs::exists(out / "cloud.ply"));
  const auto procs = read_json_file(out / "processes.json");
  for (const auto& p : procs["processes"]) {
    if (p["name"] != "coordinator") {
      EXPECT_EQ(p["exit_code"], 0) << p.dump();
    }
  }
  const CommandResult left = run_command("pgrep -f 'model-ou[t] " + out.string() + "'");
  EXPECT_NE(left.exit_code, 0) << "a twin is still running: " << left.output;
}

TEST(ScanIntegration, AProcessThatKeepsDyingStopsTheScanWithItsName) {
  const fs::path out = fresh_dir("crash") / "scan";
  const pid_t pid = start_scan(out, "--object sphere --planner ring --views 40 --sim-speed 2 --no-log");
  ASSERT_TRUE(wait_for_views(out, 1, 60)) << "no view recorded";
  // Kill this scan's twin (its arguments name the output folder) each time it is started again:
  // after 3 restarts the launcher gives up.
  int kills = 0;
  int code = -1;
  for (int i = 0; i < 400 && code < 0; ++i) {
    if (run_command("pkill -KILL -f 'model-ou[t] " + out.string() + "/twin_model.xml'").exit_code == 0) ++kills;
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (code < 0) code = wait_exit(pid, 30);
  EXPECT_EQ(code, 1);
  EXPECT_EQ(kills, 4);
  std::ifstream in(out.string() + ".stdout");
  const std::string said((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(said.find("twin stopped unexpectedly (killed by signal 9 (SIGKILL), after 3 restarts)"), std::string::npos)
      << said;
  const auto scan = read_json_file(out / "scan.json");
  EXPECT_EQ(scan["status"]["state"], "failed");
  EXPECT_NE(scan["status"]["message"].get<std::string>().find("twin stopped unexpectedly"), std::string::npos);
  const CommandResult left = run_command("pgrep -a -f 'pbnbv-[m]otion|pbnbv-[c]amera|pbnbv-[c]oordinator'");
  // Other tests may run scans in parallel: look only for processes of this scan.
  EXPECT_EQ(left.output.find(out.string()), std::string::npos) << left.output;
}
