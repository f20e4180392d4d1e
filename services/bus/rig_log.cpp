#include "bus/rig_log.hpp"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "bus/channels.hpp"

namespace fs = std::filesystem;

namespace pbnbv::bus {

namespace {

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

}  // namespace

RigLog read_rig_log(const std::vector<std::string>& paths, const std::string& scan_id) {
  if (paths.empty()) throw std::invalid_argument("no LCM log to read");
  RigLog log;
  int64_t order = 0;
  bool any_arm = false, any_frame = false;
  for (const std::string& path : paths) {
    lcm::LogFile file(path, "r");
    if (!file.good()) throw std::invalid_argument("cannot read the LCM log " + path);
    while (const lcm::LogEvent* e = file.readNextEvent()) {
      ++order;
      const auto mine = [&](const std::string& id, bool may_be_unscoped) {
        if (id == scan_id || (may_be_unscoped && id.empty())) return true;
        log.other_scans.insert(id);
        return false;
      };
      if (e->channel == channels::kArmStatus) {
        arm_status_t m;
        if (!decode_logged(*e, &m) || m.num_joints != 6) continue;
        any_arm = true;
        if (!mine(m.scan_id, true)) continue;
        log.arm_statuses.push_back({order, std::move(m)});
      } else if (e->channel == channels::kTurntableStatus) {
        turntable_status_t m;
        if (!decode_logged(*e, &m) || !mine(m.scan_id, true)) continue;
        log.turntable_statuses.push_back({order, std::move(m)});
      } else if (e->channel == channels::kDepthFrame) {
        depth_frame_t m;
        if (!decode_logged(*e, &m)) continue;
        any_frame = true;
        if (!mine(m.scan_id, true)) continue;
        log.frames.push_back({order, std::move(m)});
      } else if (e->channel == channels::kArmCommand) {
        arm_command_t m;
        if (!decode_logged(*e, &m) || !mine(m.scan_id, false) || m.mode != arm_command_t::kModePosition || m.num_joints != 6) continue;
        log.arm_commands.push_back({order, std::move(m)});
      } else if (e->channel == channels::kTurntableCommand) {
        turntable_command_t m;
        if (!decode_logged(*e, &m) || !mine(m.scan_id, false)) continue;
        log.turntable_commands.push_back({order, std::move(m)});
      }
    }
  }
  log.other_scans.erase("");
  log.other_scans.erase(scan_id);
  const std::string files = joined(paths);
  if (!any_arm || !any_frame) {
    throw std::invalid_argument(files + " holds no " + std::string(!any_arm ? "ARM_STATUS" : "DEPTH_FRAME") +
                                ": not a recording of the rig channels (ARM_STATUS, TURNTABLE_STATUS, DEPTH_FRAME, "
                                "ARM_COMMAND, TURNTABLE_COMMAND)");
  }
  if (log.frames.empty() || log.arm_commands.empty()) {
    const std::vector<std::string> others(log.other_scans.begin(), log.other_scans.end());
    throw std::invalid_argument(files + " holds no " + std::string(log.frames.empty() ? "DEPTH_FRAME" : "ARM_COMMAND") +
                                " of scan " + scan_id +
                                (others.empty() ? std::string() : ": it is a recording of scan " + joined(others)));
  }
  return log;
}

std::vector<std::string> scan_log_files(const std::string& dir) {
  std::vector<std::string> files;
  if (!fs::is_directory(dir)) return files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().filename().string().rfind("scan.lcmlog", 0) == 0) files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());  // scan.lcmlog, scan.lcmlog.00, .01, ...
  return files;
}

}  // namespace pbnbv::bus
