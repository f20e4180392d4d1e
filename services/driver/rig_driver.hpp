#pragma once
// A rig driver on the bus: the ARM_COMMAND, TURNTABLE_COMMAND and DEPTH_TRIGGER subscriptions,
// each command checked (rig_contract.hpp) before the driver's handler moves anything and a
// refusal latched as the status's fault until a command is accepted, and the statuses numbered
// and published. What a lab writes is the handlers and a loop that reads its devices and calls
// publish_statuses at least 50 times a second (README "Writing a driver"; the twin,
// twin/twin_main.cpp, is the reference driver built on it). A driver may own part of the rig
// (pbnbv-ur-driver: the arm; another driver the turntable and the camera): it subscribes to the
// commands of the parts it has a handler for and publishes only their statuses.
#include <functional>
#include <optional>
#include <string>

#include "bus/bus.hpp"
#include "driver/rig_contract.hpp"

namespace pbnbv::driver {

class RigDriver {
 public:
  // Each handler is optional (at least one is set): an empty one means another driver owns that
  // part of the rig, and this one neither subscribes to its commands nor publishes its status.
  struct Handlers {
    // Starts a move to the target (or a hold). Throws OutOfLimits for a target outside the
    // limits, std::invalid_argument for any other refusal; nothing moves then.
    std::function<void(const ArmTarget&)> move_arm;
    // The turntable's (see Options::no_turntable for a rig without one).
    std::function<void(const TurntableTarget&)> turn_table;
    // Captures the frame answering a trigger (depth_frame builds it); it is published as returned.
    std::function<depth_frame_t(const depth_trigger_t&)> capture;
  };
  struct Options {
    int arm_joints = 6;
    // Pass commands with a speed scale outside (0, 1] to the handlers (a driver that clamps it
    // itself, or the twin playing a faulty driver); the contract refuses them.
    bool any_speed_scale = false;
    // The rig has no turntable: TURNTABLE_COMMAND is subscribed to and every one refused ("this
    // rig has no turntable"), so that a scan asking for one is told why (no turn_table handler).
    bool no_turntable = false;
  };

  // Subscribes on `bus` (its serve_scan scope names the statuses' scan_id) to the commands it has
  // handlers for. The handlers are called from bus.spin_once. Throws std::invalid_argument when
  // no handler is set, or a turntable handler with no_turntable.
  RigDriver(bus::Bus& bus, Handlers handlers, Options options);

  // Publishes ARM_STATUS and TURNTABLE_STATUS for the readings given, numbered from 0 (one number
  // per call), with the faults latched; returns the sequence number used. Throws
  // std::invalid_argument for a reading of a part this driver does not own (no handler).
  int64_t publish_statuses(const Stamp& stamp, const std::optional<ArmReading>& arm,
                           const std::optional<TurntableReading>& turntable);

  // A failure of the arm's drive itself (a protective stop, a lost controller connection): while
  // set, every ARM_STATUS reports it as kFaultDriver with `text`, ahead of a refused command's
  // fault (which stays latched beneath it). The driver clears it ("") when the drive is well.
  void set_arm_drive_fault(const std::string& text);

  // The arm touched something while executing command `command_seq` (the driver's collision
  // detection; the twin's contact check) and has stopped: every ARM_STATUS reports kFaultContact
  // with `text` ("contact: link_6 / platter, ...") and that seq, latched like a refused command's
  // fault until the driver accepts a command. Count the event in ArmReading::contacts too.
  void set_arm_contact(int64_t command_seq, const std::string& text);

  bool owns_arm() const { return static_cast<bool>(handlers_.move_arm); }
  bool owns_turntable() const { return static_cast<bool>(handlers_.turn_table) || options_.no_turntable; }
  bool owns_camera() const { return static_cast<bool>(handlers_.capture); }
  const FaultLatch& arm_fault() const { return arm_fault_; }
  const FaultLatch& arm_drive_fault() const { return arm_drive_fault_; }
  const FaultLatch& turntable_fault() const { return turntable_fault_; }
  int64_t statuses_published() const { return status_seq_; }

 private:
  void on_arm(const arm_command_t& c);
  void on_turntable(const turntable_command_t& c);

  bus::Bus& bus_;
  Handlers handlers_;
  Options options_;
  FaultLatch arm_fault_;
  FaultLatch arm_drive_fault_;
  FaultLatch turntable_fault_;
  int64_t status_seq_ = 0;
};

}  // namespace pbnbv::driver
