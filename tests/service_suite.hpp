#pragma once
// A suite of real service processes started once per test executable, on the bus of the
// executable's private network namespace (the test runs under scripts/netns-run), and a listener
// that records what they publish. Shared by the integration tests that talk to services
// directly: bad_input_test, registration_service_test, planning_services_test.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "core/mapping/voxel_map.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/base/pose.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/capture_request_t.hpp"
#include "pbnbv/ellipsoid_set_t.hpp"
#include "pbnbv/heartbeat_t.hpp"
#include "pbnbv/mesh_request_t.hpp"
#include "pbnbv/mesh_result_t.hpp"
#include "pbnbv/move_request_t.hpp"
#include "pbnbv/move_result_t.hpp"
#include "pbnbv/plan_request_t.hpp"
#include "pbnbv/point_cloud_t.hpp"
#include "pbnbv/registered_cloud_t.hpp"
#include "pbnbv/view_plan_t.hpp"
#include "pbnbv/voxel_set_t.hpp"
#include "bus/message_guard.hpp"
#include "process/processes.hpp"
#include "test_util.hpp"

namespace pbnbv::testing {

constexpr double kObjectZ = 0.15;  // a 0.3 m sphere resting on the turntable

// Records the services' heartbeats and answers.
class Listener {
 public:
  Listener() : lcm_("udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608") {
    lcm_.subscribe("HEARTBEAT", &Listener::on_raw<heartbeat_t, &Listener::on_heartbeat>, this);
    lcm_.subscribe("MOVE_RESULT", &Listener::on_raw<move_result_t, &Listener::on_move>, this);
    lcm_.subscribe("CLOUD", &Listener::on_raw<point_cloud_t, &Listener::on_cloud>, this);
    lcm_.subscribe("ARM_STATUS", &Listener::on_raw<arm_status_t, &Listener::on_arm>, this);
    lcm_.subscribe("REGISTERED_CLOUD", &Listener::on_raw<registered_cloud_t, &Listener::on_registered>, this);
    lcm_.subscribe("VOXEL_MAP", &Listener::on_raw<voxel_set_t, &Listener::on_map>, this);
    lcm_.subscribe("ELLIPSOIDS", &Listener::on_raw<ellipsoid_set_t, &Listener::on_ellipsoids>, this);
    lcm_.subscribe("VIEW_PLAN", &Listener::on_raw<view_plan_t, &Listener::on_plan>, this);
    lcm_.subscribe("MESH_RESULT", &Listener::on_raw<mesh_result_t, &Listener::on_mesh>, this);
  }
  lcm::LCM& lcm() { return lcm_; }
  // Handles messages until `done` or the timeout; returns done().
  bool spin_until(const std::function<bool()>& done, double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < end) {
      if (done()) return true;
      lcm_.handleTimeout(20);
    }
    return done();
  }
  std::map<std::string, heartbeat_t> heartbeats;
  std::map<int64_t, move_result_t> moves;
  std::map<int64_t, point_cloud_t> clouds;
  arm_status_t arm;
  bool have_arm = false;
  std::map<std::pair<std::string, int64_t>, registered_cloud_t> registered;
  std::map<std::pair<std::string, int32_t>, voxel_set_t> maps;
  std::map<std::pair<std::string, int32_t>, ellipsoid_set_t> ellipsoids;
  std::map<std::pair<std::string, int64_t>, view_plan_t> plans;
  int plan_answers = 0;
  std::map<std::pair<std::string, int64_t>, mesh_result_t> meshes;

 private:
  // Messages pass the message guard before they are decoded, as a service's do (the suites send
  // hostile bytes on these channels too).
  template <class T, void (Listener::*keep)(const T&)>
  void on_raw(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    T m;
    if (bus::decode_checked(channel, rbuf->data, rbuf->data_size, &m)) (this->*keep)(m);
  }
  void on_heartbeat(const heartbeat_t& m) { heartbeats[m.service] = m; }
  void on_move(const move_result_t& m) { moves[m.request_id] = m; }
  void on_cloud(const point_cloud_t& m) { clouds[m.request_id] = m; }
  void on_arm(const arm_status_t& m) { arm = m; have_arm = true; }
  void on_registered(const registered_cloud_t& m) {
    registered[{m.scan_id, m.request_id}] = m;
  }
  void on_map(const voxel_set_t& m) { maps[{m.scan_id, m.iteration}] = m; }
  void on_ellipsoids(const ellipsoid_set_t& m) {
    ellipsoids[{m.scan_id, m.iteration}] = m;
  }
  void on_plan(const view_plan_t& m) {
    plans[{m.scan_id, m.request_id}] = m;
    ++plan_answers;
  }
  void on_mesh(const mesh_result_t& m) { meshes[{m.scan_id, m.request_id}] = m; }
  lcm::LCM lcm_;
};

// Requests as the services' tests send them: scan "bad-input", the suite's sphere.
inline move_request_t move_request(int64_t id, const Pose& object_T_camera) {
  move_request_t r{};
  r.utime = 0;
  r.scan_id = "bad-input";
  r.iteration = 0;
  r.request_id = id;
  double p[3], q[4];
  pose_to_arrays(object_T_camera, p, q);
  std::copy(p, p + 3, r.object_T_camera.position_m);
  std::copy(q, q + 4, r.object_T_camera.quat_wxyz);
  r.object_z_m = kObjectZ;
  for (int k = 0; k < 3; ++k) {
    r.keepout_min_m[k] = -0.17;
    r.keepout_max_m[k] = 0.17;
  }
  r.keepout_min_m[2] = -0.15;
  r.speed_scale = 1.0;
  r.timeout_s = 60;
  r.plan_only = false;
  return r;
}

inline capture_request_t capture_request(int64_t id) {
  capture_request_t r;
  r.utime = 0;
  r.scan_id = "bad-input";
  r.iteration = 0;
  r.request_id = id;
  r.not_before_utime = 0;
  r.object_z_m = kObjectZ;
  for (int k = 0; k < 3; ++k) {
    r.crop_min_m[k] = -0.3;
    r.crop_max_m[k] = 0.3;
  }
  r.ground_clearance_m = 0.004;
  r.voxel_m = 0.002;
  r.timeout_s = 10;
  return r;
}

template <class T>
void publish_truncated(lcm::LCM& lcm, const std::string& channel, const T& msg) {
  std::vector<uint8_t> buf(msg.getEncodedSize());
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  lcm.publish(channel, buf.data(), static_cast<unsigned>(buf.size() / 2));
}


// A process suite: the services given, started once for the executable and stopped at its end.
class ServiceSuite : public ::testing::Test {
 protected:
  struct Service {
    std::string name;  // as its heartbeat names it
    std::vector<std::string> argv;
  };

  // Starts the services (logs in a fresh folder `name`) and waits up to 60 s for a heartbeat of
  // each (and for ARM_STATUS when the twin is one of them).
  static void start_suite(const std::string& name, const std::vector<Service>& services) {
    dir_ = fresh_dir(name);
    bool twin = false;
    for (const auto& s : services) {
      process::Child c;
      c.name = s.name;
      c.argv = s.argv;
      c.log_path = (dir_ / (s.name + ".log")).string();
      children_.push_back(c);
      twin = twin || s.name == "twin";
    }
    for (auto& c : children_) process::start(c);
    listener_ = new Listener();
    ASSERT_TRUE(listener_->spin_until([&] {
      for (const auto& s : services) {
        if (!listener_->heartbeats.count(s.name)) return false;
      }
      return !twin || listener_->have_arm;
    }, 60)) << "services did not start; logs in " << dir_.string();
  }

  // Stops them; each must exit cleanly.
  static void stop_suite() {
    process::stop_all(children_, 5.0);
    for (const auto& c : children_) {
      EXPECT_EQ(c.exit_code, 0) << c.name << " did not exit cleanly:\n" << process::tail_lines(c.log_path, 20);
    }
    children_.clear();
    delete listener_;
    listener_ = nullptr;
  }

  static bool all_running() {
    process::reap(children_);
    for (const auto& c : children_) if (!c.running) return false;
    return true;
  }

  static int64_t rejected(const std::string& service) {
    auto it = listener_->heartbeats.find(service);
    return it == listener_->heartbeats.end() ? -1 : it->second.messages_rejected;
  }

  // Waits for fresh heartbeats (published at 1 Hz) that count at least `n` rejections.
  static bool rejections_reach(const std::string& service, int64_t n) {
    return listener_->spin_until([&] { return rejected(service) >= n; }, 5.0);
  }

  inline static std::filesystem::path dir_;
  inline static std::vector<process::Child> children_;
  inline static Listener* listener_ = nullptr;
};

// Planning inputs. A VOXEL_MAP of a 0.3 m object at 0.03 m: an occupied ball on the turntable and, on its +y
// side, a slab of frontier voxels (the unexplored side).
inline voxel_set_t synthetic_map(const std::string& scan_id, int iteration) {
  voxel_set_t m{};
  m.scan_id = scan_id;
  m.iteration = iteration;
  m.updated = true;
  m.message = "synthetic";
  m.resolution_m = 0.03;
  for (int k = 0; k < 3; ++k) {
    m.bbox_min_m[k] = -0.21;
    m.bbox_max_m[k] = 0.21;
  }
  for (int i = -4; i <= 4; ++i)
    for (int j = -4; j <= 4; ++j)
      for (int k = -4; k <= 4; ++k) {
        const Eigen::Vector3f c(0.03f * i, 0.03f * j, 0.03f * k);
        if (c.norm() <= 0.12f && c.norm() > 0.08f) m.occupied_centres_m.push_back({c.x(), c.y(), c.z()});
        if (j == 5 - 1 && std::abs(i) <= 3 && std::abs(k) <= 3) m.frontier_centres_m.push_back({c.x(), 0.18f, c.z()});
      }
  m.num_occupied = static_cast<int32_t>(m.occupied_centres_m.size());
  m.num_frontier = static_cast<int32_t>(m.frontier_centres_m.size());
  // The cells as the mapping service sends them (ray casting and pbnbv's combined ranking read
  // them): the ball's shell Occupied, the slab Frontier, the ball's inside Unknown, the rest Empty.
  for (int k = 0; k < 3; ++k) m.dims[k] = 14;  // 0.42 m / 0.03 m
  m.cells.assign(14 * 14 * 14, static_cast<int8_t>(VoxelState::kEmpty));
  auto cell = [&](float x, float y, float z) -> int8_t& {
    auto i = [&](float v) { return std::clamp(static_cast<int>((v + 0.21f) / 0.03f), 0, 13); };
    return m.cells[i(x) + 14 * (i(y) + 14 * i(z))];
  };
  for (int i = -4; i <= 4; ++i)
    for (int j = -4; j <= 4; ++j)
      for (int k = -4; k <= 4; ++k) {
        if (Eigen::Vector3f(0.03f * i, 0.03f * j, 0.03f * k).norm() <= 0.08f) {
          cell(0.03f * i, 0.03f * j, 0.03f * k) = static_cast<int8_t>(VoxelState::kUnknown);
        }
      }
  for (const auto& c : m.occupied_centres_m) cell(c[0], c[1], c[2]) = static_cast<int8_t>(VoxelState::kOccupied);
  for (const auto& c : m.frontier_centres_m) cell(c[0], c[1], c[2]) = static_cast<int8_t>(VoxelState::kFrontier);
  m.num_cells = static_cast<int32_t>(m.cells.size());
  return m;
}

inline plan_request_t plan_request(const std::string& scan_id, int64_t id, int map_iteration) {
  plan_request_t r{};
  r.scan_id = scan_id;
  r.iteration = 1;
  r.request_id = id;
  r.planner = plan_request_t::kPlannerPbnbv;
  r.map_iteration = map_iteration;
  r.num_views_done = 0;
  r.num_excluded = 0;
  r.num_candidates = 800;
  r.num_parallels = 24;
  r.num_sectors = 1;
  r.full_sphere = false;
  r.working_distance_m = 0.6;
  r.num_alternatives = 3;
  r.stop_fraction = 0;
  r.first_quality = std::nan("");
  r.width_px = 1280;
  r.height_px = 720;
  r.fx = r.fy = 696;
  r.cx = 640;
  r.cy = 360;
  r.depth_min_m = 0.1;
  r.depth_max_m = 3.0;
  r.check_reachability = true;
  r.object_z_m = kObjectZ;
  for (int k = 0; k < 3; ++k) {
    r.keepout_min_m[k] = -0.17;
    r.keepout_max_m[k] = 0.17;
  }
  r.keepout_min_m[2] = -0.15;
  return r;
}

}  // namespace pbnbv::testing
