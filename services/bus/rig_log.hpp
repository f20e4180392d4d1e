#pragma once
// The rig channels of a recorded scan (scan.lcmlog, and scan.lcmlog.NN after lcm-logger
// restarts), read for playing the scan's rig back (pbnbv-replay-rig, `pbnbv replay`): the arm's
// and the turntable's statuses, the motion executor's commands and the camera's frames of one
// scan, each with its place in the log (convert_rig.hpp's timeline_of makes them the timeline
// core/scan/replay_rig.hpp plays).
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "bus/message_guard.hpp"

#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/turntable_command_t.hpp"
#include "pbnbv/turntable_status_t.hpp"

namespace pbnbv::bus {

// Decodes a log event as T once the message guard passed it (bus/message_guard.hpp: a logged
// packet claiming gigabytes is refused, not allocated); false (not a throw) for an event that does
// not decode: a log may hold a truncated last event or another program's messages on a channel.
template <class T>
bool decode_logged(const lcm::LogEvent& e, T* msg) {
  return decode_checked(e.channel, e.data, e.datalen, msg);
}

// A message and its event number in the log (over every file, in order).
template <class T>
struct Logged {
  int64_t order = 0;
  T msg;
};

struct RigLog {
  std::vector<Logged<arm_status_t>> arm_statuses;  // of the scan's rig, log order
  std::vector<Logged<turntable_status_t>> turntable_statuses;
  std::vector<Logged<depth_frame_t>> frames;  // answering the scan's triggers
  std::vector<Logged<arm_command_t>> arm_commands;  // position commands of the scan
  std::vector<Logged<turntable_command_t>> turntable_commands;
  std::set<std::string> other_scans;  // scans the rig channels also carry
};

// Reads the rig channels of scan `scan_id` from `paths`, in order. A status is the scan's when it
// names the scan or no scan; a command or a frame when it names the scan (a frame may name none).
// Throws std::invalid_argument naming the files when one cannot be read, when they hold no rig
// channel (no ARM_STATUS or no DEPTH_FRAME), or when their frames and commands are of other scans
// only (naming them).
RigLog read_rig_log(const std::vector<std::string>& paths, const std::string& scan_id);

// scan.lcmlog and its continuations scan.lcmlog.NN in `dir`, in order (empty: none).
std::vector<std::string> scan_log_files(const std::string& dir);

}  // namespace pbnbv::bus
