// The scan sequence's messages survive the round trip through LCM types, and a bad field is named.
#include "bus/convert_scan.hpp"

#include <gtest/gtest.h>

#include "error_message.hpp"

#include <cmath>
#include <functional>
#include <limits>
#include <string>

using namespace pbnbv;
using pbnbv::testing::expect_error;

namespace {
}  // namespace

TEST(ConvertScan, MoveRequestRoundTripsAndAnEmptyKeepoutStaysEmpty) {
  MoveRequest r;
  r.scan_id = "bunny-1";
  r.iteration = 3;
  r.request_id = 12;
  r.object_T_camera = look_at_z_up(Eigen::Vector3d(0.5, 0.2, 0.4), Eigen::Vector3d::Zero());
  r.object_z_m = 0.15;
  r.keepout = Eigen::AlignedBox3d(Eigen::Vector3d(-0.2, -0.2, -0.15), Eigen::Vector3d(0.2, 0.2, 0.17));
  r.speed_scale = 0.5;
  r.timeout_s = 30;
  const MoveRequest b = bus::from_msg(bus::to_msg(r));
  EXPECT_EQ(b.scan_id, "bunny-1");
  EXPECT_EQ(b.request_id, 12);
  EXPECT_LT((b.object_T_camera.matrix() - r.object_T_camera.matrix()).norm(), 1e-12);
  EXPECT_EQ(b.keepout.min(), r.keepout.min());
  EXPECT_EQ(b.keepout.max(), r.keepout.max());
  r.keepout = Eigen::AlignedBox3d();
  EXPECT_TRUE(bus::from_msg(bus::to_msg(r)).keepout.isEmpty());
}

TEST(ConvertScan, BadRequestFieldsAreNamed) {
  MoveRequest r;
  move_request_t m = bus::to_msg(r);
  m.speed_scale = 0;
  expect_error([&] { bus::from_msg(m); }, "MOVE_REQUEST speed_scale");
  m = bus::to_msg(r);
  m.keepout_min_m[1] = 1.0;  // above its max (0)
  expect_error([&] { bus::from_msg(m); }, "MOVE_REQUEST keepout_max_m[1]");
  CaptureRequest c;
  capture_request_t cm = bus::to_msg(c);
  cm.voxel_m = std::numeric_limits<double>::quiet_NaN();
  expect_error([&] { bus::from_msg(cm); }, "CAPTURE_REQUEST voxel_m");
}

// turntable_choice: its four constants come through as they are (2, the grid's least turn, is
// what a scan recorded before the least turn was narrowed is replayed with; 3 the quickest move);
// any other byte is refused naming the field and the constants.
TEST(ConvertScan, TheTurntableChoiceIsOneOfItsConstants) {
  MoveRequest r;
  for (TurntableChoice c : {TurntableChoice::kPreferred, TurntableChoice::kLeastTurn, TurntableChoice::kLeastTurnOnGrid,
                            TurntableChoice::kQuickest}) {
    r.turntable_choice = c;
    EXPECT_EQ(bus::from_msg(bus::to_msg(r)).turntable_choice, c);
  }
  move_request_t m = bus::to_msg(r);
  EXPECT_EQ(m.turntable_choice, move_request_t::kQuickest);
  for (int8_t bad : {int8_t{4}, int8_t{-1}, int8_t{127}}) {
    m.turntable_choice = bad;
    expect_error([&] { bus::from_msg(m); }, "MOVE_REQUEST turntable_choice = " + std::to_string(bad) +
                                                " is not one of its constants (0 preferred azimuth, 1 least turn, 2 least "
                                                "turn on the grid, 3 quickest move)");
  }
}

TEST(ConvertScan, CloudRoundTripsItsPointsAndRejectsANonFiniteOne) {
  CaptureResult c;
  c.scan_id = "s";
  c.ok = true;
  c.points = {Eigen::Vector3f(0.1f, 0.2f, 0.3f), Eigen::Vector3f(-1, 0, 2)};
  c.joint_position_rad << 0.1, 0.2, 0.3, 0.4, 0.5, 0.6;
  const CaptureResult b = bus::from_msg(bus::to_msg(c));
  ASSERT_EQ(b.points.size(), 2u);
  EXPECT_EQ(b.points[1], Eigen::Vector3f(-1, 0, 2));
  EXPECT_EQ(b.joint_position_rad, c.joint_position_rad);
  point_cloud_t m = bus::to_msg(c);
  m.points_m[1][2] = std::nanf("");
  expect_error([&] { bus::from_msg(m); }, "CLOUD points_m[1]");
}

// The contacts of a move: the count and the last one's text, through the message; a count below
// -1 or a text without a count is refused naming the field.
TEST(ConvertScan, AMoveResultCarriesItsContacts) {
  MoveResult r;
  r.status = MoveStatus::kTimedOut;
  r.contacts = 1;
  r.contact = "link_4 / pedestal, 0.8 mm deep, at rig time 3.210 s, during command 9";
  const MoveResult b = bus::from_msg(bus::to_msg(r));
  EXPECT_EQ(b.contacts, 1);
  EXPECT_EQ(b.contact, r.contact);
  EXPECT_EQ(bus::from_msg(bus::to_msg(MoveResult{})).contacts, 0);
  move_result_t m = bus::to_msg(r);
  m.contacts = -7;
  expect_error([&] { bus::from_msg(m); }, "MOVE_RESULT contacts = -7 is below -1");
  m = bus::to_msg(r);
  m.contacts = 0;
  expect_error([&] { bus::from_msg(m); }, "MOVE_RESULT contact is given with MOVE_RESULT contacts = 0");
  m.contacts = -1;  // the rig cannot tell
  m.contact = "";
  EXPECT_EQ(bus::from_msg(m).contacts, -1);
}

TEST(ConvertScan, MoveResultStatusOutsideItsConstantsIsRejected) {
  MoveResult r;
  r.status = MoveStatus::kReached;
  EXPECT_EQ(bus::from_msg(bus::to_msg(r)).status, MoveStatus::kReached);
  move_result_t m = bus::to_msg(r);
  m.status = 9;
  expect_error([&] { bus::from_msg(m); }, "MOVE_RESULT status");
}

// ---- The coordinator's other messages ----

namespace {
view_plan_t plan_message(int alternatives) {
  view_plan_t m{};
  m.scan_id = "s";
  m.iteration = 2;
  m.request_id = 7;
  m.planner = plan_request_t::kPlannerPbnbv;
  m.outcome = view_plan_t::kView;
  m.reason = "best F";
  m.ranking = view_plan_t::kRankingF;
  m.object_T_camera = bus::to_msg(look_at_z_up(Eigen::Vector3d(0.6, 0, 0.3), Eigen::Vector3d::Zero()));
  m.view_quality = 1500;
  m.partition = 2;
  m.num_allowed_sectors = 2;
  m.allowed_sectors = {1, 2};
  m.sphere_centre_m[2] = 0.05;
  m.num_scored = 700;
  m.plan_s = 0.04;
  m.num_alternatives = alternatives;
  for (int a = 0; a < alternatives; ++a) {
    m.alternatives.push_back(bus::to_msg(look_at_z_up(Eigen::Vector3d(0.6, 0.01 * (a + 1), 0.3), Eigen::Vector3d::Zero())));
    m.alternative_quality.push_back(1400 - a);
  }
  return m;
}
}  // namespace

TEST(ConvertScan, ViewPlanKeepsItsViewAlternativesAndFigures) {
  const ViewPlan p = bus::from_msg(plan_message(3));
  EXPECT_EQ(p.request_id, 7);
  EXPECT_EQ(p.outcome, PlanOutcome::kView);
  EXPECT_NEAR(p.object_T_camera.translation().x(), 0.6, 1e-12);
  ASSERT_EQ(p.alternatives.size(), 3u);
  EXPECT_NEAR(p.alternatives[2].translation().y(), 0.03, 1e-12);
  EXPECT_EQ(p.alternative_quality, std::vector<double>({1400, 1399, 1398}));
  EXPECT_EQ(p.allowed_sectors, std::vector<int>({1, 2}));
  EXPECT_EQ(p.sphere_centre_m.z(), 0.05);
  EXPECT_EQ(p.num_scored, 700);
  EXPECT_EQ(p.ranking, Ranking::kF);
}

TEST(ConvertScan, ViewPlanOutcomeAndPosesAreChecked) {
  view_plan_t m = plan_message(2);
  m.outcome = 3;
  expect_error([&] { bus::from_msg(m); }, "VIEW_PLAN outcome");
  m = plan_message(2);
  m.alternatives[1].quat_wxyz[0] = 2;  // not a unit quaternion
  expect_error([&] { bus::from_msg(m); }, "VIEW_PLAN alternatives[1]");
  m = plan_message(2);
  m.ranking = 6;  // not one of the constants
  expect_error([&] { bus::from_msg(m); }, "VIEW_PLAN ranking = 6 is not one of its constants (0..5)");
  m.ranking = view_plan_t::kRankingGapAngle;
  EXPECT_EQ(bus::from_msg(m).ranking, Ranking::kGapAngle);
  m.planner = -1;
  expect_error([&] { bus::from_msg(m); }, "VIEW_PLAN planner = -1 is not one of its constants (0..4)");
  // A stop carries no view: its (unset) poses are not read.
  m = plan_message(0);
  m.outcome = view_plan_t::kStop;
  m.object_T_camera.quat_wxyz[0] = 0;
  const ViewPlan stop = bus::from_msg(m);
  EXPECT_EQ(stop.outcome, PlanOutcome::kStop);
  EXPECT_TRUE(stop.alternatives.empty());
}

TEST(ConvertScan, PlanRequestCarriesTheScanSoFar) {
  PlanRequest r;
  r.scan_id = "s";
  r.request_id = 11;
  r.views_done = {look_at_z_up(Eigen::Vector3d(0.6, 0, 0.3), Eigen::Vector3d::Zero())};
  r.excluded = {look_at_z_up(Eigen::Vector3d(0, 0.6, 0.3), Eigen::Vector3d::Zero()),
                look_at_z_up(Eigen::Vector3d(0, -0.6, 0.3), Eigen::Vector3d::Zero())};
  r.camera.width = 640;
  r.depth_range.max_m = 2.5;
  r.joint_position_rad << 1, 2, 3, 4, 5, 6;
  r.keepout = Eigen::AlignedBox3d(Eigen::Vector3d(-0.1, -0.1, -0.2), Eigen::Vector3d(0.1, 0.1, 0.2));
  r.first_quality = std::numeric_limits<double>::quiet_NaN();
  const plan_request_t m = bus::to_msg(r);
  EXPECT_EQ(m.request_id, 11);
  EXPECT_EQ(m.num_views_done, 1);
  EXPECT_EQ(m.num_excluded, 2);
  EXPECT_NEAR(m.excluded[1].position_m[1], -0.6, 1e-12);
  EXPECT_EQ(m.width_px, 640);
  EXPECT_EQ(m.depth_max_m, 2.5);
  EXPECT_EQ(m.joint_position_rad[5], 6);
  EXPECT_EQ(m.keepout_min_m[2], -0.2);
  EXPECT_EQ(m.keepout_max_m[0], 0.1);
  EXPECT_TRUE(std::isnan(m.first_quality));
  // No keep-out box: zeros, as the scorer reads "none".
  r.keepout = Eigen::AlignedBox3d();
  const plan_request_t none = bus::to_msg(r);
  EXPECT_EQ(none.keepout_min_m[0], 0);
  EXPECT_EQ(none.keepout_max_m[2], 0);
}

TEST(ConvertScan, RegisteredCloudNamesItsBadField) {
  CaptureResult c;
  c.scan_id = "s";
  c.points = {Eigen::Vector3f(0.1f, 0.2f, 0.3f)};
  registered_cloud_t m;
  m.scan_id = "s";
  m.request_id = 4;
  m.cloud = bus::to_msg(c);
  m.kinematic_object_T_camera = bus::to_msg(Pose::Identity());
  m.correction = bus::to_msg(Pose(Eigen::Translation3d(0.001, 0, 0)));
  m.accepted = true;
  m.translation_m = 0.001;
  m.iteration = 2;
  m.frame_file = "frames/view_003.ply";
  m.depth_file = "";
  m.normals = registered_cloud_t::kNormalsNeighbours;
  m.frame_points = 200;
  m.new_points = 50;
  m.model_points_before = 1000;
  m.new_surface_radius_m = 0.005;
  m.accumulate_s = 0.01;
  const RegisteredCloud r = bus::from_msg(m);
  EXPECT_EQ(r.request_id, 4);
  EXPECT_TRUE(r.accepted);
  EXPECT_EQ(r.cloud.points.size(), 1u);
  EXPECT_NEAR(r.correction.translation().x(), 0.001, 1e-15);
  EXPECT_EQ(r.frame_file, "frames/view_003.ply");
  EXPECT_FALSE(r.normals_from_depth);
  ASSERT_TRUE(r.new_surface.has_value());
  EXPECT_EQ(r.new_surface->percent_of_model(), 5.0);
  // The files it names are the view's own or none: no other path is taken from the wire.
  for (const char* path : {"../../etc/passwd", "frames/view_001.ply", "/tmp/x.ply"}) {
    registered_cloud_t bad = m;
    bad.frame_file = path;
    expect_error([&] { bus::from_msg(bad); }, "REGISTERED_CLOUD frame_file '" + std::string(path) + "' is neither '' nor 'frames/view_003.ply'");
  }
  registered_cloud_t bad = m;
  bad.depth_file = "depth/../../x.png";
  expect_error([&] { bus::from_msg(bad); }, "REGISTERED_CLOUD depth_file");
  bad = m;
  bad.new_points = 201;  // more new points than the view has
  expect_error([&] { bus::from_msg(bad); }, "REGISTERED_CLOUD new surface: new_points 201, frame_points 200");
  bad = m;
  bad.new_points = -1;  // not merged: no figure
  EXPECT_FALSE(bus::from_msg(bad).new_surface.has_value());
  bad.new_points = -2;
  expect_error([&] { bus::from_msg(bad); }, "REGISTERED_CLOUD new_points = -2");
  bad = m;
  bad.normals = 7;
  expect_error([&] { bus::from_msg(bad); }, "REGISTERED_CLOUD normals = 7");
  m.cloud.points_m[0][1] = std::nanf("");
  expect_error([&] { bus::from_msg(m); }, "REGISTERED_CLOUD cloud: CLOUD points_m[0]");
  m = registered_cloud_t{};
  m.cloud = bus::to_msg(c);
  m.kinematic_object_T_camera = bus::to_msg(Pose::Identity());
  expect_error([&] { bus::from_msg(m); }, "REGISTERED_CLOUD correction");  // all-zero quaternion
}

// A cloud's normals: none, or one unit vector (or zero: none found) per point.
TEST(ConvertScan, CloudNormalsAreOnePerPointAndUnitOrZero) {
  CaptureResult c;
  c.scan_id = "s";
  c.ok = true;
  c.points = {Eigen::Vector3f(0.1f, 0.2f, 0.3f), Eigen::Vector3f(0.1f, 0.2f, 0.4f)};
  c.normals = {Eigen::Vector3f(0, 0, 1), Eigen::Vector3f::Zero()};
  point_cloud_t m = bus::to_msg(c);
  EXPECT_EQ(m.num_normals, 2);
  EXPECT_EQ(bus::from_msg(m).normals, c.normals);
  m.normals[1] = {0.5f, 0, 0};
  expect_error([&] { bus::from_msg(m); }, "CLOUD normals[1] is neither a unit vector nor zero (length 0.5");
  m.normals[1] = {std::nanf(""), 0, 0};
  expect_error([&] { bus::from_msg(m); }, "CLOUD normals[1] is neither a unit vector nor zero");
  m.normals.pop_back();
  m.num_normals = 1;
  expect_error([&] { bus::from_msg(m); }, "CLOUD num_normals = 1: neither 0 nor num_points (2)");
  c.normals.clear();
  EXPECT_TRUE(bus::from_msg(bus::to_msg(c)).normals.empty());
}

// MESH_REQUEST and MESH_RESULT round trip; a request's views are bounded and ascending, a
// result's figures checked.
TEST(ConvertScan, MeshRequestsAndResultsAreChecked) {
  MeshRequest q;
  q.scan_id = "s";
  q.request_id = 9;
  q.views = {0, 2, 5};
  q.camera = CameraIntrinsics{320, 180, 200, 200, 160, 90};
  q.point_spacing_m = 0.002;
  mesh_request_t qm = bus::to_msg(q);
  EXPECT_EQ(qm.views, (std::vector<int32_t>{1, 3, 6}));  // the message counts from 1
  const MeshRequest back = bus::from_msg(qm, 1000);
  EXPECT_EQ(back.views, q.views);
  EXPECT_EQ(back.camera.cx, 160.0);
  qm.views = {1, 3, 3};
  expect_error([&] { bus::from_msg(qm, 1000); }, "MESH_REQUEST views[2] = 3: the views are 1..1000, ascending");
  qm.views = {1001};
  expect_error([&] { bus::from_msg(qm, 1000); }, "MESH_REQUEST views[0] = 1001");
  qm.views = {0};
  expect_error([&] { bus::from_msg(qm, 1000); }, "MESH_REQUEST views[0] = 0: the views are 1..1000, ascending");
  qm.views = {};
  expect_error([&] { bus::from_msg(qm, 1000); }, "MESH_REQUEST num_views = 0 is outside 1..1000");
  qm = bus::to_msg(q);
  qm.width = 0;
  expect_error([&] { bus::from_msg(qm, 1000); }, "MESH_REQUEST camera:");

  MeshResult r;
  r.scan_id = "s";
  r.request_id = 9;
  r.ok = true;
  r.mesh.files = {"mesh.ply", "mesh.obj"};
  r.mesh.triangles = 12;
  r.mesh.watertight = true;
  r.mesh.volume_m3 = 0.001;
  r.mesh.voxel_m = 0.001;
  r.mesh.truncation_m = 0.004;
  r.mesh.image_scale = 2;
  mesh_result_t rm = bus::to_msg(r);
  const MeshResult got = bus::from_msg(rm);
  EXPECT_TRUE(got.ok);
  EXPECT_EQ(got.mesh.triangles, 12u);
  EXPECT_EQ(got.mesh.volume_m3, 0.001);
  EXPECT_EQ(got.mesh.files, r.mesh.files);
  rm.triangles = -1;
  expect_error([&] { bus::from_msg(rm); }, "MESH_RESULT triangles = -1 is negative");
  rm = bus::to_msg(r);
  rm.method = 5;
  expect_error([&] { bus::from_msg(rm); }, "MESH_RESULT method = 5");
  rm = bus::to_msg(r);
  rm.area_m2 = std::nan("");
  expect_error([&] { bus::from_msg(rm); }, "MESH_RESULT area_m2");
  rm.status = mesh_result_t::kFailed;  // no mesh: its figures are not read
  rm.message = "no accepted view";
  EXPECT_FALSE(bus::from_msg(rm).ok);
  EXPECT_EQ(bus::from_msg(rm).message, "no accepted view");
}

TEST(ConvertScan, VoxelMapAndEllipsoidSummariesAreChecked) {
  voxel_set_t v{};
  v.scan_id = "s";
  v.iteration = 3;
  v.request_id = (int64_t{1} << 40) + 5;
  v.updated = true;
  v.resolution_m = 0.03;
  v.bbox_max_m[0] = 0.3;
  v.num_empty = 12;
  v.num_frontier = 2;
  v.frontier_centres_m = {{0, 0, 0}, {0.03f, 0, 0}};
  const VoxelMapSummary s = bus::from_msg(v);
  EXPECT_EQ(s.iteration, 3);
  EXPECT_EQ(s.request_id, (int64_t{1} << 40) + 5);  // the view's capture request, whole
  EXPECT_EQ(s.num_empty, 12);
  EXPECT_EQ(s.num_frontier, 2);
  EXPECT_EQ(s.bbox_max_m.x(), 0.3);
  v.num_unknown = -1;
  expect_error([&] { bus::from_msg(v); }, "VOXEL_MAP num_unknown");
  v.num_unknown = 0;
  v.bbox_min_m[1] = std::numeric_limits<double>::infinity();
  expect_error([&] { bus::from_msg(v); }, "VOXEL_MAP bbox corner 1");

  ellipsoid_set_t e{};
  e.scan_id = "s";
  e.iteration = 3;
  e.request_id = (int64_t{1} << 40) + 5;
  e.fit_s = 0.01;
  e.num_ellipsoids = 2;
  e.ellipsoids.resize(2);
  e.ellipsoids[0].cls = ellipsoid_t::kOccupied;
  e.ellipsoids[1].cls = ellipsoid_t::kFrontier;
  e.ellipsoids[1].quat_wxyz[0] = 1;
  e.ellipsoids[1].semi_axes_m[0] = 0.05;
  e.ellipsoids[1].num_voxels = 9;
  const EllipsoidSetSummary es = bus::from_msg(e);
  EXPECT_EQ(es.request_id, (int64_t{1} << 40) + 5);
  ASSERT_EQ(es.ellipsoids.size(), 2u);
  EXPECT_FALSE(es.ellipsoids[0].frontier);
  EXPECT_TRUE(es.ellipsoids[1].frontier);
  EXPECT_EQ(es.ellipsoids[1].semi_axes_m.x(), 0.05);
  EXPECT_EQ(es.ellipsoids[1].num_voxels, 9);
  e.ellipsoids[0].cls = 5;
  expect_error([&] { bus::from_msg(e); }, "ELLIPSOIDS ellipsoids[0].cls");
}

TEST(ConvertScan, ScanStatesAreTheMessageConstants) {
  const std::pair<ScanState, int8_t> states[] = {
      {ScanState::kStarting, scan_status_t::kStarting}, {ScanState::kMoving, scan_status_t::kMoving},
      {ScanState::kCapturing, scan_status_t::kCapturing}, {ScanState::kIntegrating, scan_status_t::kIntegrating},
      {ScanState::kPlanning, scan_status_t::kPlanning}, {ScanState::kDone, scan_status_t::kDone},
      {ScanState::kFailed, scan_status_t::kFailed},     {ScanState::kStopped, scan_status_t::kStopped}};
  for (const auto& [state, constant] : states) {
    ScanStatus s;
    s.state = state;
    EXPECT_EQ(bus::to_msg(s).state, constant);
  }
  ScanStatus s;
  s.scan_id = "s";
  s.iteration = 4;
  s.num_views_done = 3;
  s.num_points = 1234;
  s.message = "moving to view 5";
  const scan_status_t m = bus::to_msg(s);
  EXPECT_EQ(m.iteration, 4);
  EXPECT_EQ(m.num_views_done, 3);
  EXPECT_EQ(m.num_points, 1234);
  EXPECT_EQ(m.message, "moving to view 5");
}

TEST(ConvertScan, DecodedArraysAlwaysHaveTheLengthOfTheirCount) {
  // Why no receiver checks "num_x == x.size()": lcm-gen's decoder reads the count and then
  // exactly that many elements, so a decoded message always agrees with itself; a buffer too
  // short for its count does not decode at all (the bus rejects it before any handler).
  const view_plan_t sent = plan_message(4);
  std::vector<uint8_t> buf(static_cast<std::size_t>(sent.getEncodedSize()));
  ASSERT_EQ(sent.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  view_plan_t got;
  ASSERT_GT(got.decode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  EXPECT_EQ(got.alternatives.size(), 4u);
  EXPECT_EQ(got.alternative_quality.size(), 4u);
  EXPECT_EQ(got.allowed_sectors.size(), 2u);
  // The same bytes cut before the last alternative quality: the decoder refuses them.
  view_plan_t cut;
  EXPECT_LT(cut.decode(buf.data(), 0, static_cast<int>(buf.size()) - 8), 0);
}
