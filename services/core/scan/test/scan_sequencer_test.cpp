// The coordinator's per-view sequence without a bus: a fake clock stepped by 0.25 s, and
// hand-made answers from the "services" (each arrives a fixed time after its request), so every
// round trip, deadline and re-send below can be checked by hand.
#include "core/scan/scan_sequencer.hpp"

#include <gtest/gtest.h>

#include "error_message.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <set>

#include "core/base/format.hpp"
#include "core/base/units.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "core/surface/scan_model.hpp"
#include "file_test_util.hpp"

using namespace pbnbv;
using nlohmann::json;

namespace {

constexpr double kStep = 0.25;  // the fake clock's tick, s (exact in binary)

// A scan's settings for the tests: a 0.2 m cube object, the arm rig, 3 views.
ScanSettings test_settings(const std::string& planner, int views) {
  ScanSettings s;
  s.scan_id = "unit-scan";
  s.rig = RigKind::kArm;
  s.planner = parse_name<PlannerKind>(planner);
  s.views = views;
  s.normalisation.extent_m = Eigen::Vector3d::Constant(0.2);
  s.object_z_m = 0.1;
  s.keepout_min_m = Eigen::Vector3d(-0.12, -0.12, -0.1);
  s.keepout_max_m = Eigen::Vector3d::Constant(0.12);
  s.working_distance_m = 0.6;
  s.ring_elevation_deg = 30;
  s.move_timeout_s = 60;
  s.capture_timeout_s = 10;
  s.startup_timeout_s = 90;
  s.map_pose = MapPose::kRegistered;  // the sequence most tests below follow; the rig's pose: its own tests
  return s;
}

// Ten points 1 cm apart along x, 10 cm further on for each view: no two fall in one 2 mm voxel.
PointCloud view_points(int view) {
  PointCloud c;
  for (int k = 0; k < 10; ++k) c.emplace_back(0.1f * view + 0.01f * k, 0.05f, 0.02f);
  return c;
}

// A camera pose looking at the origin from `eye`.
Pose view_from(double x, double y, double z) { return look_at_z_up(Eigen::Vector3d(x, y, z), Eigen::Vector3d::Zero()); }

class ScanSequencerTest : public pbnbv::testing::TempDirTest {
 protected:
  // Starts a scan and lets every service be heard at t = 0.
  void start(const ScanSettings& s, bool hear_everyone = true) {
    settings_ = s;
    model_.emplace(dir_, s.voxel_m, s.stop_radius_m);
    model_->restore();  // a resumed scan's
    seq_ = std::make_unique<ScanSequencer>(s, dir_);
    if (recorded_) seq_->replay(*recorded_, "recorded/scan.json");
    seq_->start(now_);
    collect();
    if (hear_everyone) {
      for (const char* w : {"ARM_STATUS", "TURNTABLE_STATUS", "heartbeat of motion", "heartbeat of camera",
                            "heartbeat of registration", "heartbeat of mapping", "heartbeat of scorer",
                            "heartbeat of ellipsoids"}) {
        deliver(Heard{w});
      }
    }
  }

  // Steps the clock until the scan ends or `until_s`, delivering answers when they are due.
  void run(double until_s = 3600) {
    while (!seq_->finished() && now_ < until_s) {
      now_ += kStep;
      while (!due_.empty() && due_.begin()->first <= now_) {
        const ScanEvent e = due_.begin()->second;
        due_.erase(due_.begin());
        deliver(e);
      }
      seq_->tick(now_);
      collect();
    }
  }

  void deliver(const ScanEvent& e) {
    seq_->handle(e, now_);
    collect();
  }

  // Takes the sequencer's outputs and lets the fake services answer its requests.
  void collect() {
    for (const ScanOutput& out : seq_->take_outputs()) {
      if (const auto* r = std::get_if<MoveRequest>(&out)) {
        moves_.push_back({now_, *r});
        if (auto a = motion(*r)) later(2.0, *a);
      } else if (const auto* r = std::get_if<CaptureRequest>(&out)) {
        captures_.push_back({now_, *r});
        answer_capture(*r);
      } else if (const auto* r = std::get_if<PlanRequest>(&out)) {
        plans_.push_back({now_, *r});
        if (auto a = scorer(*r)) later(0.5, *a);
      } else if (const auto* r = std::get_if<MeshRequest>(&out)) {
        meshes_.push_back({now_, *r});
        if (auto a = mesher(*r)) later(0.5, *a);
      } else if (const auto* s = std::get_if<ScanStatus>(&out)) {
        statuses_.push_back(*s);
      } else if (const auto* p = std::get_if<ProgressLine>(&out)) {
        lines_.push_back(p->text);
      }
    }
  }

  void later(double delay_s, const ScanEvent& e) { due_.emplace(now_ + delay_s, e); }

  // The camera answers after 1 s, the registration 0.5 s after the cloud (register_after_s), the
  // map 0.25 s after that and (pbnbv) the ellipsoids 0.25 s after the map. With the map at the
  // rig's pose (settings' map_pose rig) the map comes 0.25 s after the cloud, whenever the
  // registration does.
  double register_after_s_ = 0.5;
  void answer_capture(const CaptureRequest& r) {
    std::optional<CaptureResult> c = camera(r);
    if (!c) return;
    later(1.0, *c);
    if (auto reg = registration(*c)) {
      add_to_model(*reg);
      const bool rig_pose = settings_.map_pose == MapPose::kRig;
      const double map_at = rig_pose ? 1.25 : 1.25 + register_after_s_;
      if (std::isfinite(register_after_s_)) later(1.0 + register_after_s_, *reg);
      if (!rig_pose && !std::isfinite(register_after_s_)) return;
      if (auto map = mapping(*reg)) {
        later(map_at, *map);
        if (settings_.planner == PlannerKind::kPbnbv) later(map_at + 0.25, ellipsoids(map->iteration, map->request_id));
      }
    }
  }

  // ---- The fake services' answers (a test replaces the one it is about) ----

  std::function<std::optional<MoveResult>(const MoveRequest&)> motion = [](const MoveRequest& r) {
    MoveResult m;
    m.scan_id = r.scan_id;
    m.iteration = r.iteration;
    m.request_id = r.request_id;
    m.status = MoveStatus::kReached;
    m.requested_object_T_camera = m.reached_object_T_camera = r.object_T_camera;
    m.position_error_m = 0.001;
    m.angle_error_rad = 0.01;
    m.joint_position_rad = Vector6d::Constant(0.1 * (r.iteration + 1));
    m.joint_target_rad = m.joint_position_rad;
    m.turntable_angle_rad = m.turntable_target_rad = 0.5 * r.iteration;
    m.plan_s = 0.125;
    m.move_s = 1.0;
    m.settle_s = 0.5;
    m.rig_motion_s = 1.25;
    m.settled_utime = 1000000 * (r.iteration + 1);
    m.within_tolerance_utime = m.settled_utime - 500000;  // 0.75 s of motion, 0.5 s of settling
    return m;
  };

  std::function<std::optional<CaptureResult>(const CaptureRequest&)> camera = [](const CaptureRequest& r) {
    CaptureResult c;
    c.scan_id = r.scan_id;
    c.iteration = r.iteration;
    c.request_id = r.request_id;
    c.ok = true;
    c.message = "ok";
    c.object_T_camera = view_from(0.5, 0.1 * r.iteration, 0.4);
    c.depth_frame_seq = 100 + r.iteration;
    c.num_valid_pixels = 5000;
    c.num_cropped = 7;
    c.capture_s = 0.75;
    c.process_s = 0.0625;
    c.points = view_points(r.iteration);
    return c;
  };

  std::function<std::optional<RegisteredCloud>(const CaptureResult&)> registration = [](const CaptureResult& c) {
    RegisteredCloud r;
    r.scan_id = c.scan_id;
    r.iteration = c.iteration;
    r.request_id = c.request_id;
    r.cloud = c;
    r.kinematic_object_T_camera = c.object_T_camera;
    r.accepted = c.ok;
    r.reason = "kinematic pose kept";
    r.register_s = 0.25;
    return r;
  };

  std::function<std::optional<VoxelMapSummary>(const RegisteredCloud&)> mapping = [](const RegisteredCloud& r) {
    VoxelMapSummary m;
    m.scan_id = r.scan_id;
    m.iteration = r.iteration;
    m.request_id = r.request_id;
    m.updated = r.accepted;
    m.message = r.accepted ? "updated" : "registration rejected the view";
    m.resolution_m = 0.03;
    m.bbox_min_m = Eigen::Vector3d::Constant(-0.3);
    m.bbox_max_m = Eigen::Vector3d::Constant(0.3);
    m.num_none = 100;
    m.num_empty = 200;
    m.num_occupied = 30;
    m.num_unknown = 400;
    m.num_frontier = 5;
    m.update_s = 0.002;
    return m;
  };

  // The camera's capture of view `view` fails, saying `why`.
  void fail_capture(int view, const std::string& why) {
    camera = [inner = camera, view, why](const CaptureRequest& r) {
      std::optional<CaptureResult> c = inner(r);
      if (r.iteration == view) {
        c->ok = false;
        c->message = why;
        c->points.clear();
      }
      return c;
    };
  }

  // The rig cannot reach a view below the turntable top (z < 0).
  void unreachable_below() {
    motion = [inner = motion](const MoveRequest& r) {
      std::optional<MoveResult> m = inner(r);
      if (r.object_T_camera.translation().z() < 0) {
        m->status = MoveStatus::kUnreachable;
        m->reason = "no inverse kinematics solution";
      }
      return m;
    };
  }

  // What the registration service does with an answer it sends (the real model: frames/,
  // cloud.ply, the new surface), once per capture request.
  void add_to_model(RegisteredCloud& r) {
    if (!r.cloud.ok) return;
    auto [done, first] = modelled_.try_emplace(r.request_id);
    if (first) {
      const ModelUpdate u = model_->add_view(r.iteration, r.cloud.points, {}, r.cloud.object_T_camera, r.accepted);
      done->second.frame_file = u.frame_file;
      done->second.normals_from_depth = u.normals_from_depth;
      done->second.new_surface = u.new_surface;
      done->second.accumulate_s = 0.125;
      done->second.model_points = static_cast<int>(model_->points().size());
    }
    r.frame_file = done->second.frame_file;  // a repeat: answered as the first time
    r.normals_from_depth = done->second.normals_from_depth;
    r.new_surface = done->second.new_surface;
    r.accumulate_s = done->second.accumulate_s;
    r.model_points = done->second.model_points;
  }

  // The registration service's mesh of the views asked for (the real one, from the frames).
  std::function<std::optional<MeshResult>(const MeshRequest&)> mesher = [this](const MeshRequest& r) {
    MeshResult m;
    m.scan_id = r.scan_id;
    m.request_id = r.request_id;
    try {
      m.mesh = model_->mesh(r.views, r.camera, r.point_spacing_m);
      m.ok = true;
    } catch (const std::exception& e) {
      m.message = e.what();
    }
    return m;
  };

  static EllipsoidSetSummary ellipsoids(int map_view, int64_t map_request_id) {
    EllipsoidSetSummary e;
    e.scan_id = "unit-scan";
    e.iteration = map_view;
    e.request_id = map_request_id;
    e.occupied_components = 1;
    e.frontier_components = 1;
    e.fit_s = 0.02;
    EllipsoidSummary f;
    f.frontier = true;
    f.centre_m = Eigen::Vector3d(0.01, 0.02, 0.03);
    f.semi_axes_m = Eigen::Vector3d(0.05, 0.04, 0.03);
    f.num_voxels = 12;
    e.ellipsoids = {f};
    return e;
  }

  // A plan for every request: a view from +y above, no alternatives.
  std::function<std::optional<ViewPlan>(const PlanRequest&)> scorer = [](const PlanRequest& r) {
    return make_plan(r, view_from(0.1, 0.7, 0.3 + 0.01 * r.iteration), {});
  };

  static ViewPlan make_plan(const PlanRequest& r, const Pose& best, const std::vector<Pose>& alternatives) {
    ViewPlan p;
    p.scan_id = r.scan_id;
    p.iteration = r.iteration;
    p.request_id = r.request_id;
    p.planner = r.planner;
    p.outcome = PlanOutcome::kView;
    p.reason = "best F";
    p.object_T_camera = best;
    p.view_quality = 1234.5;
    p.first_quality = 2000;
    p.num_candidates = 800;
    p.num_unreachable = 40;
    p.num_scored = 760;
    p.plan_s = 0.1;
    p.alternatives = alternatives;
    p.alternative_quality.assign(alternatives.size(), 1000.0);
    return p;
  }

  json scan_json() const { return read_json((dir_ / "scan.json").string()); }

  // Move requests of view i, in order.
  std::vector<MoveRequest> moves_of(int i) const {
    std::vector<MoveRequest> out;
    for (const auto& [t, r] : moves_) {
      if (r.iteration == i) out.push_back(r);
    }
    return out;
  }

  ScanSettings settings_;
  std::optional<std::vector<std::vector<Pose>>> recorded_;  // replaying these views' poses
  std::unique_ptr<ScanSequencer> seq_;
  double now_ = 0;
  std::multimap<double, ScanEvent> due_;
  std::vector<std::pair<double, MoveRequest>> moves_;
  std::vector<std::pair<double, CaptureRequest>> captures_;
  std::vector<std::pair<double, PlanRequest>> plans_;
  std::vector<std::pair<double, MeshRequest>> meshes_;
  std::optional<ScanModel> model_;        // the registration service's
  std::map<int64_t, RegisteredCloud> modelled_;  // by capture request: what the model made of its view
  std::vector<ScanStatus> statuses_;
  std::vector<std::string> lines_;
};

TEST_F(ScanSequencerTest, ThreeViewRingScanEndToEnd) {
  start(test_settings("ring", 3));
  run();
  ASSERT_TRUE(seq_->finished());
  EXPECT_EQ(seq_->exit_code(), 0);
  EXPECT_EQ(seq_->state(), ScanState::kDone);
  // Each view: move answered after 2 s, cloud 1 s later, registration 0.5 s, map 0.25 s:
  // 3.75 s a view, 11.25 s for three; then the mesh, answered 0.5 s after its request.
  EXPECT_EQ(now_, 11.75);
  ASSERT_EQ(moves_.size(), 3u);
  ASSERT_EQ(captures_.size(), 3u);
  EXPECT_TRUE(plans_.empty());
  ASSERT_EQ(meshes_.size(), 1u);
  EXPECT_EQ(meshes_[0].first, 11.25);
  EXPECT_EQ(meshes_[0].second.views, std::vector<int>({0, 1, 2}));  // the merged views
  EXPECT_EQ(meshes_[0].second.point_spacing_m, settings_.voxel_m);
  EXPECT_EQ(meshes_[0].second.camera.width, settings_.camera.width);
  // The ring: radius d_c + half the cube's diagonal = 0.6 + 0.1 * sqrt(3), 30 deg up, azimuths
  // 0, 120, 240 deg.
  const double radius = 0.6 + 0.1 * std::sqrt(3.0);
  for (int k = 0; k < 3; ++k) {
    const double az = deg_to_rad(120.0 * k), el = deg_to_rad(30.0);
    const Eigen::Vector3d eye = radius * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    EXPECT_LT((moves_[k].second.object_T_camera.translation() - eye).norm(), 1e-12) << "view " << k;
    EXPECT_EQ(moves_[k].first, 3.75 * k);
    // The capture waits for a frame exposed after the rig settled.
    EXPECT_EQ(captures_[k].second.not_before_utime, 1000000 * (k + 1));
    EXPECT_EQ(captures_[k].first, 3.75 * k + 2.0);
  }
  // Keep-out and crop boxes pass from the settings to the requests.
  EXPECT_EQ(moves_[0].second.keepout.min(), Eigen::Vector3d(-0.12, -0.12, -0.1));
  EXPECT_EQ(captures_[0].second.crop.max(), Eigen::Vector3d::Constant(0.5));

  const json scan = scan_json();
  EXPECT_EQ(scan["status"]["state"], "done");
  EXPECT_EQ(scan["status"]["message"], "scan complete: view budget reached (--views 3)");
  EXPECT_EQ(scan["status"]["views_done"], 3);
  EXPECT_EQ(scan["status"]["views_planned"], 3);
  EXPECT_EQ(scan["status"]["num_points"], 30);
  EXPECT_EQ(scan["status"]["elapsed_s"], 11.75);
  EXPECT_EQ(scan["stop"], json({{"reason", "view budget reached (--views 3)"}, {"after_views", 3}, {"rule", "budget"}}));
  EXPECT_EQ(scan["plan"]["planner"], "ring");
  EXPECT_NEAR(scan["plan"]["radius_m"].get<double>(), radius, 1e-15);
  EXPECT_EQ(scan["plan"]["elevation_deg"], 30.0);
  EXPECT_EQ(scan["settings"]["scan_id"], "unit-scan");
  ASSERT_EQ(scan["views"].size(), 3u);
  for (int k = 0; k < 3; ++k) {
    const json& v = scan["views"][k];
    EXPECT_EQ(v["view"], k + 1);  // counted from 1, as view_001
    EXPECT_FALSE(v.contains("plan"));
    EXPECT_EQ(v["option"], 0);
    EXPECT_EQ(v["move"]["status"], "reached");
    EXPECT_NEAR(v["move"]["angle_error_deg"].get<double>(), 0.01 * 180 / kPi, 1e-12);
    EXPECT_EQ(v["capture"]["status"], "ok");
    EXPECT_EQ(v["capture"]["num_points"], 10);
    EXPECT_EQ(v["capture"]["depth_frame_seq"], 100 + k);
    EXPECT_EQ(v["registration"]["accepted"], true);
    EXPECT_EQ(v["map"]["voxels"]["frontier"], 5);
    EXPECT_EQ(v["frame_file"], "frames/view_00" + std::to_string(k + 1) + ".ply");
    EXPECT_EQ(v["merged"], true);
    EXPECT_EQ(v["time_s"]["move_round_trip"], 2.0);
    EXPECT_EQ(v["time_s"]["capture_round_trip"], 1.0);
    EXPECT_EQ(v["time_s"]["register_round_trip"], 0.5);
    EXPECT_EQ(v["time_s"]["map_round_trip"], 0.25);
    EXPECT_EQ(v["time_s"]["move"], 1.0);
    EXPECT_GE(v["time_s"]["view_total"].get<double>(), 3.75);
    EXPECT_EQ(read_ply((dir_ / v["frame_file"].get<std::string>()).string()).size(), 10u);
    // Rig time: 0.75 s of motion and 0.5 s of settling (the move's rig clock); the capture from
    // the settled move's answer (3.75k + 2.0) to the frame's arrival at the camera service (the
    // cloud answered at 3.75k + 3.0, less its 0.0625 s of processing): 0.9375 s; the rig waits from
    // there to the next command (the next move answered at 3.75k + 5.75, less its 1.5 s of moving
    // and settling): 1.3125 s; after the last view until the scan stops with its map at 11.25 s:
    // 0.8125 s.
    const double compute = k < 2 ? 1.3125 : 0.8125;
    EXPECT_EQ(v["rig_time_s"], json({{"motion", 0.75}, {"settle", 0.5}, {"capture", 0.9375}, {"compute", compute},
                                     {"total", 2.1875 + compute}}))
        << "view " << k + 1;
  }
  // The scan's wall time from the first command (2.0 - 1.5 s) to its stop (11.25 s), 10.75 s, with
  // its three moves' 1.5 s of wall time each replaced by their 1.25 s on the rig's clock: 10 s.
  EXPECT_EQ(scan["rig_time_s"], json({{"motion", 2.25}, {"settle", 1.5}, {"capture", 2.8125}, {"compute", 3.4375},
                                      {"total", 10.0}, {"views", 3}, {"views_incomplete", 0}}));
  EXPECT_EQ(read_ply((dir_ / "cloud.ply").string()).size(), 30u);
  // The finished scan's mesh: the three merged frames' 30 points fused (core/surface tests its shape).
  ASSERT_TRUE(scan.contains("mesh"));
  EXPECT_EQ(scan["mesh"]["frames"], 3) << scan["mesh"];
  EXPECT_EQ(scan["mesh"]["points"], 30);
  for (const char* f : {"mesh.ply", "mesh.obj"}) EXPECT_TRUE(std::filesystem::exists(dir_ / f)) << f;

  // Status: starting, then per view moving, capturing, registering, adding; then done.
  ASSERT_FALSE(statuses_.empty());
  EXPECT_EQ(statuses_.front().state, ScanState::kStarting);
  EXPECT_EQ(statuses_.back().state, ScanState::kDone);
  EXPECT_EQ(statuses_.back().num_views_done, 3);
  EXPECT_EQ(statuses_.back().num_points, 30);
  int moving = 0;
  for (const auto& s : statuses_) moving += s.state == ScanState::kMoving && s.message.rfind("moving to view", 0) == 0;
  EXPECT_GE(moving, 3);
  // Progress: the stages of each view, then its summary.
  const std::vector<std::string> first = {"[view 1/3] moving", "[view 1/3] capturing", "[view 1/3] registering",
                                          "[view 1/3] mapping"};
  ASSERT_GE(lines_.size(), 5u);
  EXPECT_EQ(std::vector<std::string>(lines_.begin(), lines_.begin() + 4), first);
  EXPECT_EQ(lines_[4], "[view 1/3] done: 10 points, 10 in the model; kinematic pose kept, 5 frontier voxels; "
                       "move 1.50 s, capture 0.75 s, register 0.25 s, map 2.00 ms; 100.00 % new surface");
  EXPECT_EQ(lines_.back(), "mesh.ply: " + std::to_string(scan["mesh"]["triangles"].get<std::size_t>()) + " triangles, " +
                              std::to_string(scan["mesh"]["boundary_loops"].get<std::size_t>()) + " holes, " +
                              fixed(scan["mesh"]["seconds"].get<double>(), 2) + " s");
  EXPECT_EQ(seq_->summary(), "scan complete: view budget reached (--views 3): 3 of 3 views, 30 points, 11.75 s; rig time "
                             "10.0 s (motion 2.2, settle 1.5, capture 2.8, compute 3.4) -> " +
                                 (dir_ / "scan.json").string());
}

// The mesh is the registration service's: a lost MESH_RESULT is asked for again with the same id
// every 3 s; one that never comes, or says there is no mesh, leaves the scan done with the reason
// in scan.json's "mesh".
TEST_F(ScanSequencerTest, TheScanEndsDoneWhenItsMeshIsLateLostOrFails) {
  int asked = 0;
  mesher = [&](const MeshRequest& r) -> std::optional<MeshResult> {
    if (++asked < 3) return std::nullopt;  // the first two answers are lost
    MeshResult m;
    m.scan_id = r.scan_id;
    m.request_id = r.request_id;
    m.message = "frames/view_002.ply: no such file";
    return m;
  };
  start(test_settings("ring", 3));
  run();
  ASSERT_EQ(seq_->exit_code(), 0);
  ASSERT_EQ(meshes_.size(), 3u);
  EXPECT_EQ(meshes_[1].first - meshes_[0].first, 3.0);  // re-sent every resend_s
  EXPECT_EQ(meshes_[2].second.request_id, meshes_[0].second.request_id);
  EXPECT_EQ(now_, 11.25 + 6.5);
  json scan = scan_json();
  EXPECT_EQ(scan["status"]["state"], "done");
  EXPECT_EQ(scan["mesh"], json({{"error", "frames/view_002.ply: no such file"}}));
  EXPECT_EQ(lines_.back(), "no mesh: frames/view_002.ply: no such file");

  // No answer at all: done after mesh_s (600 s), naming the registration service.
  TearDown();
  SetUp();
  meshes_.clear();
  mesher = [](const MeshRequest&) -> std::optional<MeshResult> { return std::nullopt; };
  now_ = 0;
  start(test_settings("ring", 3));
  run();
  ASSERT_EQ(seq_->exit_code(), 0);
  EXPECT_EQ(now_, 11.25 + 600.0);
  scan = scan_json();
  EXPECT_EQ(scan["mesh"]["error"], "the registration service sent no MESH_RESULT in 600 s (the mesh request sent 200 times)");
}

TEST_F(ScanSequencerTest, AnUnreachableBestViewIsReplacedByTheNextAlternative) {
  const Pose best = view_from(0.0, 0.0, -0.7);  // from below the table: the rig cannot
  const Pose alternative = view_from(0.7, 0.0, 0.3);
  scorer = [&](const PlanRequest& r) { return make_plan(r, r.iteration == 1 ? best : view_from(0, 0.7, 0.3), {alternative}); };
  unreachable_below();
  start(test_settings("pbnbv", 3));
  run();
  ASSERT_EQ(seq_->exit_code(), 0);
  // View 1 (the first planned one): the best view, then its alternative, each with its own id.
  const std::vector<MoveRequest> tries = moves_of(1);
  ASSERT_EQ(tries.size(), 2u);
  EXPECT_TRUE(tries[0].object_T_camera.isApprox(best));
  EXPECT_TRUE(tries[1].object_T_camera.isApprox(alternative));
  EXPECT_NE(tries[0].request_id, tries[1].request_id);
  // The plan for view 2 excludes the unreachable view and starts from view 1's joints.
  ASSERT_EQ(plans_.size(), 2u);
  const PlanRequest& next = plans_[1].second;
  EXPECT_EQ(next.iteration, 2);
  EXPECT_EQ(next.map_iteration, 1);
  EXPECT_EQ(next.seed, 1 + 2);
  ASSERT_EQ(next.excluded.size(), 1u);
  EXPECT_TRUE(next.excluded[0].isApprox(best));
  EXPECT_EQ(next.views_done.size(), 2u);
  EXPECT_EQ(next.joint_position_rad, Vector6d::Constant(0.2));
  EXPECT_TRUE(next.check_reachability);
  EXPECT_TRUE(std::isnan(plans_[0].second.first_quality)) << "unknown before the first plan";
  EXPECT_EQ(next.first_quality, 2000);

  const json scan = scan_json();
  EXPECT_EQ(scan["plan"]["planner"], "pbnbv");
  const json& v0 = scan["views"][0];
  EXPECT_EQ(v0["plan"], json({{"planner", "initial view"}}));
  const json& v1 = scan["views"][1];
  EXPECT_EQ(v1["option"], 1);
  ASSERT_EQ(v1["failed_moves"].size(), 1u);
  EXPECT_EQ(v1["failed_moves"][0]["option"], 0);
  EXPECT_EQ(v1["failed_moves"][0]["status"], "unreachable");
  EXPECT_EQ(v1["failed_moves"][0]["reason"], "no inverse kinematics solution");
  // The unreachable option's pose, so that a resumed scan excludes it again: the plan's best view.
  EXPECT_NEAR(v1["failed_moves"][0]["object_T_camera"]["position_m"][2].get<double>(), -0.7, 1e-12);
  EXPECT_NEAR(v1["requested_object_T_camera"]["position_m"][0].get<double>(), 0.7, 1e-12);
  EXPECT_EQ(v1["move"]["status"], "reached");
  // Two moves of 2 s each.
  EXPECT_EQ(v1["time_s"]["move_round_trip"], 4.0);
  // Rig time: the refused option moved nothing (view 2's motion is its alternative's), and the
  // rig stood waiting from view 1's frame (3.0 - 0.0625 s) through the map, the plan, the refusal
  // and the alternative's command (answered at 8.25 s less 1.5 s of moving and settling).
  EXPECT_EQ(v1["rig_time_s"]["motion"], 0.75);
  EXPECT_EQ(v0["rig_time_s"]["compute"], 8.25 - 1.5 - 2.9375);
  // The plan as recorded: from the map of view 0, with that map's and the ellipsoids' times.
  const json& plan = v1["plan"];
  EXPECT_EQ(plan["outcome"], "view");
  EXPECT_EQ(plan["map_of_view"], 1);  // counted from 1
  EXPECT_EQ(plan["candidates"], json({{"generated", 800}, {"unreachable", 40}, {"excluded", 0}, {"scored", 760}}));
  EXPECT_EQ(plan["figure"], "plans/view_002.png");
  EXPECT_NEAR(plan["planner_step_ms"].get<double>(), 2.0 + 20.0 + 100.0, 1e-9);
  EXPECT_NEAR(plan["time_ms"]["ellipsoid_fit"].get<double>(), 20.0, 1e-12);
  ASSERT_EQ(plan["ellipsoids"]["list"].size(), 1u);
  EXPECT_EQ(plan["ellipsoids"]["list"][0]["class"], "frontier");
  EXPECT_EQ(plan["ellipsoids"]["list"][0]["voxels"], 12);
  EXPECT_EQ(plan["alternative_quality_px"], json::array({1000.0}));
}

// The first view out of reach: the rig tries the same view 45 deg round the vertical axis, then
// -45 deg, ... (first_view_options), and the scan goes on from the first it reaches instead of
// failing.
TEST_F(ScanSequencerTest, AnUnreachableFirstViewFallsBackToTheNextOption) {
  ScanSettings s = test_settings("pbnbv", 2);
  const std::vector<Pose> options = first_view_options(s);
  ASSERT_EQ(options.size(), 24u);  // 8 azimuths x 3 elevations
  // Same distance from the centre, 45 deg apart in azimuth at the same height.
  const Eigen::Vector3d a = options[0].translation(), b = options[1].translation();
  EXPECT_NEAR(a.norm(), b.norm(), 1e-12);
  EXPECT_NEAR(a.z(), b.z(), 1e-12);
  EXPECT_NEAR(std::acos(a.head<2>().normalized().dot(b.head<2>().normalized())), kPi / 4, 1e-9);
  motion = [inner = motion, first = options[0]](const MoveRequest& r) {
    std::optional<MoveResult> m = inner(r);
    if (r.object_T_camera.isApprox(first)) {
      m->status = MoveStatus::kUnreachable;
      m->reason = "the turntable's housing is in the way";
    }
    return m;
  };
  start(s);
  run();
  ASSERT_EQ(seq_->exit_code(), 0);
  const std::vector<MoveRequest> tries = moves_of(0);
  ASSERT_EQ(tries.size(), 2u);
  EXPECT_TRUE(tries[0].object_T_camera.isApprox(options[0]));
  EXPECT_TRUE(tries[1].object_T_camera.isApprox(options[1]));
  const json v0 = scan_json()["views"][0];
  EXPECT_EQ(v0["option"], 1);
  EXPECT_EQ(v0["failed_moves"][0]["reason"], "the turntable's housing is in the way");
  EXPECT_EQ(scan_json()["status"]["views_done"], 2);
}

TEST_F(ScanSequencerTest, MoreThanAHundredAlternativesKeepRequestIdsUnique) {
  // View 1's plan has 120 alternatives; only the last is reachable. The motion executor answers
  // a request id it has seen with the answer it gave (idempotent requests), so an id reused by
  // view 2 (as i * 100 + k did: view 1 option 100 = view 2 option 0 = 200) would get view 1's
  // "unreachable".
  std::vector<Pose> alternatives;
  for (int k = 0; k < 120; ++k) alternatives.push_back(view_from(0.5 + 0.001 * k, 0.2, k < 119 ? -0.5 : 0.5));
  scorer = [&](const PlanRequest& r) {
    return make_plan(r, r.iteration == 1 ? view_from(0.5, -0.2, -0.5) : view_from(0, 0.7, 0.3), r.iteration == 1 ? alternatives : std::vector<Pose>{});
  };
  std::map<int64_t, MoveResult> answered;
  motion = [&, inner = motion](const MoveRequest& r) -> std::optional<MoveResult> {
    if (auto a = answered.find(r.request_id); a != answered.end()) return a->second;
    std::optional<MoveResult> m = inner(r);
    if (r.object_T_camera.translation().z() < 0) {
      m->status = MoveStatus::kUnreachable;
      m->reason = "below the table";
    }
    answered[r.request_id] = *m;
    return m;
  };
  ScanSettings s = test_settings("pbnbv", 3);
  s.alternatives = 120;
  start(s);
  run();
  ASSERT_EQ(seq_->exit_code(), 0);
  ASSERT_EQ(moves_of(1).size(), 121u);
  std::set<int64_t> ids;
  for (const auto& [t, r] : moves_) ids.insert(r.request_id);
  for (const auto& [t, r] : captures_) ids.insert(r.request_id);
  for (const auto& [t, r] : plans_) ids.insert(r.request_id);
  for (const auto& [t, r] : meshes_) ids.insert(r.request_id);
  EXPECT_EQ(ids.size(), moves_.size() + captures_.size() + plans_.size() + meshes_.size()) << "a request id was used twice";
  // Consecutive from a random start: the next id is the first plus the number used.
  EXPECT_EQ(seq_->so_far().next_request_id, *ids.begin() + static_cast<int64_t>(ids.size()));
  EXPECT_GE(*ids.begin(), int64_t{1} << 32);
  const json scan = scan_json();
  EXPECT_EQ(scan["views"][1]["option"], 120);
  EXPECT_EQ(scan["views"][1]["failed_moves"].size(), 120u);
  EXPECT_EQ(scan["views"][2]["move"]["status"], "reached");
  EXPECT_EQ(scan["status"]["views_done"], 3);
  EXPECT_EQ(plans_[1].second.excluded.size(), 120u);
}

TEST_F(ScanSequencerTest, ALostMoveResultIsAskedForAgainAfterThreeSecondsWithTheSameId) {
  int asked = 0;
  motion = [&, inner = motion](const MoveRequest& r) -> std::optional<MoveResult> {
    if (++asked == 1) return std::nullopt;  // the first answer is lost
    return inner(r);
  };
  start(test_settings("ring", 1));
  run();
  ASSERT_EQ(seq_->exit_code(), 0);
  ASSERT_EQ(moves_.size(), 2u);
  EXPECT_EQ(moves_[0].first, 0.0);
  EXPECT_EQ(moves_[1].first, 3.0);
  EXPECT_EQ(moves_[1].second.request_id, moves_[0].second.request_id);
  EXPECT_TRUE(moves_[1].second.object_T_camera.isApprox(moves_[0].second.object_T_camera));
  // Answered 2 s after the second request: 5 s after the first.
  EXPECT_EQ(scan_json()["views"][0]["time_s"]["move_round_trip"], 5.0);
}

TEST_F(ScanSequencerTest, ABusyMotionExecutorIsAskedAgainAtOnce) {
  int asked = 0;
  motion = [&, inner = motion](const MoveRequest& r) -> std::optional<MoveResult> {
    std::optional<MoveResult> m = inner(r);
    if (++asked == 1) m->status = MoveStatus::kBusy;
    return m;
  };
  start(test_settings("ring", 1));
  run();
  ASSERT_EQ(seq_->exit_code(), 0);
  ASSERT_EQ(moves_.size(), 2u);
  EXPECT_EQ(moves_[1].first, 2.0);  // when "busy" arrived
  EXPECT_EQ(moves_[1].second.request_id, moves_[0].second.request_id);
}

TEST_F(ScanSequencerTest, NoMoveResultFailsTheScanAtTheMoveTimeoutPlusFifteenSeconds) {
  motion = [](const MoveRequest&) -> std::optional<MoveResult> { return std::nullopt; };
  ScanSettings s = test_settings("ring", 2);
  s.move_timeout_s = 20;
  start(s);
  run();
  EXPECT_EQ(seq_->exit_code(), 1);
  EXPECT_EQ(now_, 35.0);
  EXPECT_EQ(moves_.size(), 12u);  // at 0, 3, ..., 33 s
  const json scan = scan_json();
  EXPECT_EQ(scan["status"]["message"], "the motion executor sent no MOVE_RESULT for view 1 in 35 s (the move request sent 12 times)");
  EXPECT_EQ(scan["views"][0]["move"]["status"], "no_answer");
}

TEST_F(ScanSequencerTest, TheRegistrationDeadlineFailsTheScanNamingTheRegistrationService) {
  registration = [](const CaptureResult&) -> std::optional<RegisteredCloud> { return std::nullopt; };
  start(test_settings("ring", 2));
  run();
  ASSERT_TRUE(seq_->finished());
  EXPECT_EQ(seq_->exit_code(), 1);
  EXPECT_EQ(seq_->state(), ScanState::kFailed);
  // The cloud came at 3 s; the registration's answer is waited for 60 s.
  EXPECT_EQ(now_, 63.0);
  const json scan = scan_json();
  EXPECT_EQ(scan["status"]["state"], "failed");
  EXPECT_EQ(scan["status"]["message"],
            "the registration service sent no REGISTERED_CLOUD for view 1 in 60 s (the capture request sent 60 times)");
  EXPECT_EQ(scan["status"]["views_done"], 0);
  EXPECT_EQ(scan["status"]["elapsed_s"], 63.0);
  EXPECT_FALSE(scan.contains("stop"));
  ASSERT_EQ(scan["views"].size(), 1u);
  EXPECT_EQ(scan["views"][0]["capture"]["status"], "ok");
  EXPECT_FALSE(scan["views"][0].contains("registration"));
  EXPECT_FALSE(scan["views"][0].contains("frame_file"));
  EXPECT_EQ(seq_->summary(),
            "scan the registration service sent no REGISTERED_CLOUD for view 1 in 60 s (the capture request sent 60 "
            "times): 0 of 2 views, 0 points, 63.00 s; rig time 62.2 s (motion 0.8, settle 0.5, capture 0.9, compute "
            "60.1) -> " +
                                 (dir_ / "scan.json").string());
}

TEST_F(ScanSequencerTest, AMissingMapFailsTheScanNamingTheMappingService) {
  mapping = [](const RegisteredCloud&) -> std::optional<VoxelMapSummary> { return std::nullopt; };
  start(test_settings("ring", 2));
  run();
  EXPECT_EQ(seq_->exit_code(), 1);
  EXPECT_EQ(now_, 3.5 + 60.0);
  EXPECT_EQ(scan_json()["status"]["message"],
            "the mapping service sent no VOXEL_MAP for view 1 in 60 s (the capture request sent 60 times)");
  EXPECT_TRUE(scan_json()["views"][0].contains("registration"));
}

// ---- The map at the rig's pose (map_pose rig, the default) ----
// The registration answers 3 s after the cloud (4 s after the capture request), the map 0.25 s
// after the cloud: view 2 is planned and moved to before view 1's registration has come.

// The times of the requests sent for view i, of one kind.
template <typename Request>
std::vector<double> times_of(const std::vector<std::pair<double, Request>>& sent, int view) {
  std::vector<double> out;
  for (const auto& [t, r] : sent) {
    if (r.iteration == view) out.push_back(t);
  }
  return out;
}

TEST_F(ScanSequencerTest, WithTheMapAtTheRigsPoseTheNextViewIsPlannedAndMovedToWhileTheRegistrationRefines) {
  register_after_s_ = 3.0;
  ScanSettings s = test_settings("pbnbv", 3);
  s.map_pose = MapPose::kRig;
  start(s);
  run();
  ASSERT_TRUE(seq_->finished());
  EXPECT_EQ(seq_->exit_code(), 0) << seq_->summary();
  // View 1: moved at 0 (answer at 2), captured at 2 (cloud at 3, map at 3.25, registration at 6).
  ASSERT_EQ(times_of(captures_, 0).front(), 2.0);
  // View 2's plan is asked for on the map (3.25) and its move at the plan's answer (3.75), both
  // before view 1's registration (6); the move's answer (5.75) waits for it: view 2 is captured at 6.
  ASSERT_EQ(plans_.size(), 2u);
  EXPECT_EQ(plans_[0].first, 3.25);
  EXPECT_EQ(times_of(moves_, 1).front(), 3.75);
  EXPECT_EQ(times_of(captures_, 1).front(), 6.0);
  // The plan of view 2 took view 1 at the rig's pose (the camera's); view 3's at the registered one
  // (here the same: the fake registration keeps the kinematic pose).
  ASSERT_EQ(plans_[0].second.views_done.size(), 1u);
  EXPECT_TRUE(plans_[0].second.views_done[0].isApprox(view_from(0.5, 0.0, 0.4)));
  // Every view recorded in order, with its registration and map.
  const json scan = scan_json();
  ASSERT_EQ(scan["views"].size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const json& v = scan["views"][i];
    EXPECT_EQ(v["view"], i + 1);
    EXPECT_TRUE(v.contains("registration")) << i;
    EXPECT_TRUE(v["map"]["updated"]) << i;
    EXPECT_EQ(v["time_s"]["register_round_trip"], 3.0) << i;  // from the cloud
  }
  EXPECT_EQ(scan["status"]["views_done"], 3);
  // View 1's compute (rig time): from the frame (3 - 0.0625) to move 2's command (its answer at
  // 5.75 less 1.5 s of moving and settling: 4.25), and the rig's wait from that answer to the
  // registration (5.75 -> 6): 1.3125 + 0.25.
  EXPECT_EQ(scan["views"][0]["rig_time_s"]["compute"], 1.5625);
  // The mesh is asked for once the last view is recorded: every view in it.
  ASSERT_EQ(meshes_.size(), 1u);
  EXPECT_EQ(meshes_[0].second.views, (std::vector<int>{0, 1, 2}));
}

TEST_F(ScanSequencerTest, WithTheMapAtTheRigsPoseAViewWaitsForTheRegistrationAsLongAsAfterIt) {
  // The same fakes with the map after the registration: view 1's compute is the whole wait.
  register_after_s_ = 3.0;
  start(test_settings("pbnbv", 3));
  run();
  ASSERT_EQ(seq_->exit_code(), 0) << seq_->summary();
  // The map at 6.25, the plan asked for then, its answer at 6.75, the move's at 8.75; the frame
  // came at 2.9375.
  EXPECT_EQ(plans_[0].first, 6.25);
  EXPECT_EQ(scan_json()["views"][0]["rig_time_s"]["compute"], 8.75 - 1.5 - 2.9375);
}

TEST_F(ScanSequencerTest, WithTheMapAtTheRigsPoseALateRegistrationFailsTheScanAtItsDeadline) {
  register_after_s_ = std::numeric_limits<double>::infinity();  // never answers
  ScanSettings s = test_settings("pbnbv", 3);
  s.map_pose = MapPose::kRig;
  start(s);
  run();
  ASSERT_TRUE(seq_->finished());
  EXPECT_EQ(seq_->exit_code(), 1);
  // The cloud came at 3: its registration is waited for 60 s while view 2 is planned and moved to.
  EXPECT_EQ(now_, 63.0);
  const json scan = scan_json();
  EXPECT_EQ(scan["status"]["message"].get<std::string>().rfind(
                "the registration service sent no REGISTERED_CLOUD for view 1 in 60 s (the capture request sent ", 0),
            0u)
      << scan["status"]["message"];
  // View 1 is recorded as it is (mapped, not registered); view 2 was not captured.
  ASSERT_EQ(scan["views"].size(), 1u);
  EXPECT_FALSE(scan["views"][0].contains("registration"));
  EXPECT_TRUE(scan["views"][0]["map"]["updated"]);
  EXPECT_EQ(scan["status"]["views_done"], 0);
  EXPECT_TRUE(times_of(captures_, 1).empty());
  // Its capture request was sent again about every second meanwhile (the same id).
  const std::vector<double> resent = times_of(captures_, 0);
  EXPECT_GE(resent.size(), 58u);
  for (const auto& [t, r] : captures_) EXPECT_EQ(r.request_id, captures_.front().second.request_id);
}

TEST_F(ScanSequencerTest, APlannerStopEndsTheScanDoneWithItsReason) {
  scorer = [](const PlanRequest& r) {
    ViewPlan p = make_plan(r, Pose::Identity(), {});
    p.outcome = PlanOutcome::kStop;
    p.reason = "no frontier ellipsoid remains";
    return p;
  };
  start(test_settings("pbnbv", 5));
  run();
  ASSERT_TRUE(seq_->finished());
  EXPECT_EQ(seq_->exit_code(), 0);
  EXPECT_EQ(plans_.size(), 1u);
  const json scan = scan_json();
  EXPECT_EQ(scan["status"]["state"], "done");
  EXPECT_EQ(scan["status"]["message"], "scan complete: no frontier ellipsoid remains");
  EXPECT_EQ(scan["status"]["views_done"], 1);
  EXPECT_EQ(scan["stop"], json({{"reason", "no frontier ellipsoid remains"}, {"after_views", 1}, {"rule", "planner"}}));
  EXPECT_EQ(scan["planning_stopped"]["outcome"], "stop");
  EXPECT_EQ(scan["planning_stopped"]["map_of_view"], 1);
  EXPECT_EQ(scan["views"].size(), 1u);
  // The rig waited from the cloud's frame (3.0 - 0.0625 s) through the map and the plan that said
  // stop (answered at 4.25 s): the scan no longer uses the rig from there.
  EXPECT_EQ(scan["views"][0]["rig_time_s"]["compute"], 1.3125);
  EXPECT_EQ(scan["rig_time_s"]["total"], 0.75 + 0.5 + 0.9375 + 1.3125);
  EXPECT_EQ(seq_->summary().rfind("scan complete: no frontier ellipsoid remains: 1 of 5 views, 10 points", 0), 0u)
      << seq_->summary();
}

TEST_F(ScanSequencerTest, WithTheMapAtTheRigsPoseAPlannerStopWaitsForTheViewsRegistration) {
  scorer = [](const PlanRequest& r) {
    ViewPlan p = make_plan(r, Pose::Identity(), {});
    p.outcome = PlanOutcome::kStop;
    p.reason = "no frontier ellipsoid remains";
    return p;
  };
  register_after_s_ = 3.0;
  ScanSettings s = test_settings("pbnbv", 5);
  s.map_pose = MapPose::kRig;
  start(s);
  run();
  ASSERT_TRUE(seq_->finished());
  EXPECT_EQ(seq_->exit_code(), 0);
  // The plan (asked for at 3.25, answered at 3.75) said stop before view 1's registration (6):
  // the scan ends done once view 1 is recorded, its mesh made from it.
  const json scan = scan_json();
  EXPECT_EQ(scan["status"]["message"], "scan complete: no frontier ellipsoid remains");
  EXPECT_EQ(scan["stop"], json({{"reason", "no frontier ellipsoid remains"}, {"after_views", 1}, {"rule", "planner"}}));
  ASSERT_EQ(scan["views"].size(), 1u);
  EXPECT_TRUE(scan["views"][0].contains("registration"));
  EXPECT_EQ(scan["status"]["views_done"], 1);
  ASSERT_EQ(meshes_.size(), 1u);
  EXPECT_EQ(meshes_[0].first, 6.0);
  EXPECT_EQ(meshes_[0].second.views, (std::vector<int>{0}));
  // The rig waited from the frame (2.9375) until the scan no longer needed it (6).
  EXPECT_EQ(scan["views"][0]["rig_time_s"]["compute"], 6.0 - 2.9375);
}

TEST_F(ScanSequencerTest, TheSurfaceRuleStopsWhenTheLastViewsAddNothingNew) {
  // Every view after the first sees the first view's ten points again (within 5 mm of the model):
  // views 2 and 3 add 0 % new surface, so a window of 2 from view 3 on stops after view 3 of 6.
  camera = [base = camera](const CaptureRequest& r) {
    std::optional<CaptureResult> c = base(r);
    c->points = view_points(0);
    if (r.iteration > 0) {
      for (auto& p : c->points) p.z() += 0.003f;  // 3 mm off: not new
    }
    return c;
  };
  ScanSettings s = test_settings("pbnbv", 6);
  s.surface_rule.window = 2;
  s.surface_rule.max_new_percent = 0.5;
  s.surface_rule.min_views = 3;
  start(s);
  run();
  ASSERT_TRUE(seq_->finished());
  EXPECT_EQ(seq_->exit_code(), 0);
  const json scan = scan_json();
  EXPECT_EQ(scan["status"]["views_done"], 3);
  EXPECT_EQ(scan["stop"]["rule"], "surface");
  EXPECT_EQ(scan["stop"]["after_views"], 3);
  EXPECT_EQ(scan["stop"]["reason"], "views 2-3 each added less than 0.50 % new surface (0.00, 0.00 % of the model)");
  EXPECT_EQ(scan["stop"]["figures"]["window"], 2);
  EXPECT_EQ(scan["stop"]["figures"]["percent_of_model_by_view"], json({100.0, 0.0, 0.0}));
  EXPECT_EQ(scan["views"][0]["new_surface"]["new_points"], 10);
  EXPECT_EQ(scan["views"][1]["new_surface"]["model_points"], 10);
  EXPECT_EQ(scan["views"][1]["new_surface"]["new_points"], 0);

}

TEST_F(ScanSequencerTest, WithTheStopRuleOffViewsThatAddNothingStillUseTheBudget) {
  camera = [base = camera](const CaptureRequest& r) {
    std::optional<CaptureResult> c = base(r);
    c->points = view_points(0);
    return c;
  };
  ScanSettings s = test_settings("pbnbv", 6);
  s.stop_rule = StopRule::kOff;
  start(s);
  run();
  const json scan = scan_json();
  EXPECT_EQ(scan["status"]["views_done"], 6);
  EXPECT_EQ(scan["stop"]["rule"], "budget");
  EXPECT_EQ(scan["views"][5]["new_surface"]["percent_of_model"], 0.0);
}

TEST_F(ScanSequencerTest, AReplayMovesToTheRecordedViewsAndRecordsItsOwnPlans) {
  // Recorded: view 1 at A; view 2 at B after B0 was unreachable; view 3 at C. This scan's planner
  // chooses P for view 2 and stops at view 3; the replay moves to the recorded views anyway.
  const Pose a = view_from(0.9, 0, 0.3), b0 = view_from(0, 0.9, 0.9), b = view_from(0, 0.9, 0.3),
             c = view_from(-0.9, 0, 0.3), p = view_from(0.5, 0.5, 0.5);
  recorded_ = std::vector<std::vector<Pose>>{{a}, {b0, b}, {c}};
  motion = [inner = motion, b0](const MoveRequest& r) {
    std::optional<MoveResult> m = inner(r);
    if (r.object_T_camera.isApprox(b0)) m->status = MoveStatus::kUnreachable;
    return m;
  };
  scorer = [p](const PlanRequest& r) {
    ViewPlan plan = make_plan(r, p, {view_from(0.6, 0.4, 0.5)});
    if (r.iteration == 2) {
      plan.outcome = PlanOutcome::kStop;
      plan.reason = "no frontier ellipsoid remains";
    }
    return plan;
  };
  start(test_settings("pbnbv", 10));
  run();
  ASSERT_TRUE(seq_->finished());
  EXPECT_EQ(seq_->exit_code(), 0);
  ASSERT_EQ(moves_.size(), 4u);
  EXPECT_TRUE(moves_of(0).at(0).object_T_camera.isApprox(a));
  ASSERT_EQ(moves_of(1).size(), 2u);
  EXPECT_TRUE(moves_of(1)[0].object_T_camera.isApprox(b0));
  EXPECT_TRUE(moves_of(1)[1].object_T_camera.isApprox(b));
  EXPECT_TRUE(moves_of(2).at(0).object_T_camera.isApprox(c));
  EXPECT_EQ(plans_.size(), 2u);
  // The unreachable recorded pose is excluded from the next plan, as in the recording.
  ASSERT_EQ(plans_[1].second.excluded.size(), 1u);
  EXPECT_TRUE(plans_[1].second.excluded[0].isApprox(b0));
  const json scan = scan_json();
  EXPECT_EQ(scan["replay_of"], "recorded/scan.json");
  EXPECT_EQ(scan["status"]["state"], "done");
  EXPECT_EQ(scan["status"]["views_planned"], 3);
  EXPECT_EQ(scan["stop"]["rule"], "replay");
  ASSERT_EQ(scan["views"].size(), 3u);
  EXPECT_TRUE(pose_from_json(scan["views"][1]["plan"]["object_T_camera"], "plan").isApprox(p));
  EXPECT_EQ(scan["views"][1]["option"], 1);
  EXPECT_EQ(scan["views"][2]["plan"]["outcome"], "stop");
  EXPECT_FALSE(scan["views"][2]["plan"].contains("object_T_camera"));
  EXPECT_TRUE(pose_from_json(scan["views"][2]["requested_object_T_camera"], "view 3").isApprox(c));
}

TEST_F(ScanSequencerTest, AFailedPlanFailsTheScan) {
  scorer = [](const PlanRequest& r) {
    ViewPlan p = make_plan(r, Pose::Identity(), {});
    p.outcome = PlanOutcome::kFailed;
    p.reason = "no reachable candidate";
    return p;
  };
  start(test_settings("raycast", 3));
  run();
  EXPECT_EQ(seq_->exit_code(), 1);
  const json scan = scan_json();
  EXPECT_EQ(scan["status"]["message"], "no plan for view 2: no reachable candidate");
  EXPECT_EQ(scan["stop"]["rule"], "planner failed");
}

TEST_F(ScanSequencerTest, ARejectedRegistrationIsNotMergedAndItsViewIsExcludedFromTheNextPlan) {
  registration = [inner = registration](const CaptureResult& c) {
    std::optional<RegisteredCloud> r = inner(c);
    if (c.iteration == 1) {
      r->accepted = false;
      r->reason = "overlap 0.05 below 0.3";
    }
    return r;
  };
  start(test_settings("pbnbv", 3));
  run();
  ASSERT_EQ(seq_->exit_code(), 0);
  const json scan = scan_json();
  const json& v1 = scan["views"][1];
  EXPECT_EQ(v1["registration"]["accepted"], false);
  EXPECT_EQ(v1["map"]["updated"], false);
  EXPECT_EQ(v1["merged"], false);
  EXPECT_EQ(read_ply((dir_ / "frames" / "view_002.ply").string()).size(), 10u);  // kept in frames/
  EXPECT_EQ(read_ply((dir_ / "cloud.ply").string()).size(), 20u);               // views 0 and 2 only
  EXPECT_EQ(scan["status"]["num_points"], 20);
  EXPECT_EQ(scan["status"]["views_done"], 3);
  // The plan for view 2: only view 0 mapped, view 1's reached pose excluded, planned from the
  // latest map (view 1's answer, unchanged).
  ASSERT_EQ(plans_.size(), 2u);
  const PlanRequest& next = plans_[1].second;
  ASSERT_EQ(next.views_done.size(), 1u);
  ASSERT_EQ(next.excluded.size(), 1u);
  EXPECT_TRUE(next.excluded[0].isApprox(moves_of(1).back().object_T_camera));
  EXPECT_EQ(next.map_iteration, 1);
  // At the end: views 0 and 2 mapped, view 1 excluded.
  EXPECT_EQ(seq_->so_far().views_taken.size(), 2u);
  EXPECT_EQ(seq_->so_far().excluded.size(), 1u);
  EXPECT_EQ(seq_->so_far().last_map, 2);
  EXPECT_EQ(seq_->so_far().views_done, 3);
  EXPECT_NE(std::find(lines_.begin(), lines_.end(),
                      "[view 2/3] done: 10 points, 10 in the model; not merged, 5 frontier voxels; "
                      "move 1.50 s, capture 0.75 s, register 0.25 s, map 2.00 ms, plan 122.00 ms"),
            lines_.end());
}

TEST_F(ScanSequencerTest, AFailedCaptureExcludesTheViewAndTheScanGoesOn) {
  fail_capture(0, "no DEPTH_FRAME for trigger 3 after 3 tries");
  start(test_settings("ring", 2));
  run();
  ASSERT_EQ(seq_->exit_code(), 0);
  const json scan = scan_json();
  EXPECT_EQ(scan["status"]["views_done"], 1);
  ASSERT_EQ(scan["views"].size(), 2u);
  EXPECT_EQ(scan["views"][0]["capture"]["status"], "failed");
  EXPECT_FALSE(scan["views"][0].contains("frame_file"));
  EXPECT_EQ(scan["views"][1]["merged"], true);
}

// A REGISTERED_CLOUD or a VOXEL_MAP lost on the bus: the capture request is sent again (same id),
// the camera's repeated CLOUD makes the registration and the mapping service answer again, and the
// view completes 3 s later instead of failing at the 60 s deadline.
TEST_F(ScanSequencerTest, ALostRegisteredCloudOrMapIsAskedForAgainThroughTheCaptureRequest) {
  int registered = 0, mapped = 0;
  registration = [&, inner = registration](const CaptureResult& c) -> std::optional<RegisteredCloud> {
    if (++registered == 1) return std::nullopt;  // the first answer is lost
    return inner(c);
  };
  mapping = [&, inner = mapping](const RegisteredCloud& r) -> std::optional<VoxelMapSummary> {
    if (++mapped == 1) return std::nullopt;  // and the first map of the view too
    return inner(r);
  };
  start(test_settings("ring", 2));
  run();
  ASSERT_EQ(seq_->exit_code(), 0) << scan_json()["status"].dump();
  EXPECT_EQ(scan_json()["views"].size(), 2u);
  EXPECT_EQ(scan_json()["status"]["views_done"], 2);
  // View 1: capture sent at 0 s; its re-sends (every second) bring the registration, then the map.
  ASSERT_GE(captures_.size(), 3u);
  EXPECT_EQ(captures_[1].second.request_id, captures_[0].second.request_id);
  EXPECT_EQ(captures_[2].second.request_id, captures_[0].second.request_id);
  EXPECT_LT(now_, 20.0);  // not a 60 s deadline
}

// A plan that does not come (a lost map, a restarted fitter or scorer): with the plan request, the
// last view's capture request is sent again, so that its map and ellipsoids are published again.
TEST_F(ScanSequencerTest, ALatePlanSendsTheLastViewsCaptureRequestAgain) {
  int asked = 0;
  scorer = [&, inner = scorer](const PlanRequest& r) -> std::optional<ViewPlan> {
    if (++asked == 1) return std::nullopt;  // the first plan request goes unanswered
    return inner(r);
  };
  start(test_settings("pbnbv", 2));
  run();
  ASSERT_EQ(seq_->exit_code(), 0) << scan_json()["status"].dump();
  ASSERT_EQ(plans_.size(), 2u);
  const double resent_at = plans_[1].first;
  int repeats = 0;
  for (const auto& [t, c] : captures_) repeats += t == resent_at && c.iteration == 0 ? 1 : 0;
  std::string seen;
  for (const auto& [t, c] : captures_) seen += " " + std::to_string(t) + ":" + std::to_string(c.iteration);
  EXPECT_EQ(repeats, 1) << "the first view's capture request, with the plan request at " << resent_at << " s; captures at" << seen;
}

TEST_F(ScanSequencerTest, ALostCaptureIsAskedForAgainEverySecondWithTheSameId) {
  int asked = 0;
  camera = [&, inner = camera](const CaptureRequest& r) -> std::optional<CaptureResult> {
    if (++asked < 3) return std::nullopt;
    return inner(r);
  };
  start(test_settings("ring", 1));
  run();
  ASSERT_EQ(seq_->exit_code(), 0);
  ASSERT_EQ(captures_.size(), 3u);
  EXPECT_EQ(captures_[1].first - captures_[0].first, 1.0);
  EXPECT_EQ(captures_[2].first - captures_[0].first, 2.0);
  EXPECT_EQ(captures_[2].second.request_id, captures_[0].second.request_id);
}

TEST_F(ScanSequencerTest, TheStartupDeadlineNamesWhatWasNotHeard) {
  ScanSettings s = test_settings("ring", 2);
  s.startup_timeout_s = 5;
  start(s, false);
  deliver(Heard{"ARM_STATUS"});
  for (const char* w : {"heartbeat of motion", "heartbeat of camera", "heartbeat of registration"}) deliver(Heard{w});
  run();
  EXPECT_EQ(seq_->exit_code(), 1);
  EXPECT_EQ(now_, 5.25);
  EXPECT_TRUE(moves_.empty());
  EXPECT_EQ(scan_json()["status"]["message"], "not ready after 5.00 s: no TURNTABLE_STATUS, heartbeat of mapping");
}

TEST_F(ScanSequencerTest, StoppingEndsTheScanStoppedWithoutTheViewInProgress) {
  start(test_settings("ring", 3));
  run(5.0);  // view 1 done at 3.75 s; view 2 moving
  seq_->stop(now_);
  collect();
  EXPECT_EQ(seq_->exit_code(), 130);
  const json scan = scan_json();
  EXPECT_EQ(scan["status"]["state"], "stopped");
  EXPECT_EQ(scan["status"]["message"], "stopped by the user");
  EXPECT_EQ(scan["views"].size(), 1u);
  EXPECT_EQ(statuses_.back().state, ScanState::kStopped);
}

TEST_F(ScanSequencerTest, AnswersOfAnotherScanOrAnOldRequestAreIgnored) {
  motion = [](const MoveRequest&) -> std::optional<MoveResult> { return std::nullopt; };
  start(test_settings("ring", 1));
  const MoveRequest asked = moves_.at(0).second;
  MoveResult foreign;
  foreign.scan_id = "another-scan";
  foreign.request_id = asked.request_id;
  foreign.status = MoveStatus::kUnreachable;
  deliver(foreign);
  MoveResult stale = foreign;
  stale.scan_id = "unit-scan";
  stale.request_id = asked.request_id + 1000;
  deliver(stale);
  run(10);
  EXPECT_FALSE(seq_->finished());
  EXPECT_FALSE(std::filesystem::exists(dir_ / "scan.json")) << "nothing recorded yet";
}

// A map and ellipsoids of view 1 for another request (a cloud forged with a guessed request id that
// a mapping service took, or an earlier capture of the view), the map before the real one and the
// ellipsoids after, are not the view's: the view records the real map, the plan of view 2 asks for the map of view 1's capture
// request and is recorded with the real ellipsoids. (Before, the first map of the view's iteration
// was taken, and the last ellipsoids.)
TEST_F(ScanSequencerTest, AMapOrEllipsoidsOfAnotherRequestForTheViewAreNotItsAnswers) {
  mapping = [&, inner = mapping](const RegisteredCloud& r) -> std::optional<VoxelMapSummary> {
    std::optional<VoxelMapSummary> real = inner(r);
    if (r.iteration == 0) {
      VoxelMapSummary forged = *real;
      forged.request_id = r.request_id + 7;
      forged.num_frontier = 999;
      later(1.6, forged);  // before the real map (1.75 s)
      EllipsoidSetSummary e = ellipsoids(0, r.request_id + 7);
      e.fit_s = 9.0;
      later(2.1, e);  // after the real ellipsoids (2.0 s), before the plan (2.25 s)
    }
    return real;
  };
  start(test_settings("pbnbv", 2));
  run();
  ASSERT_EQ(seq_->exit_code(), 0);
  ASSERT_EQ(plans_.size(), 1u);
  EXPECT_EQ(plans_[0].second.map_iteration, 0);
  EXPECT_EQ(plans_[0].second.map_request_id, captures_.at(0).second.request_id);
  const json scan = scan_json();
  EXPECT_EQ(scan["views"][0]["map"]["voxels"]["frontier"], 5);
  EXPECT_NEAR(scan["views"][1]["plan"]["time_ms"]["ellipsoid_fit"].get<double>(), 20.0, 1e-12);
}

// Request ids start at a random number per scan (2^32 or more), so a sender that has not seen the
// scan's requests cannot answer one: a forged "stop" for every id from 0 to 60 (the ids a scan
// used to start from) ends nothing, and the scan completes its views.
TEST_F(ScanSequencerTest, RequestIdsStartAtARandomNumberSoForgedAnswersToSmallIdsEndNothing) {
  std::set<int64_t> firsts;
  for (int k = 0; k < 4; ++k) firsts.insert(first_request_id());
  EXPECT_EQ(firsts.size(), 4u) << "four scans, four different first ids";
  for (const int64_t f : firsts) EXPECT_GE(f, int64_t{1} << 32);

  // While each plan is awaited, 61 forged stops arrive before the scorer's answer.
  scorer = [&](const PlanRequest& r) -> std::optional<ViewPlan> {
    for (int64_t id = 0; id <= 60; ++id) {
      ViewPlan stop;
      stop.scan_id = "unit-scan";
      stop.iteration = r.iteration;
      stop.request_id = id;
      stop.planner = PlannerKind::kPbnbv;
      stop.outcome = PlanOutcome::kStop;
      stop.reason = "forged";
      later(0.1, stop);
    }
    return make_plan(r, view_from(0.1, 0.7, 0.3 + 0.01 * r.iteration), {});
  };
  start(test_settings("pbnbv", 3));
  run();
  ASSERT_EQ(seq_->exit_code(), 0);
  const json scan = scan_json();
  EXPECT_EQ(scan["status"]["views_done"], 3);
  EXPECT_EQ(scan["status"]["state"], "done");
  for (const auto& [t, r] : plans_) EXPECT_GE(r.request_id, int64_t{1} << 32);
}

// An answer with the outstanding request's id is still refused when a field is not what was
// asked: another view, another planner, more alternatives than asked for, a pose that is not a
// rigid transform, a candidate count above N. Each is counted (scan.json "answers_refused") and
// logged, none is acted on; the scorer's own answer then plans the view.
TEST_F(ScanSequencerTest, AnAnswerWhoseFieldsAreNotWhatWasAskedIsRefusedCountedAndNotActedOn) {
  ScanSettings s = test_settings("pbnbv", 2);
  s.alternatives = 3;
  const Pose real = view_from(0.1, 0.7, 0.31);
  scorer = [&](const PlanRequest& r) -> std::optional<ViewPlan> {
    const ViewPlan good = make_plan(r, real, {});
    ViewPlan wrong_view = make_plan(r, view_from(0.9, 0.1, 0.2), {});
    wrong_view.iteration = r.iteration + 5;
    ViewPlan wrong_planner = wrong_view;
    wrong_planner.iteration = r.iteration;
    wrong_planner.planner = PlannerKind::kRandom;
    ViewPlan too_many = make_plan(r, view_from(0.9, 0.1, 0.2), std::vector<Pose>(4, real));
    ViewPlan sheared = make_plan(r, view_from(0.9, 0.1, 0.2), {});
    sheared.object_T_camera.matrix()(0, 1) += 0.5;
    ViewPlan counted = make_plan(r, view_from(0.9, 0.1, 0.2), {});
    counted.num_scored = 100000;
    ViewPlan stop = good;  // a well-formed stop of another view
    stop.outcome = PlanOutcome::kStop;
    stop.iteration = r.iteration - 1;
    double t = 0.1;
    for (const ViewPlan& bad : {wrong_view, wrong_planner, too_many, sheared, counted, stop}) later(t += 0.05, bad);
    return good;  // at 0.5 s, after the six
  };
  start(s);
  run();
  ASSERT_EQ(seq_->exit_code(), 0);
  const json scan = scan_json();
  EXPECT_EQ(scan["status"]["views_done"], 2);
  EXPECT_EQ(scan["status"]["answers_refused"], 6) << "six refused for view 2";
  ASSERT_EQ(moves_of(1).size(), 1u);
  EXPECT_TRUE(moves_of(1)[0].object_T_camera.isApprox(real, 1e-12)) << "the scorer's own plan was moved to";
  int logged = 0;
  for (const std::string& l : lines_) logged += l.find("refused a VIEW_PLAN") != std::string::npos;
  EXPECT_EQ(logged, 6);
}

TEST_F(ScanSequencerTest, StatusIsRepeatedEverySecondWhileWaiting) {
  motion = [](const MoveRequest&) -> std::optional<MoveResult> { return std::nullopt; };
  start(test_settings("ring", 1));
  statuses_.clear();
  run(10);
  EXPECT_EQ(statuses_.size(), 10u);  // at 1, 2, ..., 10 s
  EXPECT_EQ(statuses_.back().elapsed_s, 10.0);
  EXPECT_EQ(statuses_.back().state, ScanState::kMoving);
}

}  // namespace

namespace {

// A scan stopped after two views (the launcher killed, the machine rebooted) and resumed from its
// folder by a new sequencer: it goes on with view 3, plans it from the two views taken, never
// reuses a request id, keeps the first plan's quality for the stop rule, and ends with the same
// record as one that was never interrupted (three views, the merged cloud of all three).
TEST_F(ScanSequencerTest, AStoppedScanResumesFromItsFolderWithTheNextView) {
  const ScanSettings s = test_settings("pbnbv", 3);
  start(s);
  const auto views = [&] { return std::filesystem::exists(dir_ / "scan.json") ? scan_json()["views"].size() : 0u; };
  while (!seq_->finished() && views() < 2) run(now_ + 0.25);
  ASSERT_EQ(scan_json()["views"].size(), 2u);
  seq_->stop(now_, "stopped: the launcher died");
  const json stopped = scan_json();
  ASSERT_EQ(stopped["status"]["state"], "stopped");
  // F of the first plan, which the stop rule compares against (scan.json keeps it).
  const double first_quality = stopped["views"][1]["plan"]["first_quality_px"].get<double>();
  ASSERT_TRUE(std::isfinite(first_quality));
  int64_t max_id = 0;
  for (const auto& [t, r] : moves_) max_id = std::max(max_id, r.request_id);
  for (const auto& [t, r] : captures_) max_id = std::max(max_id, r.request_id);
  for (const auto& [t, r] : plans_) max_id = std::max(max_id, r.request_id);
  const std::size_t plans_before = plans_.size(), moves_before = moves_.size();
  due_.clear();  // the old processes are gone with their answers

  seq_ = std::make_unique<ScanSequencer>(s, dir_);
  seq_->resume(now_);
  collect();
  for (const char* w : {"ARM_STATUS", "TURNTABLE_STATUS", "heartbeat of motion", "heartbeat of camera",
                        "heartbeat of registration", "heartbeat of mapping", "heartbeat of scorer",
                        "heartbeat of ellipsoids"}) {
    deliver(Heard{w});
  }
  run();
  ASSERT_EQ(seq_->exit_code(), 0) << scan_json()["status"].dump();
  const json done = scan_json();
  EXPECT_EQ(done["status"]["state"], "done");
  EXPECT_EQ(done["status"]["views_done"], 3);
  ASSERT_EQ(done["views"].size(), 3u);
  EXPECT_EQ(done["views"][2]["view"], 3);
  // The new plan: for view 3 (iteration 2), from the two views taken, with the first quality.
  ASSERT_GT(plans_.size(), plans_before);
  const PlanRequest& p = plans_[plans_before].second;
  EXPECT_EQ(p.iteration, 2);
  EXPECT_EQ(p.views_done.size(), 2u);
  EXPECT_EQ(p.map_iteration, 1);
  EXPECT_EQ(p.first_quality, first_quality);
  // Every request after the resume has an id above every id before it.
  for (std::size_t k = moves_before; k < moves_.size(); ++k) EXPECT_GT(moves_[k].second.request_id, max_id);
  EXPECT_GT(p.request_id, max_id);
  EXPECT_GT(done["status"]["elapsed_s"].get<double>(), stopped["status"]["elapsed_s"].get<double>());
}

// The rig's drivers silent for 40 s (longer than a move's deadline): the scan pauses at the view
// with the rig still, asks again at every re-send, and goes on when they are back; no view is
// lost or excluded.
TEST_F(ScanSequencerTest, ASilentRigPausesTheScanUntilItIsBack) {
  motion = [&, inner = motion](const MoveRequest& r) -> std::optional<MoveResult> {
    std::optional<MoveResult> m = inner(r);
    if (now_ < 40.0 && r.iteration == 1) {
      m->status = MoveStatus::kRigSilent;
      m->reason = "no recent ARM_STATUS/TURNTABLE_STATUS from the rig";
    }
    return m;
  };
  ScanSettings s = test_settings("ring", 3);
  s.move_timeout_s = 20;  // the view's move deadline would be 35 s
  start(s);
  run();
  ASSERT_EQ(seq_->exit_code(), 0) << scan_json()["status"].dump();
  EXPECT_EQ(scan_json()["status"]["views_done"], 3);
  EXPECT_FALSE(scan_json()["views"][1].contains("failed_moves"));
  EXPECT_GT(now_, 40.0);
  bool paused = false, resumed = false;
  for (const std::string& l : lines_) {
    paused = paused || l.find("paused: no recent ARM_STATUS") != std::string::npos;
    resumed = resumed || l.find("resumed: the rig is back") != std::string::npos;
  }
  EXPECT_TRUE(paused);
  EXPECT_TRUE(resumed);
}

TEST_F(ScanSequencerTest, ResumingAFolderWithoutThisScanIsNamed) {
  const ScanSettings s = test_settings("ring", 2);
  ScanSequencer seq(s, dir_ / "empty");
  EXPECT_NE(pbnbv::testing::error_message([&] { seq.resume(0.0); }).find("cannot resume: " + (dir_ / "empty" / "scan.json").string() +
                                                           " does not exist"),
            std::string::npos);
}

// A planted scan.json cannot push the resumed scan's numbers past what they hold: a view beyond
// the scan's view count, a request id near int64's end (the next id would overflow), a view
// that is a real number and an elapsed time that is not a duration are refused, naming the
// file and the entry.
TEST_F(ScanSequencerTest, ResumingRefusesNumbersOutOfTheirRange) {
  const ScanSettings s = test_settings("pbnbv", 3);
  start(s);
  const auto views = [&] { return std::filesystem::exists(dir_ / "scan.json") ? scan_json()["views"].size() : 0u; };
  while (!seq_->finished() && views() < 2) run(now_ + 0.25);
  seq_->stop(now_, "stopped: the launcher died");
  const json good = scan_json();
  const std::string file = (dir_ / "scan.json").string();
  struct Case {
    std::function<void(json&)> plant;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {[](json& j) { j["views"][1]["view"] = 2147483647; }, "views[1] view = 2147483647 is not a whole number in 1..1000"},
      {[](json& j) { j["views"][0]["view"] = 0.5; }, "views[0] view = 0.5 is not a whole number in 1..1000"},
      // Views count from 1 (format 2): a 0 is refused, naming the field and the range.
      {[](json& j) { j["views"][0]["view"] = 0; }, "views[0] view = 0 is not a whole number in 1..1000"},
      {[](json& j) { j["views"][1]["plan"]["map_of_view"] = 1001; }, "map_of_view = 1001 is not a whole number in 0..1000"},
      {[](json& j) {
         j["views"][1]["view"] = 6;  // within what a scan may have, beyond this one's (its files renamed too)
         j["views"][1]["frame_file"] = "frames/view_006.ply";
         j["views"][1]["depth_file"] = "depth/view_006.png";
       },
       "view 6 is beyond the scan's 3 views"},
      {[](json& j) { j["views"][1]["capture"]["request_id"] = 9223372036854775807LL; },
       "view 2 capture request_id = 9223372036854775807 is not a whole number in 0..4611686018427387904"},
      {[](json& j) { j["status"]["next_request_id"] = -5; }, "status next_request_id = -5 is not a whole number"},
      {[](json& j) { j["status"]["elapsed_s"] = -1.0; }, "status elapsed_s = -1.000000 is not a duration"},
  };
  for (const Case& c : cases) {
    json planted = good;
    c.plant(planted);
    write_json_atomic(planted, file);
    ScanSequencer again(s, dir_);
    const std::string what = pbnbv::testing::error_message([&] { again.resume(now_); });
    EXPECT_NE(what.find(file), std::string::npos) << what;
    EXPECT_NE(what.find(c.expected), std::string::npos) << what;
  }
}

}  // namespace

namespace {

// Two JSON documents equal, numbers within a relative 1e-12 (a field written in mm or degrees
// from m or rad comes back through the inverse unit).
void expect_same_json(const json& a, const json& b, const std::string& at = "scan.json") {
  if (a.is_number() && b.is_number()) {
    const double x = a.get<double>(), y = b.get<double>();
    EXPECT_LE(std::abs(x - y), 1e-12 * std::max(1.0, std::abs(x))) << at << ": " << x << " != " << y;
    return;
  }
  ASSERT_EQ(a.type_name(), std::string(b.type_name())) << at;
  if (a.is_object()) {
    for (auto it = a.begin(); it != a.end(); ++it) {
      ASSERT_TRUE(b.contains(it.key())) << at << "." << it.key() << " is not read back";
      expect_same_json(it.value(), b[it.key()], at + "." + it.key());
    }
    for (auto it = b.begin(); it != b.end(); ++it) EXPECT_TRUE(a.contains(it.key())) << at << "." << it.key() << " added";
  } else if (a.is_array()) {
    ASSERT_EQ(a.size(), b.size()) << at;
    for (std::size_t i = 0; i < a.size(); ++i) expect_same_json(a[i], b[i], at + "[" + std::to_string(i) + "]");
  } else {
    EXPECT_EQ(a, b) << at;
  }
}

// scan.json read back into its types and written again is the file as it was, every section of
// every kind of view: planned (with ellipsoids), a view the rig could not reach first, a rejected
// registration, a failed capture, the stop, the mesh, the status.
TEST_F(ScanSequencerTest, TheRecordReadsBackIntoItsTypesAndWritesTheSameFile) {
  const Pose below = view_from(0.0, 0.0, -0.7);
  scorer = [&](const PlanRequest& r) { return make_plan(r, r.iteration == 1 ? below : view_from(0, 0.7, 0.3), {view_from(0.7, 0, 0.3)}); };
  unreachable_below();
  registration = [inner = registration](const CaptureResult& c) {
    std::optional<RegisteredCloud> r = inner(c);
    if (c.iteration == 2) {
      r->accepted = false;
      r->reason = "rejected: overlap 0.1";
    }
    return r;
  };
  fail_capture(3, "no DEPTH_FRAME for trigger 12 after 3 tries");
  start(test_settings("pbnbv", 5));
  run();
  ASSERT_EQ(seq_->exit_code(), 0);
  const json written = scan_json();
  const RecordedScan r = read_scan_record(dir_);
  ASSERT_EQ(r.views.size(), 5u);
  EXPECT_TRUE(r.views[0].initial_view);
  ASSERT_TRUE(r.views[1].plan.has_value());
  EXPECT_EQ(r.views[1].failed_moves.size(), 1u);
  EXPECT_FALSE(r.views[2].registration->accepted);
  EXPECT_FALSE(r.views[3].capture->ok);
  EXPECT_EQ(r.views[4].capture_points, 10u);
  ASSERT_TRUE(r.mesh.has_value());
  EXPECT_EQ(r.status.state, "done");
  expect_same_json(written, to_json(r));
  // What a replay moves to: each view's failed moves, then the option it reached.
  const std::vector<std::vector<Pose>> attempts = recorded_attempts(r);
  ASSERT_EQ(attempts.size(), 5u);
  ASSERT_EQ(attempts[1].size(), 2u);
  EXPECT_TRUE(attempts[1][0].isApprox(below));
  EXPECT_TRUE(attempts[1][1].isApprox(view_from(0.7, 0, 0.3)));
  EXPECT_EQ(attempts[2].size(), 1u);
  // The merged views' frames, for a mesh: views 0, 1 and 4 (2 rejected, 3 not captured).
  const std::vector<MergedFrame> merged = merged_frames(r, dir_);
  ASSERT_EQ(merged.size(), 3u);
  EXPECT_EQ(merged[2].view, 4);
  EXPECT_EQ(merged[2].file, dir_ / "frames" / "view_005.ply");

  // A planted frame file is refused naming the file and the view, before anything opens it.
  json planted = written;
  planted["views"][1]["frame_file"] = "../../../etc/passwd";
  write_json_atomic(planted, (dir_ / "scan.json").string());
  pbnbv::testing::expect_error([&] { read_scan_record(dir_); }, "scan.json views[1] view 2: frame_file is not frames/view_002.ply");
  // A field of the wrong type is named with its view and section.
  planted = written;
  planted["views"][0]["move"]["position_error_m"] = "far";
  write_json_atomic(planted, (dir_ / "scan.json").string());
  pbnbv::testing::expect_error([&] { read_scan_record(dir_); }, "views[0] view 1 move position_error_m is not a number");
}

}  // namespace
