#pragma once
// Publishing the rig commands a motion step asks for (core/scan's MotionSequencer), as the motion
// executor and `pbnbv calibrate` both do: stamped now, naming the scan they belong to.
#include <optional>
#include <string>

#include "bus/bus.hpp"
#include "bus/convert_rig.hpp"

namespace pbnbv::bus {

inline void publish_rig_commands(Bus& bus, const std::optional<ArmCommand>& arm,
                                 const std::optional<TurntableCommand>& turntable, const std::string& scan_id) {
  if (arm) {
    arm_command_t a = to_msg(*arm);
    a.utime = now_utime();
    a.scan_id = scan_id;
    bus.publish(channels::kArmCommand, a);
  }
  if (turntable) {
    turntable_command_t t = to_msg(*turntable);
    t.utime = now_utime();
    t.scan_id = scan_id;
    bus.publish(channels::kTurntableCommand, t);
  }
}

}  // namespace pbnbv::bus
