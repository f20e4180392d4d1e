// `pbnbv`'s command line: every default comes from the table of scan options, the defaults that
// depend on the rig are resolved, a settings file sets options and the command line overrides
// it, and each bad option is named (with its value and range) before anything starts.
#include "launcher/command_line.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace fs = std::filesystem;

namespace pbnbv::launcher {
namespace {

struct Parsed {
  std::optional<int> code;
  std::string out, err;
};

Parsed parse(CommandLine& line, std::vector<std::string> words) {
  words.insert(words.begin(), "pbnbv");
  std::vector<const char*> argv;
  for (const auto& w : words) argv.push_back(w.c_str());
  std::ostringstream out, err;
  Parsed p;
  p.code = line.parse(static_cast<int>(argv.size()), argv.data(), out, err);
  p.out = out.str();
  p.err = err.str();
  return p;
}

std::string file_with(const std::string& name, const std::string& text) {
  const fs::path path = fs::temp_directory_path() / ("pbnbv-command-line-test-" + name + ".toml");
  std::ofstream(path) << text;
  return path.string();
}

TEST(LauncherCommandLine, ScanDefaultsAreTheTables) {
  CommandLine line;
  const Parsed p = parse(line, {"scan"});
  ASSERT_EQ(p.code, std::nullopt) << p.err;
  ASSERT_EQ(line.command(), Command::kScan);
  const ScanOptions& o = line.scan();
  const ScanSettings& s = o.settings;
  EXPECT_EQ(o.object, "bunny");
  EXPECT_DOUBLE_EQ(o.size_m, 0.3);
  EXPECT_FALSE(o.up.has_value());
  EXPECT_EQ(s.rig, RigKind::kArm);
  EXPECT_EQ(s.planner, PlannerKind::kPbnbv);
  EXPECT_EQ(s.views, 10);
  EXPECT_EQ(s.candidates, 800);
  EXPECT_EQ(s.parallels, 24);
  EXPECT_EQ(s.sectors, 4);
  EXPECT_EQ(s.t_max, 10);
  EXPECT_EQ(s.area, CandidateArea::kHemisphere);
  EXPECT_EQ(s.when_done, WhenDone::kSpread);
  EXPECT_DOUBLE_EQ(s.map_resolution_m, 0.03);
  EXPECT_DOUBLE_EQ(s.voxel_m, 0.002);
  EXPECT_DOUBLE_EQ(s.working_distance_m, 0.6);
  EXPECT_DOUBLE_EQ(s.ring_elevation_deg, 30.0);  // arm rig
  EXPECT_FALSE(s.initial_view_m.allFinite());
  EXPECT_DOUBLE_EQ(s.sim_speed, 4.0);
  EXPECT_DOUBLE_EQ(s.speed_scale, 1.0);
  EXPECT_EQ(s.camera.width, 1280);
  EXPECT_EQ(s.camera.height, 720);
  EXPECT_DOUBLE_EQ(s.camera.fx, 696.0);
  EXPECT_DOUBLE_EQ(s.camera.cx, 640.0);  // width / 2
  EXPECT_DOUBLE_EQ(s.camera.cy, 360.0);
  EXPECT_DOUBLE_EQ(s.depth_range.min_m, 0.1);
  EXPECT_DOUBLE_EQ(s.depth_range.max_m, 3.0);
  EXPECT_TRUE(o.registration);  // arm rig
  EXPECT_TRUE(o.record_log);
  EXPECT_TRUE(o.surface_metrics);
  EXPECT_EQ(o.error_seed, 7);
  EXPECT_EQ(s.rig_model_path, default_rig_path(RigKind::kArm));
}

TEST(LauncherCommandLine, FreeRigDefaultsAndDependentDefaults) {
  CommandLine line;
  const Parsed p = parse(line, {"scan", "--rig", "free", "--width", "320", "--height", "180", "--initial-view", "0,0.9,0",
                                "--no-log", "--no-surface-metrics", "--up", "y"});
  ASSERT_EQ(p.code, std::nullopt) << p.err;
  const ScanOptions& o = line.scan();
  EXPECT_DOUBLE_EQ(o.settings.ring_elevation_deg, 0.0);  // free rig
  EXPECT_FALSE(o.registration);                          // free rig: exact poses
  EXPECT_DOUBLE_EQ(o.settings.camera.cx, 160.0);
  EXPECT_DOUBLE_EQ(o.settings.camera.cy, 90.0);
  EXPECT_EQ(o.settings.initial_view_m, Eigen::Vector3d(0, 0.9, 0));
  EXPECT_FALSE(o.record_log);
  EXPECT_FALSE(o.surface_metrics);
  EXPECT_EQ(o.up, UpAxis::kY);
  CommandLine x;
  ASSERT_EQ(parse(x, {"scan", "--up", "x"}).code, std::nullopt);
  EXPECT_EQ(x.scan().up, UpAxis::kX);
}

// A named camera gives its image and range where the options do not; --rig-errors its figures
// where the error options do not; the depth filter is on unless the camera is the ideal one.
TEST(LauncherCommandLine, ACameraAndRigErrorsByName) {
  CommandLine line;
  ASSERT_EQ(parse(line, {"scan"}).code, std::nullopt);
  EXPECT_EQ(line.scan().settings.camera_model, CameraKind::kIdeal);
  EXPECT_FALSE(line.scan().settings.depth_filter);
  EXPECT_DOUBLE_EQ(line.scan().hand_eye_error_mm, 0.0);

  CommandLine d435;
  const Parsed p = parse(d435, {"scan", "--camera", "d435", "--fx", "700", "--rig-errors", "uncalibrated",
                                "--hand-eye-error-mm", "2"});
  ASSERT_EQ(p.code, std::nullopt) << p.err;
  const ScanOptions& o = d435.scan();
  EXPECT_EQ(o.settings.camera_model, CameraKind::kD435);
  EXPECT_EQ(o.settings.camera.width, 1280);
  EXPECT_DOUBLE_EQ(o.settings.camera.fx, 700.0);                   // given
  EXPECT_NEAR(o.settings.camera.fy, 640 / std::tan(43.5 * M_PI / 180), 1e-9);  // the model's: 87 deg wide
  EXPECT_DOUBLE_EQ(o.settings.depth_range.min_m, 0.28);
  EXPECT_TRUE(o.settings.depth_filter);
  EXPECT_DOUBLE_EQ(o.hand_eye_error_mm, 2.0);  // given
  EXPECT_DOUBLE_EQ(o.hand_eye_error_deg, 1.0);  // uncalibrated
  EXPECT_DOUBLE_EQ(o.turntable_error_deg, 0.5);
  EXPECT_DOUBLE_EQ(o.joint_error_deg, 0.02);
  EXPECT_DOUBLE_EQ(o.turntable_backlash_deg, 0.05);

  CommandLine bad;
  const Parsed b = parse(bad, {"scan", "--camera", "kinect2"});
  EXPECT_EQ(b.code, 2);
  EXPECT_NE(b.err.find("--camera"), std::string::npos) << b.err;
  CommandLine external;
  const Parsed e = parse(external, {"scan", "--external-rig", "--rig-errors", "calibrated"});
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.err.find("--rig-errors does not apply to --external-rig"), std::string::npos) << e.err;
}

TEST(LauncherCommandLine, TheRigFileDecidesTheKindOfRig) {
  const std::string free_model = default_rig_path(RigKind::kFree);
  {
    CommandLine line;
    const Parsed p = parse(line, {"scan", "--rig-model", free_model});
    ASSERT_EQ(p.code, std::nullopt) << p.err;
    EXPECT_EQ(line.scan().settings.rig, RigKind::kFree);
    EXPECT_EQ(line.scan().settings.rig_model_path, free_model);
    EXPECT_FALSE(line.scan().registration);  // the free rig's default
  }
  {
    CommandLine line;
    const Parsed p = parse(line, {"scan", "--rig-model", free_model, "--rig", "arm"});
    EXPECT_EQ(p.code, 2);
    EXPECT_NE(p.err.find("--rig arm disagrees with --rig-model " + free_model), std::string::npos) << p.err;
  }
  {
    CommandLine line;
    const Parsed p = parse(line, {"scan", "--rig-model", "/no/such/rig.xml"});
    EXPECT_EQ(p.code, 2);
    EXPECT_NE(p.err.find("--rig-model: rig model /no/such/rig.xml: cannot open the file"), std::string::npos) << p.err;
  }
}

// A rig file that names its camera (pbnbv_camera_model): the twin plays it, with its image and
// range, unless --camera names another.
TEST(LauncherCommandLine, TheRigFileNamesTheCamera) {
  std::ifstream in(default_rig_path(RigKind::kArm));
  std::stringstream text;
  text << in.rdbuf();
  std::string xml = text.str();
  const std::string needle = "<numeric name=\"pbnbv_camera\"";
  ASSERT_NE(xml.find(needle), std::string::npos);
  xml.insert(xml.find(needle), "<text name=\"pbnbv_camera_model\" data=\"azure-kinect-nfov\"/>");
  const std::string file =
      (fs::temp_directory_path() / ("pbnbv-command-line-test-rig-" + std::to_string(::getpid()) + ".xml")).string();
  std::ofstream(file) << xml;
  CommandLine line;
  const Parsed p = parse(line, {"scan", "--rig-model", file});
  CommandLine over;
  const Parsed q = parse(over, {"scan", "--rig-model", file, "--camera", "d405"});
  fs::remove(file);
  ASSERT_EQ(p.code, std::nullopt) << p.err;
  EXPECT_EQ(line.scan().settings.camera_model, CameraKind::kAzureKinectNfov);
  EXPECT_EQ(line.scan().settings.camera.width, 640);
  EXPECT_EQ(line.scan().settings.camera.height, 576);
  ASSERT_EQ(q.code, std::nullopt) << q.err;
  EXPECT_EQ(over.scan().settings.camera_model, CameraKind::kD405);
}

TEST(LauncherCommandLine, ASettingsFileSetsOptionsAndTheCommandLineOverridesIt) {
  const std::string file = file_with("scan", "views = 3\nplanner = \"ring\"\n");
  CommandLine line;
  const Parsed p = parse(line, {"scan", "--config", file, "--views", "5"});
  ASSERT_EQ(p.code, std::nullopt) << p.err;
  EXPECT_EQ(line.scan().settings.views, 5);                      // the command line wins
  EXPECT_EQ(line.scan().settings.planner, PlannerKind::kRing);  // from the file
  CommandLine only_file;
  ASSERT_EQ(parse(only_file, {"scan", "--config", file}).code, std::nullopt);
  EXPECT_EQ(only_file.scan().settings.views, 3);
  EXPECT_EQ(only_file.scan().settings.planner, PlannerKind::kRing);
}

TEST(LauncherCommandLine, BenchDefaultsAndAblationRuns) {
  CommandLine line;
  const Parsed p = parse(line, {"bench", "--objects", "sphere,box", "--out", "/tmp/pbnbv-bench"});
  ASSERT_EQ(p.code, std::nullopt) << p.err;
  const eval::BenchSpec& b = line.bench();
  EXPECT_EQ(b.planners, (std::vector<PlannerKind>{PlannerKind::kPbnbv, PlannerKind::kPbnbvPaper, PlannerKind::kRaycast,
                                                  PlannerKind::kRandom}));
  EXPECT_EQ(b.rig, RigKind::kFree);
  EXPECT_EQ(b.area, CandidateArea::kFullSphere);
  EXPECT_EQ(b.when_done, WhenDone::kSpread);
  EXPECT_EQ(b.candidates, 800);
  EXPECT_EQ(b.views, 10);
  EXPECT_EQ(b.objects, (std::vector<std::string>{"sphere", "box"}));
  EXPECT_TRUE(b.netns);
  EXPECT_EQ(b.first_views, 1);
  EXPECT_FALSE(b.up.has_value());

  // No --objects: the default set; sets mix with names (a name listed twice is kept once).
  CommandLine defaults;
  ASSERT_EQ(parse(defaults, {"bench", "--out", "/tmp/pbnbv-bench"}).code, std::nullopt);
  EXPECT_EQ(defaults.bench().objects, eval::object_set(eval::ObjectSet::kDefault));
  CommandLine sets;
  const Parsed ps = parse(sets, {"bench", "--objects", "tune,sphere,bunny", "--first-views", "3", "--up", "x", "--out",
                                 "/tmp/pbnbv-bench"});
  ASSERT_EQ(ps.code, std::nullopt) << ps.err;
  std::vector<std::string> tune_and_sphere = eval::object_set(eval::ObjectSet::kTune);
  tune_and_sphere.push_back("sphere");
  EXPECT_EQ(sets.bench().objects, tune_and_sphere);
  EXPECT_EQ(sets.bench().first_views, 3);
  EXPECT_EQ(sets.bench().up, UpAxis::kX);

  CommandLine ablate;
  const Parsed a = parse(ablate, {"ablate", "tmax", "--values", "5,20", "--objects", "sphere", "--out", "/tmp/pbnbv-abl"});
  ASSERT_EQ(a.code, std::nullopt) << a.err;
  const AblateOptions& o = ablate.ablate();
  EXPECT_EQ(o.parameter, AblatedParameter::kTMax);
  ASSERT_EQ(o.runs.size(), 2u);
  EXPECT_EQ(o.runs[0].first, "5");
  EXPECT_EQ(o.runs[0].second.tmax, 5);
  EXPECT_EQ(o.runs[1].second.tmax, 20);
  EXPECT_EQ(o.runs[1].second.out, fs::path("/tmp/pbnbv-abl/tmax=20"));
  EXPECT_EQ(o.runs[0].second.planners, (std::vector<PlannerKind>{PlannerKind::kPbnbv}));

  CommandLine views;
  ASSERT_EQ(parse(views, {"ablate", "initial-view", "--out", "/tmp/pbnbv-abl"}).code, std::nullopt);
  ASSERT_EQ(views.ablate().runs.size(), 4u);
  EXPECT_EQ(views.ablate().runs[3].second.initial_view, Eigen::Vector3d(0, 0.63, 0.63));
  EXPECT_EQ(views.ablate().runs[3].second.out, fs::path("/tmp/pbnbv-abl/initial-view=0_0.63_0.63"));

  // The map resolution: default values, several planners kept for each value.
  CommandLine res;
  const Parsed r = parse(res, {"ablate", "resolution", "--planners", "pbnbv,raycast", "--out", "/tmp/pbnbv-abl"});
  ASSERT_EQ(r.code, std::nullopt) << r.err;
  EXPECT_EQ(res.ablate().parameter, AblatedParameter::kResolution);
  ASSERT_EQ(res.ablate().runs.size(), 4u);
  EXPECT_EQ(res.ablate().runs[0].second.resolution_m, 0.03);
  EXPECT_EQ(res.ablate().runs[3].first, "0.005");
  EXPECT_EQ(res.ablate().runs[3].second.resolution_m, 0.005);
  EXPECT_EQ(res.ablate().runs[3].second.out, fs::path("/tmp/pbnbv-abl/resolution=0.005"));
  EXPECT_EQ(res.ablate().runs[3].second.planners, (std::vector<PlannerKind>{PlannerKind::kPbnbv, PlannerKind::kRaycast}));
}

// Lists sweep: one bench per combination (the spec: the first); a list is checked value by value
// (range, twice); ablate takes one value of each (it varies one parameter with --values).
TEST(LauncherCommandLine, BenchListsSweepEveryCombination) {
  CommandLine line;
  const Parsed p = parse(line, {"bench", "--objects", "sphere", "--resolution", "0.03,0.01", "--camera", "ideal,d435",
                                "--rig-errors", "calibrated", "--out", "/tmp/pbnbv-sweep"});
  ASSERT_EQ(p.code, std::nullopt) << p.err;
  const eval::Sweep& s = line.sweep();
  ASSERT_EQ(s.benches.size(), 4u);
  EXPECT_EQ(s.parameters, (std::vector<std::string>{"camera", "resolution"}));
  EXPECT_EQ(s.benches[1].first, "camera=ideal,resolution=0.01");
  EXPECT_EQ(s.benches[1].second.resolution_m, 0.01);
  EXPECT_EQ(s.benches[3].second.camera, CameraKind::kD435);
  EXPECT_EQ(s.benches[3].second.rig_errors, RigErrors::kCalibrated);  // one value: every bench's
  EXPECT_EQ(s.benches[3].second.out, fs::path("/tmp/pbnbv-sweep/camera=d435,resolution=0.01"));
  EXPECT_EQ(line.bench().resolution_m, 0.03);
  EXPECT_EQ(line.bench().camera, CameraKind::kIdeal);

  // One value each: a bench, in --out itself.
  CommandLine one;
  ASSERT_EQ(parse(one, {"bench", "--objects", "sphere", "--resolution", "0.01", "--out", "/tmp/pbnbv-b"}).code, std::nullopt);
  ASSERT_EQ(one.sweep().benches.size(), 1u);
  EXPECT_EQ(one.bench().resolution_m, 0.01);
  EXPECT_EQ(one.bench().out, fs::path("/tmp/pbnbv-b"));

  for (const auto& [words, why] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"--resolution", "0.03,0.5"}, "0.5 is outside its range"},
           {{"--resolution", "0.03,0.030"}, "'0.030' is listed twice"},
           {{"--first-views", "1,x"}, "'x' is not a whole number"},
           {{"--camera", "ideal,hd"}, "hd"},
           {{"--rig", "arm,arm"}, "'arm' is listed twice"}}) {
    CommandLine bad;
    std::vector<std::string> argv = {"bench", "--objects", "sphere", "--out", "/tmp/pbnbv-b"};
    argv.insert(argv.end(), words.begin(), words.end());
    const Parsed b = parse(bad, argv);
    EXPECT_EQ(b.code, 2) << words[1];
    EXPECT_NE(b.err.find(words[0]), std::string::npos) << b.err;
    EXPECT_NE(b.err.find(why), std::string::npos) << b.err;
  }
  CommandLine ablate;
  const Parsed a = parse(ablate, {"ablate", "tmax", "--camera", "ideal,d435", "--out", "/tmp/pbnbv-abl"});
  EXPECT_EQ(a.code, 2);
  EXPECT_NE(a.err.find("--camera lists several values: pbnbv ablate varies one parameter"), std::string::npos) << a.err;
}

// Each kind of bad option, on scan and on bench: exit 2, the message names the option (and the
// value and range where there is one).
TEST(LauncherCommandLine, RigCheckDefaultsAndOptions) {
  CommandLine line;
  ASSERT_EQ(parse(line, {"rig-check"}).code, std::nullopt);
  EXPECT_EQ(line.command(), Command::kRigCheck);
  EXPECT_EQ(line.rig_check().rig_model, default_rig_path(RigKind::kArm));
  EXPECT_EQ(line.rig_check().deadline_s, 5.0);
  EXPECT_FALSE(line.rig_check().passive);
  CommandLine given;
  ASSERT_EQ(parse(given, {"rig-check", "--rig-model", "my_rig.xml", "--deadline", "2.5", "--passive"}).code,
            std::nullopt);
  EXPECT_EQ(given.rig_check().rig_model, "my_rig.xml");
  EXPECT_EQ(given.rig_check().deadline_s, 2.5);
  EXPECT_TRUE(given.rig_check().passive);
}

TEST(LauncherCommandLine, BadOptionsAreNamed) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"scan", "--views"}, "pbnbv scan: --views needs a value"},
      {{"scan", "--out", "--views", "3"}, "pbnbv scan: --out: missing value (the next word, '--views', is an option)"},
      {{"scan", "--views", "3", "--views", "4"}, "pbnbv scan: --views is given 2 times (3, 4): give it once"},
      {{"scan", "--views", "2000"}, "pbnbv scan: --views: 2000 is outside its range [1, 1000]"},
      {{"scan", "--resolution", "0.5"}, "pbnbv scan: --resolution: 0.5 is outside its range [0.002, 0.2] m"},
      {{"scan", "--veiws", "3"}, "pbnbv scan: unknown option --veiws (did you mean --views?)"},
      {{"scan", "--planner", "best"}, "pbnbv scan: --planner: unknown planner 'best' (expected pbnbv, pbnbv-paper, raycast, random, ring or oracle)"},
      {{"scan", "--external-rig", "--planner", "oracle"},
       "pbnbv scan: --planner oracle does not apply to --external-rig: the oracle chooses by the object's true mesh"},
      {{"scan", "--parallels", "30", "--candidates", "20"}, "pbnbv scan: --parallels 30 must not exceed --candidates 20"},
      {{"bench", "--jobs", "--out", "x"}, "pbnbv bench: --jobs: missing value (the next word, '--out', is an option)"},
      {{"bench", "--out", "x", "--jobs", "65"}, "pbnbv bench: --jobs: 65 is outside its range [1, 64]"},
      {{"bench", "--out", "x", "--out", "y"}, "pbnbv bench: --out is given 2 times (x, y): give it once"},
      {{"bench", "--out", "x", "--candidates", "10"},
       "pbnbv bench: --candidates 10: the candidates lie on 24 parallels, so at least 24 are needed"},
      {{"bench", "--objets", "sphere"}, "pbnbv bench: unknown option --objets (did you mean --objects?)"},
      {{"bench", "--objects", "tune,tunning", "--out", "x"},
       "pbnbv bench: --objects: 'tunning' is neither an object set (default, tuning, tune or confirm), a known object"},
      {{"bench", "--out", "x", "--first-views", "11"}, "pbnbv bench: --first-views: 11 is outside its range [1, 10]"},
      {{"bench", "--out", "x", "--first-views", "3", "--initial-view", "0.9,0,0"},
       "pbnbv bench: --first-views 3 draws the first views 2..3 while --initial-view fixes the first view of every scan"},
      {{"ablate", "initial-view", "--first-views", "2", "--out", "x"},
       "pbnbv ablate: --values 0.9,0,0: --first-views 2 draws the first views"},
      {{"scan", "--up", "w"}, "pbnbv scan: --up: unknown up axis 'w' (expected z, y or x)"},
      {{"bench", "--planners", "pbnbv,ring,pbnbv", "--out", "x"}, "pbnbv bench: --planners: 'pbnbv' is listed twice"},
      {{"bench"}, "pbnbv bench: --out DIR is required"},
      {{"ablate", "--out", "x"}, "pbnbv ablate: name the parameter: tmax, beta, initial-view or resolution"},
      {{"ablate", "resolution", "--values", "0.01,0.001", "--out", "x"},
       "pbnbv ablate: --values: --resolution 0.001 is outside its range [0.002, 0.2] m"},
      {{"ablate", "resolution", "--values", "0.01,fine", "--out", "x"}, "pbnbv ablate: --values: 'fine' is not a number"},
      {{"ablate", "beta", "--values", "2,400", "--out", "x"}, "pbnbv ablate: --values: --beta 400 is outside its range [1, 360]"},
      {{"frobnicate"}, "pbnbv: unknown command 'frobnicate' (expected scan, bench, ablate, spy, view, stop, rig-host, import-urdf, rig-check, calibrate, replay, evaluate, mesh, help)"},
      {{"rig-check", "--deadline", "0"}, "pbnbv rig-check: --deadline: 0 is outside its range [0.5, 600] s"},
      {{"calibrate", "--sphere-radius", "0.05"}, "pbnbv calibrate: --rig-model is required"},
      {{"calibrate", "--rig-model", "r.xml", "--sphere-radius", "0.12", "--sphere-offset", "0.1"},
       "pbnbv calibrate: --sphere-radius 0.120000 m at --sphere-offset 0.100000 m reaches beyond the platter's 0.2 m radius"},
      {{"calibrate", "--rig-model", "r.xml", "--sphere-radius", "0.5"},
       "pbnbv calibrate: --sphere-radius: 0.5 is outside its range [0.01, 0.15] m"},
      {{"replay"}, "pbnbv replay: name the recorded scan's folder: pbnbv replay DIR"},
      {{"replay", "d", "--planner", "rign"}, "pbnbv replay: --planner"},
      {{"mesh"}, "pbnbv mesh: name the scan's folder: pbnbv mesh DIR"},
      {{"mesh", "d", "--mesh-voxel", "1"}, "pbnbv mesh: --mesh-voxel: 1 is outside its range [0.0002, 0.05] m"},
      {{"mesh", "d", "--mesh-method", "marching"}, "pbnbv mesh: --mesh-method"},
  };
  for (const auto& [words, message] : cases) {
    CommandLine line;
    const Parsed p = parse(line, words);
    EXPECT_EQ(p.code, std::optional<int>(2)) << words[0];
    EXPECT_EQ(p.err.rfind(message, 0), 0u) << "got: " << p.err << "want: " << message;
  }
}

TEST(LauncherCommandLine, MeshTakesTheFolderAndTheSurfaceSettings) {
  CommandLine line;
  const Parsed p = parse(line, {"mesh", "out/scan", "--mesh-method", "poisson", "--poisson-depth", "8", "--mesh-voxel", "0.003", "--stl"});
  ASSERT_EQ(p.code, std::nullopt) << p.err;
  EXPECT_EQ(line.command(), Command::kMesh);
  EXPECT_EQ(line.mesh().dir, "out/scan");
  EXPECT_EQ(line.mesh().surface.method, MeshMethod::kPoisson);
  EXPECT_EQ(line.mesh().surface.poisson_depth, 8);
  EXPECT_EQ(line.mesh().surface.voxel_m, 0.003);
  EXPECT_EQ(line.mesh().surface.truncation_voxels, kMeshTruncation.value);
  EXPECT_TRUE(line.mesh().stl);
}

TEST(LauncherCommandLine, HelpPrintsTheUsage) {
  for (const std::vector<std::string>& words : {std::vector<std::string>{}, {"help"}, {"--help"}}) {
    CommandLine line;
    const Parsed p = parse(line, words);
    EXPECT_EQ(p.code, std::optional<int>(0));
    // Every command and its options, with the defaults of the table.
    for (const char* part : {"scan", "bench", "ablate", "spy", "rig-check", "evaluate", "--reference FILE", "--threshold M", "--views N", "at most this many views [10] (range [1, 1000])",
                             "--candidates N", "[800]", "--when-done stop|spread", "[spread]", "--config FILE"}) {
      EXPECT_NE(p.out.find(part), std::string::npos) << part;
    }
  }
  CommandLine scan;
  const Parsed p = parse(scan, {"scan", "--help"});
  EXPECT_EQ(p.code, std::optional<int>(0));
  EXPECT_NE(p.out.find("Usage: pbnbv scan"), std::string::npos) << p.out;
  EXPECT_EQ(p.out.find("--jobs"), std::string::npos) << "a command's help lists only its own options";
}

}  // namespace
}  // namespace pbnbv::launcher
