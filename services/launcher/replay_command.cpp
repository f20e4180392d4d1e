// `pbnbv replay` (commands.hpp).
#include <algorithm>
#include <iostream>

#include "bus/bus.hpp"
#include "bus/convert_rig.hpp"
#include "bus/rig_log.hpp"
#include "core/io/json.hpp"
#include "core/scan/replay_rig.hpp"
#include "core/scan/scan_comparison.hpp"
#include "core/scan/scan_file.hpp"
#include "core/scan/scan_record.hpp"
#include "launcher/commands.hpp"
#include "launcher/scan_processes.hpp"
#include "launcher/supervise.hpp"

namespace fs = std::filesystem;

namespace pbnbv::launcher {

namespace {

// Whether the recorded scan ran with registration: settings.json's "launch", or for a folder
// written before it, the registration service's command line in processes.json (a value read
// from the record, never a command run).
bool recorded_registration(const fs::path& dir, const ScanSettings& s) {
  const nlohmann::json settings = read_json((dir / "settings.json").string());
  if (settings.contains("launch")) {
    return launch_settings_from_json(settings.at("launch"), (dir / "settings.json").string()).registration;
  }
  bool on = s.rig == RigKind::kArm;  // the scan's default
  if (!fs::exists(dir / "processes.json")) return on;
  for (const auto& p : read_json((dir / "processes.json").string()).value("processes", nlohmann::json::array())) {
    if (p.value("name", "") != "registration") continue;
    const std::vector<std::string> argv = p.value("argv", std::vector<std::string>{});
    on = std::find(argv.begin(), argv.end(), "--off") == argv.end();
  }
  return on;
}

}  // namespace

int run_replay(const ReplayOptions& o, const fs::path& bin) {
  const fs::path dir = fs::absolute(o.dir).lexically_normal();
  if (!fs::is_directory(dir)) throw std::invalid_argument(dir.string() + " is not a folder");
  for (const char* f : {"scan.json", "settings.json"}) {
    if (!fs::exists(dir / f)) throw std::invalid_argument(dir.string() + " has no " + f + ": not a scan's folder");
  }
  const std::vector<std::string> logs = bus::scan_log_files(dir.string());
  if (logs.empty()) {
    throw std::invalid_argument(dir.string() + " has no scan.lcmlog: the scan was not recorded (--no-log), there is "
                                "nothing to replay");
  }
  const std::string scan_json = (dir / "scan.json").string();
  const RecordedScan recorded = read_scan_record(scan_json);  // every field checked
  ScanSettings s = scan_settings_from_json(read_json((dir / "settings.json").string()));
  const std::string recorded_id = s.scan_id;
  if (recorded.settings.scan_id != recorded_id) {
    throw std::invalid_argument(scan_json + " is not a record of scan " + recorded_id + " (settings.json's)");
  }
  // Everything the replay needs is there before anything starts: the recorded views' poses, and a
  // frame in the log for every view that was captured.
  const std::vector<std::vector<Pose>> attempts = recorded_attempts(recorded);
  const bus::RigLog log = bus::read_rig_log(logs, recorded_id);
  const std::vector<RecordedView> views = recorded_views(bus::timeline_of(log));
  const std::size_t played = views.size();
  // Views whose readings at the exposure lcm-logger lost: their camera pose cannot be the recording's.
  nlohmann::json readings_lost = nlohmann::json::array();
  for (std::size_t v = 0; v < views.size(); ++v) {
    const auto lost = [](const StatusSpan& s) { return s.nearest_reading_lost || s.restamp_utime.has_value(); };
    if (lost(views[v].arm) || (!log.turntable_statuses.empty() && lost(views[v].turntable))) readings_lost.push_back(v + 1);
  }
  std::size_t captured = 0;
  for (const ViewRecord& v : recorded.views) {
    if (v.capture && v.capture->ok) ++captured;
  }
  if (played < captured) {
    throw std::invalid_argument(logs.front() + " holds the frames of " + std::to_string(played) + " views, " + scan_json +
                                " records " + std::to_string(captured) + " captured views: frames were lost");
  }

  s.scan_id = new_scan_id(s.object_name);
  if (o.planner) s.planner = *o.planner;
  s.validate();
  const fs::path out = fs::absolute(o.out.empty() ? dir.string() + "-replay-" + timestamp() : o.out);
  prepare_out(out, o.overwrite);
  write_json_atomic(to_json(s), (out / "settings.json").string());
  std::cout << "pbnbv replay: " << recorded_id << " (" << attempts.size() << " views, " << played << " frames in "
            << logs.size() << " log file" << (logs.size() > 1 ? "s" : "") << ") with the " << name_of(s.planner)
            << " planner -> " << out.string() << " (scan " << s.scan_id << ")" << std::endl;

  if (!readings_lost.empty()) {
    std::cerr << "warning: " << logs.front() << " lacks the rig's readings nearest the exposure of view(s) "
              << readings_lost.dump() << " (lost by lcm-logger): their camera pose will differ slightly from the "
              << "recording's, and the decisions after them may too" << std::endl;
  }
  std::vector<process::Child> children;
  children.push_back(scan_process(
      "lcm-logger", {"/usr/bin/lcm-logger", "-q", "--lcm-url=" + bus::lcm_url(), "-f", (out / "scan.lcmlog").string()}, s,
      out));
  std::vector<std::string> rig = {(bin / "pbnbv-replay-rig").string(), "--recorded-scan", recorded_id, "--log"};
  std::string list;
  for (const std::string& l : logs) list += (list.empty() ? "" : ",") + l;
  rig.push_back(list);
  children.push_back(scan_process("replay-rig", rig, s, out));
  add_services(children, s, out, bin, recorded_registration(dir, s), {"--replay-of", scan_json});
  const int code = supervise(children, s, out, true, false);
  if (!fs::exists(out / "scan.json")) return code == 0 ? 1 : code;

  nlohmann::json comparison = compare_scans(recorded, read_scan_record(out));
  comparison["original"] = dir.string();
  comparison["replay"] = out.string();
  comparison["readings_lost_in_recording"] = readings_lost;
  comparison["planner"] = {{"original", name_of(recorded.settings.planner)}, {"replay", name_of(s.planner)}};
  write_json_atomic(comparison, (out / "replay.json").string());
  std::cout << "\n" << comparison_table(comparison) << "-> " << (out / "replay.json").string() << std::endl;
  return code;
}

}  // namespace pbnbv::launcher
