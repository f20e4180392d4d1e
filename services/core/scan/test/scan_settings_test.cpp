// Scan ids: unique on a bus (two ids made in the same instant differ), readable, and safe in
// file names and channel text. Object limits: what the twin cannot load and what no rig can scan.
#include <gtest/gtest.h>

#include <functional>

#include <regex>
#include <set>
#include <string>

#include "core/geometry/mesh.hpp"
#include "core/scan/scan_settings.hpp"
#include "error_message.hpp"

using namespace pbnbv;

TEST(ScanId, ManyIdsOfOneObjectMadeAtOnceAreAllDifferent) {
  std::set<std::string> ids;
  for (int i = 0; i < 10000; ++i) ids.insert(new_scan_id("bunny"));
  EXPECT_EQ(ids.size(), 10000u);  // a time stamp gives one id for all of them
}

TEST(ScanId, TheNameIsKeptAndSixteenHexDigitsFollow) {
  const std::regex form("bunny-[0-9a-f]{16}");
  EXPECT_TRUE(std::regex_match(new_scan_id("bunny"), form)) << new_scan_id("bunny");
  EXPECT_TRUE(std::regex_match(new_scan_id("my part/v2 ü"), std::regex("my_part_v2___-[0-9a-f]{16}")))
      << new_scan_id("my part/v2 ü");
  EXPECT_TRUE(std::regex_match(new_scan_id(""), std::regex("scan-[0-9a-f]{16}")));
}

// The object limits, on bounding boxes worked out by hand.
namespace {
MeshNormalisation box(double x, double y, double z, std::size_t triangles = 12) {
  MeshNormalisation n;
  n.extent_m = Eigen::Vector3d(x, y, z);
  n.num_triangles = triangles;
  return n;
}
std::string error_of_mesh(const TriangleMesh& mesh, const MeshNormalisation& n, bool for_twin);
std::string error_of(const MeshNormalisation& n, bool for_twin = true) {
  const TriangleMesh mesh = make_box(n.extent_m);
  return error_of_mesh(mesh, n, for_twin);
}
std::string error_of_mesh(const TriangleMesh& mesh, const MeshNormalisation& n, bool for_twin = true) {
  try {
    check_object_limits(mesh, n, "the object 'part.stl'", for_twin);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(ObjectLimits, AnOrdinaryObjectPasses) {
  EXPECT_EQ(error_of(box(0.3, 0.45, 0.6, 200000)), "");  // MuJoCo's limit itself is allowed
  EXPECT_EQ(error_of(box(0.3, 0.3, 3.0)), "");           // 10:1 and 3 m: at the limit
}

TEST(ObjectLimits, TooManyTrianglesForTheTwinIsNamed) {
  const std::string e = error_of(box(0.3, 0.3, 0.3, 200001));
  EXPECT_NE(e.find("'part.stl' has 200001 triangles"), std::string::npos) << e;
  EXPECT_NE(e.find("at most 200000"), std::string::npos) << e;
  EXPECT_EQ(error_of(box(0.3, 0.3, 0.3, 200001), false), "");  // a real rig renders nothing
}

TEST(ObjectLimits, AOneMicronSheetIsFlat) {
  // A 0.3 m x 0.3 m sheet 1 um thick, its thickness scaled to 0.3 m: 90 km on each side.
  const double scale = 0.3 / 1e-6;
  const std::string e = error_of(box(0.3 * scale, 0.3 * scale, 0.3));
  EXPECT_NE(e.find("'part.stl' is flat"), std::string::npos) << e;
  // Its bounding box alone says so too, when the vertices do not (a thin rod's box, not flat).
  const std::string rod = error_of_mesh(make_box({0.3, 0.3, 0.3}), box(0.3, 0.3, 0.3 * 2000));
  EXPECT_NE(rod.find("2000 times longer than it is thick"), std::string::npos) << rod;
}

TEST(ObjectLimits, ASingleTiltedTriangleIsFlat) {
  TriangleMesh t;
  t.vertices = {{0, 0, 0}, {0.3, 0, 0.1}, {0, 0.3, 0.2}};  // no bounding-box edge is zero
  t.triangles = {{0, 1, 2}};
  MeshNormalisation n = box(0.3, 0.3, 0.2, 1);
  const std::string e = error_of_mesh(t, n);
  EXPECT_NE(e.find("is flat (3 vertices, 1 triangles"), std::string::npos) << e;
}

TEST(ObjectLimits, AnObjectLongerThanTheRigCanScanIsNamed) {
  const std::string e = error_of(box(0.3, 0.3, 3.3));  // 11:1, 3.3 m long
  EXPECT_NE(e.find("would be 3.3 m long"), std::string::npos) << e;
  EXPECT_NE(e.find("smaller --size"), std::string::npos) << e;
}

// An unknown object in a working volume on the arm rig: the object frame at the volume's centre,
// the keep-out box the whole volume (2 cm around it, down to the turntable top), the crop 5 cm
// around it; the settings file says so and reads back without a mesh normalisation.
TEST(UnknownObject, ItsFrameKeepOutAndCropComeFromTheWorkingVolume) {
  ScanSettings s;
  s.rig = RigKind::kArm;
  s.scan_id = "scan-0123456789abcdef";
  s.rig_model_path = "models/rig_arm.xml";
  s.external_rig = true;
  s.object_name = "unknown";
  s.working_volume = parse_working_volume("cylinder:0.2,0.5");
  place_object(s);
  EXPECT_DOUBLE_EQ(s.object_z_m, 0.25);
  EXPECT_TRUE(s.keepout_min_m.isApprox(Eigen::Vector3d(-0.22, -0.22, -0.25)));
  EXPECT_TRUE(s.keepout_max_m.isApprox(Eigen::Vector3d(0.22, 0.22, 0.27)));
  EXPECT_TRUE(s.crop_min_m.isApprox(Eigen::Vector3d(-0.25, -0.25, -0.3)));
  EXPECT_TRUE(s.crop_max_m.isApprox(Eigen::Vector3d(0.25, 0.25, 0.3)));
  const nlohmann::json j = to_json(s);
  EXPECT_EQ(j["object"]["working_volume"], "cylinder:0.2,0.5");
  EXPECT_FALSE(j["object"].contains("normalisation"));
  const ScanSettings back = scan_settings_from_json(j);
  EXPECT_TRUE(back.external_rig);
  ASSERT_TRUE(back.working_volume.has_value());
  EXPECT_EQ(back.working_volume->to_text(), "cylinder:0.2,0.5");
  EXPECT_TRUE(back.expected_extent_m().isApprox(Eigen::Vector3d(0.4, 0.4, 0.5)));
}

// A settings.json whose whole numbers are huge, fractional or text is refused naming the field
// (before: get<int> cast 1e300 without a word, undefined behaviour, and validate() saw garbage).
TEST(ScanSettingsJson, WholeNumbersOutOfIntOrFractionalAreRefusedByName) {
  ScanSettings s;
  s.scan_id = "numbers";
  const nlohmann::json good = to_json(s);
  EXPECT_EQ(scan_settings_from_json(good).views, s.views);
  auto refusal = [&](const std::function<void(nlohmann::json&)>& plant) -> std::string {
    nlohmann::json j = good;
    plant(j);
    return pbnbv::testing::error_message([&] { scan_settings_from_json(j); });
  };
  EXPECT_EQ(refusal([](nlohmann::json& j) { j["views"] = 1e300; }),
            "scan settings: views = 1e+300 is not a whole number in -2147483648..2147483647");
  EXPECT_EQ(refusal([](nlohmann::json& j) { j["planning"]["candidates"] = 800.5; }),
            "scan settings: planning.candidates = 800.5 is not a whole number in -2147483648..2147483647");
  EXPECT_EQ(refusal([](nlohmann::json& j) { j["camera"]["width"] = "1280"; }),
            "scan settings: camera.width = \"1280\" is not a whole number in -2147483648..2147483647");
  EXPECT_EQ(refusal([](nlohmann::json& j) { j["planning"]["seed"] = 2.5; }),
            "scan settings: planning.seed = 2.5 is not a whole number in -9223372036854775808..9223372036854775807");
}

// Registration's ICP voxel: recorded and read back; a scan recorded before it was (stop 47)
// aligned at 2 mm and resumes so; out of range it is refused naming the option.
TEST(ScanSettingsJson, TheIcpVoxelIsRecordedAndAnOlderScanKeepsTwoMillimetres) {
  ScanSettings s;
  s.scan_id = "icp";
  EXPECT_EQ(s.icp_voxel_m, 0.003);
  s.icp_voxel_m = 0.0025;
  nlohmann::json j = to_json(s);
  EXPECT_EQ(j["registration"]["icp_voxel_m"], 0.0025);
  EXPECT_EQ(scan_settings_from_json(j).icp_voxel_m, 0.0025);
  j["registration"].erase("icp_voxel_m");
  EXPECT_EQ(scan_settings_from_json(j).icp_voxel_m, 0.002);
  j["registration"]["icp_voxel_m"] = 1.0;
  const std::string why = pbnbv::testing::error_message([&] { scan_settings_from_json(j); });
  EXPECT_NE(why.find("icp-voxel"), std::string::npos) << why;
}

namespace pbnbv {

// --initial-view is a camera position 0.05..10 m from the object centre, every coordinate finite:

// The executor's turntable rule: a new scan's settings say "quickest", and the moves and plans of
// a motion-aware scan take kQuickest; a scan recorded with the narrowed least turn replays with
// kLeastTurn; a settings.json without the field (recorded before the least turn was narrowed)
// reads as the grid's, so its replay commands the turns it recorded (kLeastTurnOnGrid); plain
// motion is unaffected; any other word is refused naming the field.
TEST(ScanSettingsJson, TheTurntableRuleIsRecordedAndOlderScansReplayWithTheirs) {
  ScanSettings s;
  s.scan_id = "turn";
  s.motion = Motion::kAware;
  EXPECT_EQ(s.least_turn, LeastTurn::kQuickest);
  nlohmann::json j = to_json(s);
  EXPECT_EQ(j["planning"]["least_turn"], "quickest");
  EXPECT_EQ(turntable_choice(scan_settings_from_json(j)), TurntableChoice::kQuickest);
  j["planning"]["least_turn"] = "narrowed";
  EXPECT_EQ(scan_settings_from_json(j).least_turn, LeastTurn::kNarrowed);
  EXPECT_EQ(turntable_choice(scan_settings_from_json(j)), TurntableChoice::kLeastTurn);
  j["planning"].erase("least_turn");
  EXPECT_EQ(scan_settings_from_json(j).least_turn, LeastTurn::kGrid);
  EXPECT_EQ(turntable_choice(scan_settings_from_json(j)), TurntableChoice::kLeastTurnOnGrid);
  j["planning"]["motion"] = "plain";
  EXPECT_EQ(turntable_choice(scan_settings_from_json(j)), TurntableChoice::kPreferred);
  j["planning"]["least_turn"] = "nearest";
  const std::string why = pbnbv::testing::error_message([&] { scan_settings_from_json(j); });
  EXPECT_EQ(why, "scan settings: unknown least turn 'nearest' (expected narrowed, grid or quickest)");
}
// 1e308 (which passed and failed only in the coordinator, after every process had started), inf
// and a point at the centre are refused naming the option; 0.9 m above is taken.
TEST(InitialView, OnlyAFinitePointFiveCentimetresToTenMetresFromTheCentreIsTaken) {
  ScanSettings s;
  s.scan_id = "unit";
  s.initial_view_m = Eigen::Vector3d(0, 0, 0.9);
  EXPECT_NO_THROW(s.validate());
  auto refused = [&](const Eigen::Vector3d& p, const std::string& why) {
    s.initial_view_m = p;
    try {
      s.validate();
      ADD_FAILURE() << p.transpose() << " was taken";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("--initial-view"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  refused(Eigen::Vector3d(1e308, 0, 0), "at most 10 m");
  refused(Eigen::Vector3d(0, 10.01, 0), "at most 10 m");
  refused(Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0, 0), "finite");
  refused(Eigen::Vector3d(std::nan(""), 0, 1), "finite");
  refused(Eigen::Vector3d(0.01, 0, 0.01), "at least 0.05 m");
  s.initial_view_m = Eigen::Vector3d::Constant(std::nan(""));  // not given
  EXPECT_NO_THROW(s.validate());
}

}  // namespace pbnbv
