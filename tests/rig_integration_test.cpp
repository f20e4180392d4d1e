// The physical-rig path, proven against the twin started on its own as "the hardware" (exactly as
// a driver would be started): `pbnbv scan --external-rig` starts no twin, is given no mesh, waits
// for the drivers and scans an unknown object in the rig's working volume. Each case runs in its
// own private network namespace.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/geometry/mesh.hpp"
#include "core/io/mesh_file.hpp"
#include "core/geometry/working_volume.hpp"
#include "eval/evaluate.hpp"
#include "scan_checks.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;

namespace {

// The tests' twin renders 320 x 180 frames at the default camera's 696 px focal length; the rig
// files they scan with state that camera.
const char* const kSmallImage = "--width 320 --height 180";
const char* const kRigCamera = "320 180 696 696 160 90 0.1 3.0";

// A shell line that starts the twin as the rig's drivers (no --scan: it obeys every scan, as a
// real driver does), runs `commands`, stops the twin and exits with the commands' status.
std::string with_twin_as_hardware(const std::string& twin_options, const std::string& commands) {
  return netns_run() + " sh -c '" + bin_dir() + "/pbnbv-twin --speed 20 " + kSmallImage + " " + twin_options +
         " >/dev/null 2>&1 & T=$!; " + commands + "; rc=$?; kill $T; wait $T; exit $rc'";
}

std::string rig_model(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("pbnbv-test-rigs-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return rig_with_camera(source_dir() + "/models", name, dir, kRigCamera).string();
}

// Coverage after each view of an external-rig scan against the mesh the twin rendered:
// `twin_object_z` is where the twin put the mesh's frame above the turntable top; the scan's
// object frame sits at the working volume's centre, so the mesh is moved into it first.
std::vector<double> external_coverage(const fs::path& out, const fs::path& mesh_path, double twin_object_z) {
  const auto settings = read_json_file(out / "settings.json");
  const double scan_object_z = settings["object_z_m"].get<double>();
  TriangleMesh mesh = load_mesh(mesh_path.string());
  for (auto& v : mesh.vertices) v.z() += twin_object_z - scan_object_z;
  write_stl_binary(mesh, (out / "object.stl").string());
  return eval::evaluate_coverage(out).coverage_by_view;  // the coverage only
}

// A working volume as a user measures it: the object's bounding box rounded up to the centimetre.
std::string measured_volume(const fs::path& twin_run) {
  const auto settings = read_json_file(twin_run / "settings.json");
  std::string volume = "box:";
  for (int i = 0; i < 3; ++i) {
    const double edge = settings["object"]["normalisation"]["extent_m"][i].get<double>();
    volume += (i ? "," : "") + std::to_string(std::ceil(edge * 100) / 100);
  }
  return volume;
}

// The same object scanned the twin-in-the-loop way and as an unknown object on an external rig
// (the twin started separately with the same mesh): both complete, the external one without a
// mesh, given only a working volume measured as a user would (the object's bounding box rounded
// up to the next centimetre). Both start from the same first view, so their first views cover the
// same surface; from view 2 on they plan from two boxes, and their coverage after 6 views differs
// by what two plans differ by (below).
void compare_with_twin_in_the_loop(const std::string& name, const std::string& model) {
  const fs::path twin_run = fresh_dir(name + "-twin-in-the-loop");
  const std::string options = "--rig-model " + rig_model(model) + " --views 6";
  const CommandResult a = run_command(netns_run() + " " + bin_dir() + "/pbnbv scan --object bunny " + options + " " +
                                      kSmallImage + " --sim-speed 20 --out " + twin_run.string());
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const std::vector<double> twin_coverage =
      read_json_file(twin_run / "coverage.json")["coverage_by_view"].get<std::vector<double>>();
  ASSERT_EQ(twin_coverage.size(), 6u);
  const double object_z = read_json_file(twin_run / "settings.json")["object_z_m"].get<double>();
  const std::string volume = measured_volume(twin_run);

  const fs::path external = fresh_dir(name + "-external");
  const CommandResult b = run_command(with_twin_as_hardware(
      "--model " + rig_model(model) + " --mesh " + (twin_run / "object.stl").string() + " --object-z " +
          std::to_string(object_z) + " --model-out " + (external.parent_path() / (name + "-hw.xml")).string(),
      bin_dir() + "/pbnbv scan --external-rig " + options + " --working-volume " + volume + " --out " + external.string()));
  ASSERT_EQ(b.exit_code, 0) << b.output;
  EXPECT_NE(b.output.find("ARM_STATUS rate                     | pass"), std::string::npos) << b.output;
  EXPECT_NE(b.output.find("no coverage: the object is unknown"), std::string::npos) << b.output;
  // No twin, no mesh: the settings hold the working volume, not a normalisation.
  const auto procs = read_json_file(external / "processes.json");
  for (const auto& p : procs["processes"]) {
    EXPECT_NE(p["name"], "twin");
    EXPECT_EQ(p["exit_code"], 0) << p.dump();
  }
  const auto settings = read_json_file(external / "settings.json");
  EXPECT_TRUE(settings["external_rig"].get<bool>());
  EXPECT_FALSE(settings["object"].contains("normalisation"));
  const WorkingVolume w = parse_working_volume(settings["object"]["working_volume"].get<std::string>());
  EXPECT_EQ(w.to_text(), parse_working_volume(volume).to_text());
  EXPECT_DOUBLE_EQ(settings["object_z_m"].get<double>(), w.height_m / 2);  // the volume's centre
  EXPECT_FALSE(fs::exists(external / "object.stl"));
  const auto scan = read_json_file(external / "scan.json");
  EXPECT_EQ(scan["status"]["state"], "done");
  EXPECT_EQ(scan["views"].size(), 6u);

  const std::vector<double> external_coverage_pct = external_coverage(external, twin_run / "object.stl", object_z);
  ASSERT_EQ(external_coverage_pct.size(), 6u);
  std::cout << name << ": coverage after views 1 and 6, twin in the loop " << twin_coverage.front() << " and "
            << twin_coverage.back() << " %, external rig " << external_coverage_pct.front() << " and "
            << external_coverage_pct.back() << " %\n";
  // The first view is the same view of the same object: an object frame placed wrongly in the
  // working volume, or a turntable or camera taken the wrong way, shows here (the cloud would miss
  // the mesh). Measured 25.28 / 24.80 % (KUKA) and 25.32 / 24.77 % (UR5e): the external object
  // frame, at the volume's centre, is 3 mm above the twin's.
  EXPECT_NEAR(external_coverage_pct.front(), twin_coverage.front(), 1.0);
  // Two scans of one object whose B (mesh box against working volume) differ plan differently
  // from view 2 on, and a greedy plan is sensitive to its input: the twin-in-the-loop scan of this
  // bunny on the KUKA with its size changed by 0.5-1.5 % (--size 0.296-0.3045, eight scans) covers
  // 73.5-77.3 % after 6 views, against 78.4 % at 0.3 (stop 57). Measured pairs (twin in the loop /
  // external): with the path checks (stop 46) 78.35-78.49 / 73.59-73.94 % (KUKA) and 74.87-77.04 /
  // 76.49-76.78 % (UR5e); with the quickest move (stop 57) 78.34-78.36 / 70.93-73.92 % (KUKA,
  // nine runs; 71.22 % in CI) and 74.74-76.51 / 75.64-76.23 % (UR5e, six runs). The external
  // plan on the KUKA stays behind at 10 views too (75.2 and 76.9 % against 80.5 %), and with the
  // least turn (73.8 and 74.4 % after 6 views, 74.9 and 75.6 % after 10): it is that plan, not
  // the external path. After 6 views two such plans differ by up to 7.5 points either way.
  EXPECT_NEAR(external_coverage_pct.back(), twin_coverage.back(), 8.5);
}

}  // namespace

TEST(ExternalRig, AnUnknownObjectIsScannedAsWellAsWithTheTwinInTheLoop) {
  compare_with_twin_in_the_loop("kuka", "rig_arm.xml");
}

// The same on the UR5e (a non-spherical wrist: the general IK in the view scorer and the motion
// executor).
TEST(ExternalRig, AnUnknownObjectIsScannedAsWellOnTheUr5e) {
  compare_with_twin_in_the_loop("ur5e", "rig_ur5e.xml");
}

// --dry-run checks the drivers, plans the first view and its reachability, prints the commands it
// would send, and sends none: lcm-logger records the bus meanwhile and holds no ARM_COMMAND.
TEST(ExternalRig, ADryRunCommandsNothing) {
  const fs::path dir = fresh_dir("external-dry-run");
  const std::string log = (dir / "bus.lcmlog").string();
  // The dry run starts once the logger has recorded a message (the twin's statuses, 100 Hz), for
  // at most 10 s: a fixed 0.5 s was not always enough for lcm-logger to start on a loaded machine,
  // and the run's one DEPTH_TRIGGER went unrecorded (CI run of this stop, beside three scans).
  const std::string wait_until_recording = "for i in $(seq 100); do [ -s " + log + " ] && break; sleep 0.1; done; ";
  const CommandResult r = run_command(with_twin_as_hardware(
      "--model-out " + (dir / "hw.xml").string(),
      "/usr/bin/lcm-logger -q -f " + log + " & L=$!; " + wait_until_recording + bin_dir() +
          "/pbnbv scan --external-rig --rig-model " + rig_model("rig_arm.xml") + " --dry-run; rc=$?; sleep 0.3; kill $L; wait $L; (exit $rc)"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("dry run: nothing is commanded"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("view 1 at"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("ARM_COMMAND ["), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("candidate views around the working volume are reachable"), std::string::npos) << r.output;
  std::ifstream in(log, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_GT(bytes.size(), 10000u) << "the logger heard the twin's statuses";
  EXPECT_NE(bytes.find("ARM_STATUS"), std::string::npos);
  EXPECT_NE(bytes.find("DEPTH_TRIGGER"), std::string::npos);  // the driver check asks for one frame
  EXPECT_EQ(bytes.find("ARM_COMMAND"), std::string::npos);
  EXPECT_EQ(bytes.find("TURNTABLE_COMMAND"), std::string::npos);
}

// A first view the arm cannot reach (below the table's edge: elevation atan(-0.35 / 0.7) =
// -26.6 deg) is not refused when a fallback of first_view_options is reachable: the dry run
// shows the view the scan will start from, the first option 20 deg higher (-6.6 deg, so
// z = 0.783 sin(-6.6 deg) = -0.089 m at the same distance).
TEST(ExternalRig, ADryRunShowsTheFallbackForAnUnreachableFirstView) {
  const fs::path dir = fresh_dir("external-dry-run-fallback");
  const CommandResult r = run_command(with_twin_as_hardware(
      "--model-out " + (dir / "hw.xml").string(),
      bin_dir() + "/pbnbv scan --external-rig --rig-model " + rig_model("rig_arm.xml") +
          " --dry-run --initial-view 0.7,0,-0.35"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("the first view is unreachable ("), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the scan starts from fallback 8 of first_view_options"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("view 1 at (0.777, 0.000, -0.089) m: ARM_COMMAND ["), std::string::npos) << r.output;
}

// No driver on the bus: the scan names each missing one after --driver-timeout, creates no output
// folder and starts nothing.
TEST(ExternalRig, ADriverThatNeverAnswersIsNamed) {
  const fs::path out = fresh_dir("external-no-driver");
  fs::remove_all(out);
  const CommandResult r = run_command(netns_run() + " " + bin_dir() + "/pbnbv scan --external-rig --driver-timeout 1.5 --out " +
                                      out.string());
  EXPECT_NE(r.exit_code, 0);
  for (const char* missing : {"no ARM_STATUS in 1.5 s", "no TURNTABLE_STATUS in 1.5 s", "no DEPTH_FRAME"}) {
    EXPECT_NE(r.output.find(missing), std::string::npos) << missing << "\n" << r.output;
  }
  EXPECT_NE(r.output.find("the rig's drivers failed the check (nothing was commanded to move"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

// A working volume the arm cannot see around: refused before anything moves, naming the rig file,
// the volume and why the first view is out of reach. (0.9 m round the axis turns clear of the
// KUKA's pedestal, 0.97 m from it; a wider one is refused before the drivers are asked:
// Faults.ObjectsNoRigCanScanAreRefusedUpFront.)
TEST(ExternalRig, AWorkingVolumeTheArmCannotReachIsRefused) {
  const fs::path dir = fresh_dir("external-unreachable");
  const CommandResult r = run_command(with_twin_as_hardware(
      "--model-out " + (dir / "hw.xml").string(),
      bin_dir() + "/pbnbv scan --external-rig --rig-model " + rig_model("rig_arm.xml") +
          " --working-volume cylinder:0.9,2 --out " + (dir / "out").string()));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("around the working volume cylinder:0.9,2 cannot reach the first view"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// Two hosts joined by a link (network namespaces and a veth pair, multicast ttl=1): the rig's
// computer runs the twin as the drivers plus the motion executor and the camera service
// (pbnbv rig-host); the compute host runs the rest (pbnbv scan --external-rig --rig-host). The scan
// completes with the coverage of the same scan on one host.
TEST(TwoHosts, AScanAcrossALinkCoversWhatItDoesOnOneHost) {
  const fs::path twin_run = fresh_dir("two-hosts-object");
  const CommandResult a = run_command(netns_run() + " " + bin_dir() + "/pbnbv scan --object bunny --views 1 " + kSmallImage +
                                      " --sim-speed 20 --no-log --out " + twin_run.string());
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const double object_z = read_json_file(twin_run / "settings.json")["object_z_m"].get<double>();
  const std::string twin = "--mesh " + (twin_run / "object.stl").string() + " --object-z " + std::to_string(object_z);
  const std::string rig = rig_model("rig_arm.xml");
  // Registration off, as in NbvIntegration.Ur5eRigScansLikeTheKuka: the twin's kinematic poses are
  // exact, and an ICP rejection (a registration matter, not the link's) drops a view from one scan
  // only (seen: "not converged" at a 0.01 mm correction, 67 % against 72.8 %).
  const std::string scan = "--rig-model " + rig + " --views 5 --registration off --working-volume " + measured_volume(twin_run);

  const fs::path one = fresh_dir("one-host");
  const CommandResult b = run_command(with_twin_as_hardware(
      twin + " --model " + rig + " --model-out " + (one / "hw.xml").string(),
      bin_dir() + "/pbnbv scan --external-rig " + scan + " --out " + (one / "scan").string()));
  ASSERT_EQ(b.exit_code, 0) << b.output;

  const fs::path two = fresh_dir("two-hosts");
  const CommandResult c = run_command("PBNBV_BIN_DIR=" + bin_dir() + " " + source_dir() + "/tests/two_hosts.sh " +
                                      two.string() + " " + rig + " '" + twin + " " + kSmallImage + "' '" + scan + "'");
  ASSERT_EQ(c.exit_code, 0) << c.output << "\n" << run_command("tail -n 20 " + (two / "rig-host" / "*.log").string()).output;
  // The compute host started neither the motion executor nor the camera: the rig host's served it.
  for (const auto& p : read_json_file(two / "scan" / "processes.json")["processes"]) {
    EXPECT_NE(p["name"], "motion");
    EXPECT_NE(p["name"], "camera");
  }
  const std::vector<double> one_by_view = external_coverage(one / "scan", twin_run / "object.stl", object_z);
  const std::vector<double> two_by_view = external_coverage(two / "scan", twin_run / "object.stl", object_z);
  // No view lost on the link: both scans took all five.
  ASSERT_EQ(one_by_view.size(), 5u);
  ASSERT_EQ(two_by_view.size(), 5u);
  const auto two_scan = read_json_file(two / "scan" / "scan.json");
  EXPECT_EQ(two_scan["views"].size(), 5u);
  const double one_host = one_by_view.back();
  const double two_hosts = two_by_view.back();
  const double log_mb = fs::file_size(two / "scan" / "scan.lcmlog") / 1e6;
  const double seconds = two_scan["status"]["elapsed_s"].get<double>();
  std::cout << "coverage after views 1 and 5: one host " << one_by_view.front() << " and " << one_host << " %, two hosts "
            << two_by_view.front() << " and " << two_hosts << " %; the link carried " << log_mb << " MB in " << seconds
            << " s\n";
  // The first view is the same view in both: a frame lost or mangled on the link shows here.
  EXPECT_NEAR(two_by_view.front(), one_by_view.front(), 0.5);
  // Scans of one setup differ by the views the planner picks from poses the physics settles a
  // fraction of a millimetre apart: measured 71.82, 71.83, 72.79 and 73.31 % (one host and two,
  // 2026-12-05, idle and beside the packet-loss case); with the quickest move (stop 57) one host
  // 73.07-73.09 % in seven runs, two hosts 72.91-73.09 % or, when a later view's plan branches,
  // 70.89 and 70.91 % (two of seven runs, one in CI), so two draws differ by up to 2.2 points. A
  // view lost on the link costs 5 or more (one of five views; 67 against 72.8 % when ICP dropped
  // one), and the view counts above catch it directly.
  EXPECT_NEAR(two_hosts, one_host, 3.0);
}

// The driver's frames are not the camera the rig file states (the twin renders 320 x 180, the
// shipped rig file says 1280 x 720): the scan is refused before anything moves, naming the frame
// size and the rig file's, and leaves no output folder.
TEST(ExternalRig, AFrameWhoseSizeDisagreesWithTheRigFileIsNamed) {
  const fs::path dir = fresh_dir("external-frame-size");
  const CommandResult r = run_command(with_twin_as_hardware(
      "--model-out " + (dir / "hw.xml").string(),
      bin_dir() + "/pbnbv scan --external-rig --out " + (dir / "out").string()));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("frame size 320x180 disagrees with the rig file's camera 1280x720"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("nothing was commanded to move"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}
