// pbnbv-coordinator: the scan coordinator.
//   in:  MOVE_RESULT, CLOUD, REGISTERED_CLOUD, VOXEL_MAP, ELLIPSOIDS, VIEW_PLAN, MESH_RESULT,
//        ARM_STATUS, TURNTABLE_STATUS, HEARTBEAT
//   out: MOVE_REQUEST, CAPTURE_REQUEST, PLAN_REQUEST, MESH_REQUEST, SCAN_STATUS, HEARTBEAT
// Wires the bus to the scan's sequence (core/scan/scan_sequencer.hpp: plan -> move -> capture ->
// register -> map for each view, the mesh at the end, its deadlines and re-sends) and writes
// scan.json, the one file it owns (the frames, cloud.ply, the depth images and the mesh are the
// registration service's, maps/ the mapping service's, plans/ the view scorer's):
// converts what arrives, feeds it and the clock to the sequencer, publishes what it asks for and
// prints its progress. Messages of another scan are ignored. With --replay-of it replays a
// recorded scan (`pbnbv replay`): the recorded views, with this scan's plans recorded beside them.
// Exit code: 0 scan done, 1 failed, 130 stopped by SIGINT/SIGTERM (scan.json then says "stopped"),
// 2 bad options.
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>
#include <optional>
#include <iostream>
#include <variant>
#include <vector>

#include "bus/bus.hpp"
#include "bus/convert_rig.hpp"
#include "bus/convert_scan.hpp"
#include "cli/options.hpp"
#include "core/base/atomic_file.hpp"
#include "core/base/log.hpp"
#include "core/io/json.hpp"
#include "core/scan/scan_record.hpp"
#include "core/scan/scan_sequencer.hpp"
#include "core/scan/scan_settings.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/heartbeat_t.hpp"
#include "pbnbv/stop_request_t.hpp"
#include "pbnbv/turntable_status_t.hpp"

using namespace pbnbv;
namespace fs = std::filesystem;

namespace {

// Whether the process that started this one has died: this process was handed to another parent,
// or the launcher is a zombie or gone. Asked when a stop signal arrives, which may be the death
// signal of a launcher killed outright (PR_SET_PDEATHSIG); looks for up to 0.3 s, so that it does
// not depend on when the kernel hands this process on.
bool launcher_died(pid_t launcher) {
  for (int i = 0; i < 30; ++i) {
    if (::getppid() != launcher) return true;
    std::ifstream stat("/proc/" + std::to_string(launcher) + "/stat");
    std::string pid, name, state;
    if (!(stat >> pid >> name >> state) || state == "Z" || state == "X") return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

constexpr int kSpinMs = 20;  // longest wait for a message before the sequencer's tick
constexpr double kStopLingerS = 0.3;  // after STOP, before the scan's processes are stopped
// A full disk under --out ends the scan "failed" before a file is left half written: below this
// many free bytes the scan stops taking views, and the reserve (state/coordinator.reserve) is
// freed for scan.json's last words. (A view writes a few MB: frames, depth image, map files, log.)
constexpr int64_t kMinFreeBytes = int64_t{8} << 20;
constexpr std::size_t kReserveBytes = std::size_t{1} << 20;
constexpr double kFreeSpaceCheckS = 0.5;

// Prints a progress line: on a terminal one line per view (each stage overwrites the last),
// otherwise (logs, pipes) every stage on its own line.
void print_progress(const ProgressLine& p) {
  static const bool tty = ::isatty(STDOUT_FILENO) != 0;
  if (tty) {
    std::cout << "\r\033[K" << p.text << (p.ends_view ? "\n" : "") << std::flush;
  } else {
    std::cout << p.text << std::endl;
  }
}

// Publishes a request or status of the sequencer, stamped now.
template <class Plain>
void publish(bus::Bus& bus, const char* channel, const Plain& plain) {
  auto m = bus::to_msg(plain);
  m.utime = bus::now_utime();
  bus.publish(channel, m);
}

// Publishes the sequencer's requests and status and prints its lines, in order.
void send(bus::Bus& bus, const std::vector<ScanOutput>& outputs) {
  for (const ScanOutput& out : outputs) {
    if (const auto* r = std::get_if<MoveRequest>(&out)) {
      publish(bus, channels::kMoveRequest, *r);
    } else if (const auto* r = std::get_if<CaptureRequest>(&out)) {
      publish(bus, channels::kCaptureRequest, *r);
    } else if (const auto* r = std::get_if<PlanRequest>(&out)) {
      publish(bus, channels::kPlanRequest, *r);
    } else if (const auto* r = std::get_if<MeshRequest>(&out)) {
      publish(bus, channels::kMeshRequest, *r);
    } else if (const auto* s = std::get_if<ScanStatus>(&out)) {
      publish(bus, channels::kScanStatus, *s);
      bus.set_scan(s->scan_id, s->iteration);  // for the heartbeat
    } else if (const auto* p = std::get_if<ProgressLine>(&out)) {
      print_progress(*p);
    }
  }
}

// Subscribes to an answer channel: messages of the scan are checked and converted (a bad one is
// rejected by the bus, named) and queued for the sequencer; the bus ignores and counts those of
// another scan.
template <class Msg>
void take(bus::Bus& bus, const char* channel, std::vector<ScanEvent>& inbox) {
  bus.subscribe<Msg>(channel, [&inbox](const Msg& m) { inbox.emplace_back(bus::from_msg(m)); });
}

// Runs the scan to its end; returns the process exit code.
int run(bus::Bus& bus, const ScanSettings& settings, const fs::path& out, bool resume, const std::string& replay_of) {
  ScanSequencer scan(settings, out);
  if (!replay_of.empty()) scan.replay(recorded_attempts(read_scan_record(replay_of)), replay_of);
  bus.serve_scan(settings.scan_id);
  // Handlers only check and convert (a bad message is rejected by the bus); the sequencer
  // takes the events after each spin, so its own errors are not mistaken for bad messages.
  std::vector<ScanEvent> inbox;
  take<move_result_t>(bus, channels::kMoveResult, inbox);
  take<point_cloud_t>(bus, channels::kCloud, inbox);
  take<registered_cloud_t>(bus, channels::kRegisteredCloud, inbox);
  take<voxel_set_t>(bus, channels::kVoxelMap, inbox);
  take<ellipsoid_set_t>(bus, channels::kEllipsoids, inbox);
  take<view_plan_t>(bus, channels::kViewPlan, inbox);
  take<mesh_result_t>(bus, channels::kMeshResult, inbox);
  bus.subscribe<arm_status_t>(channels::kArmStatus, [&](const arm_status_t&) { inbox.emplace_back(Heard{"ARM_STATUS"}); });
  bus.subscribe<turntable_status_t>(channels::kTurntableStatus,
                                    [&](const turntable_status_t&) { inbox.emplace_back(Heard{"TURNTABLE_STATUS"}); });
  std::optional<std::string> stop_reason;  // STOP heard (the motion executor holds the rig)
  bus.subscribe<stop_request_t>(channels::kStop, [&](const stop_request_t& s) { stop_reason = s.reason; });
  bus.subscribe<heartbeat_t>(channels::kHeartbeat,
                             [&](const heartbeat_t& h) { inbox.emplace_back(Heard{"heartbeat of " + h.service}); });

  const pid_t parent = ::getppid();
  fs::create_directories(out / "state");
  SpaceReserve reserve((out / "state" / "coordinator.reserve").string(), kReserveBytes);
  // Ends the scan "failed" naming why (a write that failed, the disk full): scan.json is written
  // with the space the reserve held.
  auto fail_scan = [&](const std::string& why) {
    reserve.release();
    try {
      scan.abort(bus::now_s(), "failed: " + why);
    } catch (const std::exception& e) {
      log_error("cannot record that the scan failed (" + why + "): " + e.what());
    }
  };
  double next_space_check_s = 0;
  try {
    if (resume) {
      scan.resume(bus::now_s());
    } else {
      scan.start(bus::now_s());
    }
    while (!scan.finished()) {
      if (bus::now_s() >= next_space_check_s) {
        next_space_check_s = bus::now_s() + kFreeSpaceCheckS;
        const int64_t free = free_bytes(out.string());
        if (free >= 0 && free < kMinFreeBytes) {
          fail_scan("no space left on device under " + out.string() + " (" + std::to_string(free / 1024) +
                    " kB free; a view needs a few MB): free some and resume it (pbnbv scan --resume " + out.string() + ")");
          break;
        }
      }
      send(bus, scan.take_outputs());
      if (stop_requested()) {
        // SIGTERM from the kernel when the launcher died (PR_SET_PDEATHSIG): say so.
        const bool orphaned = launcher_died(parent);
        scan.stop(bus::now_s(), orphaned ? "stopped: the launcher (pid " + std::to_string(parent) + ") died"
                                         : "stopped by the user");
        break;
      }
      bus.spin_once(kSpinMs);
      if (stop_reason) {
        // The motion executor holds the rig; stay on the bus a moment so the log records it still.
        scan.stop(bus::now_s(), *stop_reason + " (STOP)");
        for (const double end = bus::now_s() + kStopLingerS; bus::now_s() < end;) bus.spin_once(kSpinMs);
        break;
      }
      for (const ScanEvent& e : inbox) scan.handle(e, bus::now_s());
      inbox.clear();
      scan.tick(bus::now_s());
    }
  } catch (const std::exception& e) {
    // A write of the record failed (a full disk, a folder gone read-only): say so in scan.json.
    log_error(e.what());
    fail_scan(e.what());
  }
  send(bus, scan.take_outputs());
  if (::isatty(STDOUT_FILENO)) std::cout << "\r\033[K";  // clear an unfinished progress line
  std::cout << scan.summary() << std::endl;
  return scan.exit_code();
}

}  // namespace

int main(int argc, char** argv) {
  set_log_name("coordinator");
  CLI::App app{"pbnbv-coordinator: runs one scan view by view (plan, move, capture, register, map) and writes "
               "its record",
               "pbnbv-coordinator"};
  cli::init(app);
  std::string out, settings_path;
  cli::add_text(app, "out", &out, "the scan's folder (its scan.json)", "DIR")->required();
  cli::add_text(app, "settings", &settings_path, "the scan's settings [DIR/settings.json]", "PATH");
  bool resume = false;
  cli::add_flag(app, "resume", &resume, "continue the scan recorded in DIR (scan.json, cloud.ply) with its next view");
  std::string replay_of;
  cli::add_text(app, "replay-of", &replay_of,
                "replay the scan recorded in this scan.json: move to its views (the plans are recorded, not followed)",
                "PATH");
  if (const std::optional<int> code = cli::parse(app, argc, argv, std::cout, std::cerr)) return *code;
  install_stop_handlers();
  try {
    if (settings_path.empty()) settings_path = (fs::path(out) / "settings.json").string();
    const ScanSettings settings = scan_settings_from_json(read_json(settings_path));
    bus::Bus bus("coordinator");
    return run(bus, settings, out, resume, replay_of);
  } catch (const std::exception& e) {
    log_error(e.what());
    return 2;
  }
}
