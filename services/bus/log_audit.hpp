#pragma once
// What a scan's LCM log (scan.lcmlog, written by lcm-logger) holds of the scan's data path, and
// what it lacks against the views the scan recorded: the launcher checks every scan's log this
// way, so a lossy log is said, not found out later.
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace pbnbv::bus {

struct LogContents {
  int64_t events = 0;                 // every event of the log, any channel
  int64_t undecodable = 0;            // events on the channels below that do not decode
  std::set<int64_t> depth_frames;     // seq of each DEPTH_FRAME of the scan (or of no scan)
  std::set<int> clouds;               // iteration of each CLOUD of the scan
  std::set<int> registered_clouds;    // iteration of each REGISTERED_CLOUD of the scan
  std::set<int> voxel_maps;           // iteration of each VOXEL_MAP of the scan
};

// Reads the log at `path`, keeping what belongs to `scan_id`. Throws std::runtime_error naming
// the file when it cannot be opened.
LogContents read_scan_log(const std::string& path, const std::string& scan_id);
// The same over several files (a restarted lcm-logger goes on in scan.lcmlog.00, .01, ...).
LogContents read_scan_logs(const std::vector<std::string>& paths, const std::string& scan_id);

// What scan.json says of a view's messages (the launcher fills it from the scan's record).
struct ViewMessages {
  int view = 0;                  // 0-based
  bool captured = false;         // it has a capture: its DEPTH_FRAME (when >= 0) and CLOUD
  int64_t depth_frame_seq = -1;
  bool registered = false;       // its REGISTERED_CLOUD
  bool mapped = false;           // its VOXEL_MAP
};

// The messages a scan's views say were sent and the log lacks, one line each ("view 3:
// DEPTH_FRAME 1733069123000042"); empty when the log holds them all.
std::vector<std::string> missing_from_log(const LogContents& log, const std::vector<ViewMessages>& views);

}  // namespace pbnbv::bus
