#pragma once
// The faults `pbnbv-twin --fault NAME[,NAME...]` plays, so that `pbnbv rig-check` can be shown to
// catch each one: the twin then behaves as a faulty real driver would.
#include <algorithm>
#include <array>
#include <vector>

#include "core/base/enum_names.hpp"

namespace pbnbv::twin {

enum class DriverFault {
  kSlowStatus,      // ARM_STATUS / TURNTABLE_STATUS at 20 Hz of rig time instead of 100 Hz
  kNoSeqEcho,       // statuses never echo a command's seq (command_seq stays -1)
  kDepthUnitMm,     // depth counts in millimetres while depth_unit_m still says 0.1 mm
  kNoTriggerId,     // frames carry trigger_seq -1 instead of the trigger's seq
  kIgnoreLimits,    // out-of-limit arm targets and bad turntable commands are executed
  kUtimeBackwards,  // every 20th status is stamped 50 ms before the previous one
  kLateExposure,    // frames are stamped 1 s after the rig time of their exposure
  // As a UR controller (--rtde-port):
  kRtdeDrop,        // the RTDE connection is closed once, 2 s of rig time after the first move starts
  kProtectiveStop,  // the second move stops halfway in a protective stop (safety mode 3) and stays there
};

inline bool has_fault(const std::vector<DriverFault>& faults, DriverFault f) {
  return std::find(faults.begin(), faults.end(), f) != faults.end();
}

}  // namespace pbnbv::twin

namespace pbnbv {
template <>
struct EnumNames<twin::DriverFault> {
  static constexpr std::string_view what = "driver fault";
  static constexpr std::array<NamedValue<twin::DriverFault>, 9> names{{
      {twin::DriverFault::kSlowStatus, "slow-status"},
      {twin::DriverFault::kNoSeqEcho, "no-seq-echo"},
      {twin::DriverFault::kDepthUnitMm, "depth-unit-mm"},
      {twin::DriverFault::kNoTriggerId, "no-trigger-id"},
      {twin::DriverFault::kIgnoreLimits, "ignore-limits"},
      {twin::DriverFault::kUtimeBackwards, "utime-backwards"},
      {twin::DriverFault::kLateExposure, "late-exposure"},
      {twin::DriverFault::kRtdeDrop, "rtde-drop"},
      {twin::DriverFault::kProtectiveStop, "protective-stop"},
  }};
};
}  // namespace pbnbv
