// pbnbv-test-hostile: hostile traffic on the bus a scan runs on, for the faults test
// (Faults.HostileTrafficFromView2TakesNothingOver). It listens for SCAN_STATUS to learn the
// scan's id (as any process on the host can), waits until the scan reaches view --from-view, and
// from then until the scan ends (or --deadline s) sends, every 100 ms:
//   - garbage: random bytes of random length (1..2000) on every pipeline and rig channel but
//     SCAN_STATUS (which it reads itself);
//   - oversized counts: a depth frame, a cloud and a voxel map of the scan whose array count says
//     2^31 - 1 elements in a message of about 100 bytes, and a zlib "frame" declaring 8192 x 8192;
//   - forged answers of the scan, well formed: VIEW_PLAN "stop", MOVE_RESULT "unreachable" and a
//     failed CLOUD for request ids 0..60 and 10 random ones, a VOXEL_MAP and ELLIPSOIDS of view
//     2^31 - 1, a PLAN_REQUEST for view 5000 (no file path can be sent: the contract has none).
// While it runs it reads VmHWM (peak resident memory) of every process in OUT/processes.json once
// a second and prints the largest seen for each when it ends, with what it sent.
//   pbnbv-test-hostile --out OUT [--from-view 2] [--deadline 600]
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/ellipsoid_set_t.hpp"
#include "pbnbv/move_result_t.hpp"
#include "pbnbv/plan_request_t.hpp"
#include "pbnbv/point_cloud_t.hpp"
#include "pbnbv/scan_status_t.hpp"
#include "pbnbv/view_plan_t.hpp"
#include "pbnbv/voxel_set_t.hpp"

namespace {

using Bytes = std::vector<uint8_t>;

template <class T>
Bytes encode(const T& m) {
  Bytes b(m.getEncodedSize());
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

// The encoding of `small` with its variable array's count (the first bytes that differ from
// `larger`, which has one element more) set to 2^31 - 1 and cut 64 bytes after the count.
Bytes inflated(const Bytes& small, const Bytes& larger) {
  std::size_t at = 0;
  while (at < small.size() && small[at] == larger[at]) ++at;
  // The count is a big-endian int32 that grew by one: its low byte differs; it starts 3 before.
  const std::size_t count_at = at - 3;
  Bytes out(small.begin(), small.begin() + std::min(small.size(), count_at + 4 + 64));
  out[count_at] = 0x7f;
  out[count_at + 1] = out[count_at + 2] = out[count_at + 3] = 0xff;
  return out;
}

pbnbv::pose_t identity_pose() {
  pbnbv::pose_t p{};
  p.quat_wxyz[0] = 1;
  return p;
}

struct Status {
  std::string scan_id;
  int iteration = -1;
  int8_t state = -1;
};

// Peak resident memory (VmHWM) of `pid` in kB, or -1 when it cannot be read.
long peak_rss_kb(long pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  }
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  std::string out;
  int from_view = 2;
  double deadline_s = 600;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--out") out = argv[i + 1];
    else if (a == "--from-view") from_view = std::stoi(argv[i + 1]);
    else if (a == "--deadline") deadline_s = std::stod(argv[i + 1]);
  }
  if (out.empty()) {
    std::cerr << "usage: pbnbv-test-hostile --out OUT [--from-view N] [--deadline S]\n";
    return 2;
  }
  lcm::LCM bus;
  if (!bus.good()) {
    std::cerr << "pbnbv-test-hostile: no LCM\n";
    return 2;
  }
  Status status;
  bus.subscribeFunction<pbnbv::scan_status_t, Status*>(
      "SCAN_STATUS",
      [](const lcm::ReceiveBuffer*, const std::string&, const pbnbv::scan_status_t* m, Status* s) {
        s->scan_id = m->scan_id;
        s->iteration = m->iteration;
        s->state = m->state;
      },
      &status);

  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  auto finished = [&] {
    return status.state == pbnbv::scan_status_t::kDone || status.state == pbnbv::scan_status_t::kFailed ||
           status.state == pbnbv::scan_status_t::kStopped;
  };
  while (elapsed() < deadline_s && (status.iteration < from_view - 1 || status.scan_id.empty()) && !finished()) {
    bus.handleTimeout(100);
  }
  if (finished() || status.scan_id.empty()) {
    std::cerr << "pbnbv-test-hostile: the scan ended or was never heard before view " << from_view << "\n";
    return 1;
  }
  const std::string scan = status.scan_id;
  std::cout << "hostile traffic for scan " << scan << " from view " << status.iteration + 1 << std::endl;

  std::mt19937_64 rng(20261204);
  const std::vector<std::string> channels = {"ARM_STATUS",  "TURNTABLE_STATUS", "DEPTH_FRAME",      "MOVE_REQUEST",
                                             "MOVE_RESULT", "CAPTURE_REQUEST",  "CLOUD",            "REGISTERED_CLOUD",
                                             "VOXEL_MAP",   "ELLIPSOIDS",       "PLAN_REQUEST",     "VIEW_PLAN",
                                             "HEARTBEAT",   "DEPTH_TRIGGER",    "ARM_COMMAND"};

  // Oversized counts, each about 100 bytes.
  pbnbv::depth_frame_t frame{};
  frame.scan_id = scan;
  frame.width = 640;
  frame.height = 480;
  frame.fx = frame.fy = 500;
  frame.cx = 320;
  frame.cy = 240;
  frame.depth_min_m = 0.1;
  frame.depth_max_m = 3;
  frame.depth_unit_m = 1e-4;
  frame.encoding = pbnbv::depth_frame_t::kEncodingRaw;
  frame.num_bytes = 1;
  frame.depth = {0};
  pbnbv::depth_frame_t frame2 = frame;
  frame2.num_bytes = 2;
  frame2.depth = {0, 0};
  const Bytes big_frame = inflated(encode(frame), encode(frame2));
  pbnbv::point_cloud_t cloud{};
  cloud.scan_id = scan;
  cloud.frame = "object";
  cloud.object_T_camera = identity_pose();
  cloud.num_points = 1;
  cloud.points_m = {{0, 0, 0}};
  pbnbv::point_cloud_t cloud2 = cloud;
  cloud2.num_points = 2;
  cloud2.points_m = {{0, 0, 0}, {0, 0, 0}};
  const Bytes big_cloud = inflated(encode(cloud), encode(cloud2));
  pbnbv::voxel_set_t map{};
  map.scan_id = scan;
  map.iteration = 2147483647;
  map.resolution_m = 0.03;
  for (int k = 0; k < 3; ++k) {
    map.bbox_min_m[k] = -0.1;
    map.bbox_max_m[k] = 0.1;
    map.dims[k] = 1;
  }
  map.num_cells = 1;
  map.cells = {1};
  pbnbv::voxel_set_t map2 = map;
  map2.num_cells = 2;
  map2.cells = {1, 1};
  const Bytes big_map = inflated(encode(map), encode(map2));
  // A zlib "frame" declaring 8192 x 8192 (the bytes are not even zlib).
  pbnbv::depth_frame_t bomb = frame;
  bomb.width = bomb.height = 8192;
  bomb.encoding = pbnbv::depth_frame_t::kEncodingZlib;
  bomb.num_bytes = 64;
  bomb.depth.assign(64, 0x78);

  long sent = 0, rounds = 0;
  std::map<std::string, long> peak_kb;
  double next_sample_s = 0;
  while (elapsed() < deadline_s && !finished()) {
    ++rounds;
    // Garbage on every channel.
    for (const std::string& c : channels) {
      Bytes junk(1 + rng() % 2000);
      for (auto& b : junk) b = static_cast<uint8_t>(rng());
      bus.publish(c, junk.data(), static_cast<unsigned>(junk.size()));
      ++sent;
    }
    bus.publish("DEPTH_FRAME", big_frame.data(), static_cast<unsigned>(big_frame.size()));
    bus.publish("CLOUD", big_cloud.data(), static_cast<unsigned>(big_cloud.size()));
    bus.publish("VOXEL_MAP", big_map.data(), static_cast<unsigned>(big_map.size()));
    bus.publish("DEPTH_FRAME", &bomb);
    sent += 4;
    // Forged answers of the scan for the view it is on.
    std::vector<int64_t> ids;
    for (int64_t id = 0; id <= 60; ++id) ids.push_back(id);
    for (int k = 0; k < 10; ++k) ids.push_back(static_cast<int64_t>(rng() >> 2));
    for (const int64_t id : ids) {
      pbnbv::view_plan_t stop{};
      stop.scan_id = scan;
      stop.iteration = status.iteration;
      stop.request_id = id;
      stop.planner = pbnbv::plan_request_t::kPlannerPbnbv;
      stop.outcome = pbnbv::view_plan_t::kStop;
      stop.reason = "forged";
      stop.ranking = pbnbv::view_plan_t::kRankingF;
      stop.object_T_camera = identity_pose();
      bus.publish("VIEW_PLAN", &stop);
      pbnbv::move_result_t move{};
      move.scan_id = scan;
      move.iteration = status.iteration;
      move.request_id = id;
      move.status = pbnbv::move_result_t::kUnreachable;
      move.reason = "forged";
      move.requested_object_T_camera = move.reached_object_T_camera = identity_pose();
      bus.publish("MOVE_RESULT", &move);
      pbnbv::point_cloud_t failed = cloud;
      failed.iteration = status.iteration;
      failed.request_id = id;
      failed.status = pbnbv::point_cloud_t::kFailed;
      failed.message = "forged";
      failed.num_points = 0;
      failed.points_m.clear();
      bus.publish("CLOUD", &failed);
      sent += 3;
    }
    pbnbv::voxel_set_t late_map = map;
    bus.publish("VOXEL_MAP", &late_map);
    pbnbv::ellipsoid_set_t late_ellipsoids{};
    late_ellipsoids.scan_id = scan;
    late_ellipsoids.iteration = 2147483647;
    bus.publish("ELLIPSOIDS", &late_ellipsoids);
    pbnbv::plan_request_t far{};
    far.scan_id = scan;
    far.iteration = 5000;
    far.request_id = static_cast<int64_t>(rng() >> 2);
    far.planner = pbnbv::plan_request_t::kPlannerPbnbv;
    bus.publish("PLAN_REQUEST", &far);
    sent += 3;

    if (elapsed() >= next_sample_s) {
      next_sample_s = elapsed() + 1.0;
      try {
        std::ifstream in(out + "/processes.json");
        const nlohmann::json procs = nlohmann::json::parse(in);
        long& launcher = peak_kb["launcher"];
        launcher = std::max(launcher, peak_rss_kb(procs.at("launcher_pid").get<long>()));
        for (const auto& p : procs.at("processes")) {
          const long kb = peak_rss_kb(p.at("pid").get<long>());
          long& peak = peak_kb[p.at("name").get<std::string>()];
          peak = std::max(peak, kb);
        }
      } catch (const std::exception&) {
        // processes.json being replaced: the next second reads it
      }
    }
    // Answers to the SCAN_STATUS, for 100 ms.
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(100);
    while (std::chrono::steady_clock::now() < until) bus.handleTimeout(20);
  }
  std::cout << "sent " << sent << " hostile messages in " << rounds << " rounds until the scan's state "
            << static_cast<int>(status.state) << " at view " << status.iteration + 1 << "\n";
  std::cout << "peak RSS (VmHWM, MB):";
  for (const auto& [name, kb] : peak_kb) std::cout << " " << name << " " << kb / 1024.0;
  std::cout << std::endl;
  return 0;
}
