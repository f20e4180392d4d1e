// A scan's processes from its settings: every argv built from settings.json and the executables'
// folder (every path a process writes to inside the scan's folder), the launcher's own settings
// kept and checked, and the folder checks of `pbnbv scan --resume` (another scan's record, a scan
// id that is not one, a rig file in another scan's folder: re-rooted into a copy that has it,
// refused otherwise).
#include "launcher/scan_processes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/scan/scan_file.hpp"
#include "core/io/json.hpp"

namespace fs = std::filesystem;

namespace pbnbv::launcher {
namespace {

const char* kScanId = "sphere-0123456789abcdef";

// The settings of a 0.3 m sphere scan on the arm rig, as run_scan makes them.
ScanSettings sphere_settings() {
  ScanSettings s;
  s.scan_id = kScanId;
  s.rig = RigKind::kArm;
  s.rig_model_path = std::string(PBNBV_MODELS_DIR) + "/rig_arm.xml";
  s.planner = PlannerKind::kPbnbv;
  s.object_name = "sphere";
  s.normalisation.source_path = "sphere";
  s.normalisation.scale = 1;
  s.normalisation.extent_m = Eigen::Vector3d::Constant(0.3);
  s.normalisation.num_vertices = 642;
  s.normalisation.num_triangles = 1280;
  place_object(s);
  s.validate();
  return s;
}

// The argument after `flag` in argv ("" when there is none).
std::string after(const std::vector<std::string>& argv, const std::string& flag) {
  const auto it = std::find(argv.begin(), argv.end(), flag);
  return it == argv.end() || it + 1 == argv.end() ? "" : *(it + 1);
}

// A scan folder as `pbnbv scan` leaves it after a few views: settings.json, object.stl, scan.json.
fs::path scan_folder(const fs::path& dir, const ScanSettings& s, const LaunchSettings& l) {
  fs::remove_all(dir);
  fs::create_directories(dir / "logs");
  write_scan_settings(s, l, dir);
  std::ofstream(dir / "object.stl") << "solid sphere\nendsolid sphere\n";
  write_json_atomic({{"format_version", kScanFormatVersion}, {"settings", to_json(s)}, {"status", {{"state", "stopped"}, {"views_done", 3}}}},
                    (dir / "scan.json").string());
  return dir;
}

fs::path test_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("pbnbv-scan-processes-test-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// The message of the std::invalid_argument `f` throws ("" when it throws none).
template <class F>
std::string refusal(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(ScanProcesses, EveryArgvComesFromTheSettingsAndWritesInsideTheFolder) {
  const ScanSettings s = sphere_settings();
  LaunchSettings l;
  l.noise_sigma = 0.002;
  l.error_seed = 11;
  const fs::path out = "/data/scans/sphere-a", bin = "/opt/pbnbv/bin";
  const std::vector<process::Child> c = scan_processes(s, l, out, bin);
  std::vector<std::string> names;
  for (const auto& p : c) names.push_back(p.name);
  EXPECT_EQ(names, (std::vector<std::string>{"lcm-logger", "twin", "motion", "camera", "registration", "mapping",
                                             "ellipsoids", "scorer", "coordinator"}));
  for (const auto& p : c) {
    ASSERT_FALSE(p.argv.empty()) << p.name;
    EXPECT_EQ(p.argv[0], p.name == "lcm-logger" ? "/usr/bin/lcm-logger" : (bin / ("pbnbv-" + p.name)).string());
    EXPECT_EQ(p.log_path, (out / "logs" / (p.name + ".log")).string());
    if (p.name != "lcm-logger" && p.name != "coordinator") EXPECT_EQ(after(p.argv, "--scan"), kScanId) << p.name;
    // Every absolute path given is the program, the rig file or a path in the scan's folder.
    for (std::size_t i = 1; i < p.argv.size(); ++i) {
      const std::string& a = p.argv[i];
      if (a.empty() || a[0] != '/' || a == s.rig_model_path) continue;
      EXPECT_EQ(a.rfind(out.string(), 0), 0u) << p.name << ": " << a << " is outside " << out;
    }
  }
  const auto& twin = c[1].argv;
  EXPECT_EQ(after(twin, "--mesh"), (out / "object.stl").string());
  EXPECT_EQ(after(twin, "--truth-out"), (out / "twin_truth.jsonl").string());
  EXPECT_EQ(after(twin, "--noise-sigma"), "0.002");
  EXPECT_EQ(after(twin, "--error-seed"), "11");
  EXPECT_EQ(after(c[0].argv, "-f"), (out / "scan.lcmlog").string());
  EXPECT_EQ(after(c[7].argv, "--out"), out.string()) << "the scorer's figures go to the scan's plans/";
  EXPECT_EQ(c.back().argv, (std::vector<std::string>{(bin / "pbnbv-coordinator").string(), "--out", out.string()}));
  EXPECT_TRUE(c.back().stdout_to_terminal) << "the coordinator's progress lines";

  // No log, registration off: no lcm-logger, the registration service --off.
  l.record_log = false;
  l.registration = false;
  const std::vector<process::Child> quiet = scan_processes(s, l, out, bin);
  EXPECT_EQ(quiet.front().name, "twin");
  EXPECT_EQ(quiet[3].name, "registration");
  EXPECT_EQ(quiet[3].argv.back(), "--off");
}

TEST(ScanProcesses, AnExternalRigOnItsHostStartsNoTwinNoMotionNoCamera) {
  ScanSettings s = sphere_settings();
  s.external_rig = true;
  LaunchSettings l;
  l.rig_host = true;
  std::vector<std::string> names;
  for (const auto& p : scan_processes(s, l, "/data/scans/x", "/opt/pbnbv/bin")) names.push_back(p.name);
  EXPECT_EQ(names, (std::vector<std::string>{"lcm-logger", "registration", "mapping", "ellipsoids", "scorer", "coordinator"}));
}

TEST(ScanProcesses, LaunchSettingsRoundTripAndBadValuesAreNamed) {
  LaunchSettings l;
  l.record_log = false;
  l.registration = false;
  l.dropout = 0.25;
  l.turntable_error_deg = -1.5;
  l.error_seed = 99;
  l.surface_metrics = false;
  const LaunchSettings back = launch_settings_from_json(to_json(l), "settings.json");
  EXPECT_EQ(back.record_log, false);
  EXPECT_EQ(back.surface_metrics, false);
  EXPECT_EQ(back.registration, false);
  EXPECT_EQ(back.rig_host, false);
  EXPECT_EQ(back.dropout, 0.25);
  EXPECT_EQ(back.turntable_error_deg, -1.5);
  EXPECT_EQ(back.error_seed, 99);

  nlohmann::json j = to_json(l);
  j["noise_sigma"] = 5;
  EXPECT_EQ(refusal([&] { launch_settings_from_json(j, "DIR/settings.json"); }),
            "DIR/settings.json: launch.noise_sigma 5 is outside the range of --noise-sigma [0, 0.1]");
  j = to_json(l);
  j["registration"] = "yes";
  EXPECT_EQ(refusal([&] { launch_settings_from_json(j, "DIR/settings.json"); }),
            "DIR/settings.json: launch.registration is \"yes\", not true or false");
  j = to_json(l);
  j["error_seed"] = 1.5;
  EXPECT_EQ(refusal([&] { launch_settings_from_json(j, "DIR/settings.json"); }),
            "DIR/settings.json: launch.error_seed is 1.5, not an integer");
  // A folder from before --no-surface-metrics resumes with the metrics.
  j = to_json(l);
  j.erase("surface_metrics");
  EXPECT_TRUE(launch_settings_from_json(j, "DIR/settings.json").surface_metrics);
  j = to_json(l);
  j.erase("dropout");
  EXPECT_EQ(refusal([&] { launch_settings_from_json(j, "DIR/settings.json"); }),
            "DIR/settings.json: \"launch\" has no \"dropout\"");
}

TEST(ScanProcesses, ACopiedFolderResumesAsItself) {
  const fs::path dir = test_dir("copy");
  LaunchSettings l;
  l.noise_sigma = 0.001;
  const fs::path original = scan_folder(dir / "original", sphere_settings(), l);
  const fs::path copy = dir / "copy";
  fs::copy(original, copy, fs::copy_options::recursive);
  const Resumable r = read_resumable(copy);
  EXPECT_EQ(r.settings.scan_id, kScanId);
  EXPECT_EQ(r.launch.noise_sigma, 0.001);
  EXPECT_EQ(r.rerooted, "");
  for (const auto& p : scan_processes(r.settings, r.launch, copy, "/opt/pbnbv/bin")) {
    for (const std::string& a : p.argv) {
      EXPECT_EQ(a.find(original.string()), std::string::npos) << p.name << " is given " << a << " of the original";
    }
  }
}

TEST(ScanProcesses, ARigFileInTheOriginalsFolderIsReRootedOrRefused) {
  const fs::path dir = test_dir("rig");
  ScanSettings s = sphere_settings();
  const fs::path original = dir / "original";
  s.rig_model_path = (original / "rig_calibrated.xml").string();
  scan_folder(original, s, LaunchSettings{});
  fs::copy_file(std::string(PBNBV_MODELS_DIR) + "/rig_arm.xml", original / "rig_calibrated.xml");
  const fs::path copy = dir / "copy";
  fs::copy(original, copy, fs::copy_options::recursive);

  const Resumable r = read_resumable(copy);
  EXPECT_EQ(r.settings.rig_model_path, (copy / "rig_calibrated.xml").string());
  EXPECT_EQ(r.rerooted, "rig_model_path " + (original / "rig_calibrated.xml").string() + " -> " +
                            (copy / "rig_calibrated.xml").string());
  EXPECT_EQ(read_resumable(original).settings.rig_model_path, (original / "rig_calibrated.xml").string());

  fs::remove(copy / "rig_calibrated.xml");
  EXPECT_EQ(refusal([&] { read_resumable(copy); }),
            "--resume " + copy.string() + ": " + (copy / "settings.json").string() + "'s rig_model_path " +
                (original / "rig_calibrated.xml").string() + " lies in another scan's folder (" + original.string() +
                ") and " + copy.string() + " has no rig_calibrated.xml: the scan would use that folder");
}

TEST(ScanProcesses, AFolderThatIsNotOneResumableScanIsRefused) {
  const fs::path dir = test_dir("refused");
  const ScanSettings s = sphere_settings();
  const std::string where = "--resume " + (dir / "scan").string() + ": ";
  const std::string settings = (dir / "scan" / "settings.json").string();

  // scan.json of another scan.
  fs::path out = scan_folder(dir / "scan", s, LaunchSettings{});
  ScanSettings other = s;
  other.scan_id = "box-fedcba9876543210";
  write_json_atomic({{"format_version", kScanFormatVersion}, {"settings", to_json(other)}, {"status", {{"state", "stopped"}}}},
                    (out / "scan.json").string());
  EXPECT_EQ(refusal([&] { read_resumable(out); }),
            where + (out / "scan.json").string() + " is a record of scan \"box-fedcba9876543210\", " + settings +
                " of scan \"" + kScanId + "\": the folder mixes two scans");

  // No "launch": a replay's folder or an older scan.
  out = scan_folder(dir / "scan", s, LaunchSettings{});
  write_json_atomic(to_json(s), settings);
  EXPECT_NE(refusal([&] { read_resumable(out); }).find(settings + " has no \"launch\" settings"), std::string::npos);

  // A scan id that would be read as an option.
  ScanSettings flag = s;
  flag.scan_id = "--out";
  out = scan_folder(dir / "scan", flag, LaunchSettings{});
  EXPECT_EQ(refusal([&] { read_resumable(out); }),
            where + settings + ": scan_id \"--out\" is not a scan id (letters, digits, '-', '_' and '.', not starting with '-')");

  // No twin object, no settings, no folder.
  out = scan_folder(dir / "scan", s, LaunchSettings{});
  fs::remove(out / "object.stl");
  EXPECT_EQ(refusal([&] { read_resumable(out); }), where + (out / "object.stl").string() + " is missing (the twin's object)");
  fs::remove(out / "settings.json");
  EXPECT_EQ(refusal([&] { read_resumable(out); }), where + "no scan to resume there (settings.json is missing)");
  EXPECT_EQ(refusal([&] { read_resumable(dir / "nowhere"); }), "--resume " + (dir / "nowhere").string() + ": no such folder");
}

}  // namespace
}  // namespace pbnbv::launcher
