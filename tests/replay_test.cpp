// `pbnbv replay`: a scan recorded with the twin, run through the pipeline again from its log with
// pbnbv-replay-rig in the twin's place, must make the same decisions in every view (the same views
// accepted, the same registered poses, the same voxel counts, the same planned next view within
// 1e-6 m and 1e-6 rad); replayed with another planner, the plans differ while the frames, poses and
// maps stay the same. A folder that cannot be replayed is named before anything starts.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/scan/scan_file.hpp"
#include "core/scan/scan_record.hpp"
#include "core/io/json.hpp"
#include "core/scan/scan_settings.hpp"
#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;
using nlohmann::json;

namespace {

// A 3-view PB-NBV scan of a 0.2 m bunny on the arm rig at 320 x 180 (small images, the same
// geometry), recorded at the default rig speed (4x: 800 statuses/s, which lcm-logger keeps up with
// on a loaded machine; at 20x it lost some), then its replay (extra options: `replay_options`).
// Both in private network namespaces.
struct Replayed {
  fs::path original, replay;
  json comparison, replay_scan;
};

fs::path record(const std::string& name) {
  const fs::path out = fresh_dir(name) / "original";
  const std::string cmd = netns_run() + " " + bin_dir() +
                          "/pbnbv scan --object bunny --size 0.2 --rig arm --views 3 " + kSmallImageOptions + " --out " + out.string();
  const CommandResult r = run_command(cmd);
  EXPECT_EQ(r.exit_code, 0) << cmd << "\n" << r.output;
  return out;
}

// `exit_code`: what pbnbv replay must exit with (1: the replayed scan failed); its processes are
// checked to have exited 0 only when it succeeded.
Replayed replay(const fs::path& original, const std::string& name, const std::string& replay_options, int exit_code = 0) {
  Replayed s;
  s.original = original;
  s.replay = original.parent_path() / name;
  const std::string cmd =
      netns_run() + " " + bin_dir() + "/pbnbv replay " + original.string() + " --out " + s.replay.string() + replay_options;
  const CommandResult r = run_command(cmd);
  EXPECT_EQ(r.exit_code, exit_code) << cmd << "\n" << r.output;
  std::cout << r.output.substr(r.output.find("\nview ") == std::string::npos ? 0 : r.output.find("\nview "));
  s.comparison = read_json((s.replay / "replay.json").string());
  s.replay_scan = read_json((s.replay / "scan.json").string());
  if (exit_code != 0) return s;
  for (const auto& p : read_json((s.replay / "processes.json").string())["processes"]) {
    EXPECT_EQ(p["exit_code"], 0) << p.dump();
  }
  return s;
}

// An LCM log of `events` (channel, message) at `path`.
template <class... Msg>
void write_log(const fs::path& path, const std::pair<std::string, Msg>&... events) {
  lcm::LogFile log(path.string(), "w");
  int64_t n = 0;
  const auto put = [&](const std::string& channel, const auto& msg) {
    std::vector<uint8_t> bytes(msg.getEncodedSize());
    msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    lcm::LogEvent e;
    e.eventnum = n++;
    e.timestamp = 1000 * n;
    e.channel = channel;
    e.datalen = static_cast<int32_t>(bytes.size());
    e.data = bytes.data();
    log.writeEvent(&e);
  };
  (put(events.first, events.second), ...);
}

// A folder with a scan's settings.json and scan.json (no views) for scan `id`.
fs::path scan_folder(const std::string& name, const std::string& id) {
  const fs::path dir = fresh_dir(name);
  ScanSettings s;
  s.scan_id = id;
  s.object_name = "bunny";
  s.normalisation.extent_m = Eigen::Vector3d::Constant(0.2);
  write_json_atomic(to_json(s), (dir / "settings.json").string());
  RecordedScan record;  // a scan stopped before its first view, written through its types
  record.pbnbv_version = "test";
  record.settings = s;
  record.status.state = "stopped";
  write_json_atomic(to_json(record), (dir / "scan.json").string());
  return dir;
}

std::string replay_error(const fs::path& dir) {
  const CommandResult r = run_command(bin_dir() + "/pbnbv replay " + dir.string() + " --out " + (dir / "replay").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_FALSE(fs::exists(dir / "replay")) << "nothing is started for a folder that cannot be replayed";
  return r.output;
}

}  // namespace

TEST(Replay, ARecordedScanReplayedMakesTheSameDecisions) {
  const fs::path original = record("replay");
  const Replayed s = replay(original, "replay", "");
  const json recorded = read_json((original / "scan.json").string());
  ASSERT_EQ(recorded["views"].size(), 3u);
  EXPECT_EQ(s.replay_scan["status"]["state"], "done");
  EXPECT_EQ(s.replay_scan["stop"]["rule"], "replay");
  EXPECT_EQ(s.replay_scan["replay_of"], (original / "scan.json").string());
  ASSERT_EQ(s.replay_scan["views"].size(), 3u);
  // A recording whose log lost the readings at an exposure cannot be replayed exactly (docs/replay.md,
  // "Replay"): this one must be complete.
  EXPECT_EQ(s.comparison["readings_lost_in_recording"], json::array());
  EXPECT_TRUE(s.comparison["same_decisions"].get<bool>())
      << s.comparison["differences"].dump(2) << "\nviews whose readings the recording lost: "
      << s.comparison["readings_lost_in_recording"].dump();
  ASSERT_EQ(s.comparison["views"].size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const json& v = s.comparison["views"][i];
    const json& a = recorded["views"][i];
    const json& b = s.replay_scan["views"][i];
    EXPECT_EQ(a["registration"]["accepted"], b["registration"]["accepted"]) << "view " << i + 1;
    EXPECT_EQ(a["map"]["voxels"], b["map"]["voxels"]) << "view " << i + 1;
    EXPECT_GT(b["map"]["voxels"]["occupied"].get<int>(), 0);
    // The frame the replay used is the recording's, seen from the same pose.
    EXPECT_EQ(a["capture"]["depth_frame_seq"], b["capture"]["depth_frame_seq"]) << "view " << i + 1;
    EXPECT_LE(v["registered_pose"]["position_m"].get<double>(), 1e-6) << "view " << i + 1;
    if (i == 0) continue;  // the initial view is not planned
    EXPECT_EQ(b["plan"]["outcome"], "view");
    EXPECT_LE(v["plan"]["position_m"].get<double>(), 1e-6) << "view " << i + 1 << " planned elsewhere";
    EXPECT_LE(v["plan"]["angle_deg"].get<double>(), 1e-6 * 180 / M_PI) << "view " << i + 1;
  }

  // Another planner on the same frames: its plans differ (a random candidate), the recorded views
  // and therefore the maps do not.
  const Replayed r = replay(original, "replay-random", " --planner random");
  EXPECT_EQ(r.replay_scan["settings"]["planner"], "random");
  EXPECT_EQ(r.comparison["planner"], json({{"original", "pbnbv"}, {"replay", "random"}}));
  EXPECT_FALSE(r.comparison["same_decisions"].get<bool>());
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(r.comparison["views"][i]["voxels"]["same"].get<bool>()) << "view " << i + 1;
    EXPECT_TRUE(r.comparison["views"][i]["accepted"]["same"].get<bool>()) << "view " << i + 1;
  }
  EXPECT_FALSE(r.comparison["views"][1]["plan"]["same"].get<bool>());
  EXPECT_GT(r.comparison["views"][1]["plan"]["position_m"].get<double>(), 0.01);

  // The executor's turntable rule is recorded (quickest). The same recording with the field taken
  // out reads as one made before the least turn was narrowed: the replay commands the grid's turns
  // (kLeastTurnOnGrid), which this scan's turning moves did not take, so the replay rig refuses
  // them. A recording made then replays (docs/replay.md; a scan of stop 47 did, all 10 views).
  EXPECT_EQ(recorded["settings"]["planning"]["least_turn"], "quickest");
  const fs::path older = original.parent_path() / "as-if-older";
  fs::copy(original, older, fs::copy_options::recursive);
  json settings = read_json((older / "settings.json").string());
  settings["planning"].erase("least_turn");
  write_json_atomic(settings, (older / "settings.json").string());
  const Replayed g = replay(older, "replay-grid", "", 1);  // no view reached: the replayed scan fails
  EXPECT_EQ(g.replay_scan["settings"]["planning"]["least_turn"], "grid");
  EXPECT_FALSE(g.comparison["same_decisions"].get<bool>()) << "the grid's turns were the quickest ones";
  int refused = 0;
  for (const json& v : g.replay_scan["views"]) {
    for (const json& f : v.value("failed_moves", json::array())) {
      if (f.dump().find("no recorded view was commanded to these joints") != std::string::npos) ++refused;
    }
  }
  EXPECT_GT(refused, 0) << g.replay_scan["views"].dump(1);
}

TEST(Replay, AFolderThatCannotBeReplayedIsNamedBeforeAnythingStarts) {
  const fs::path missing = fresh_dir("replay-missing") / "nothing";
  EXPECT_NE(replay_error(missing).find("pbnbv replay: " + missing.string() + " is not a folder"), std::string::npos);

  fs::path dir = scan_folder("replay-no-scan-json", "bunny-00000000000000aa");
  fs::remove(dir / "scan.json");
  EXPECT_NE(replay_error(dir).find(dir.string() + " has no scan.json: not a scan's folder"), std::string::npos);

  dir = scan_folder("replay-no-log", "bunny-00000000000000aa");
  EXPECT_NE(replay_error(dir).find(dir.string() + " has no scan.lcmlog: the scan was not recorded (--no-log)"),
            std::string::npos);

  // A log of other channels only.
  dir = scan_folder("replay-no-rig", "bunny-00000000000000aa");
  arm_command_t command{};
  command.scan_id = "bunny-00000000000000aa";
  command.num_joints = 6;
  command.joint_position_rad.assign(6, 0.0);
  write_log(dir / "scan.lcmlog", std::pair<std::string, arm_command_t>{"SOMETHING_ELSE", command});
  EXPECT_NE(replay_error(dir).find((dir / "scan.lcmlog").string() +
                                   " holds no ARM_STATUS: not a recording of the rig channels"),
            std::string::npos);

  // The rig channels of another scan: the statuses name no scan, the command and the frame another.
  dir = scan_folder("replay-other-scan", "bunny-00000000000000aa");
  arm_status_t status{};
  status.num_joints = 6;
  status.joint_names.assign(6, "j");
  status.joint_position_rad = status.joint_velocity_rad_s = status.joint_position_commanded_rad =
      std::vector<double>(6, 0.0);
  command.scan_id = "teapot-00000000000000bb";
  depth_frame_t frame{};
  frame.scan_id = "teapot-00000000000000bb";
  write_log(dir / "scan.lcmlog", std::pair<std::string, arm_status_t>{"ARM_STATUS", status},
            std::pair<std::string, arm_command_t>{"ARM_COMMAND", command},
            std::pair<std::string, depth_frame_t>{"DEPTH_FRAME", frame});
  EXPECT_NE(replay_error(dir).find((dir / "scan.lcmlog").string() +
                                   " holds no DEPTH_FRAME of scan bunny-00000000000000aa: it is a recording of scan "
                                   "teapot-00000000000000bb"),
            std::string::npos);
}
