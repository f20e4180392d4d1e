#pragma once
// A rig driver on the bus: the ARM_COMMAND, TURNTABLE_COMMAND and DEPTH_TRIGGER subscriptions,
// each command checked (rig_contract.hpp) before the driver's handler moves anything and a
// refusal latched as the status's fault until a command is accepted, and the statuses numbered
// and published. What a lab writes is the three handlers and a loop that reads its devices and
// calls publish_statuses at least 50 times a second (README "Writing a driver"; the twin,
// twin/twin_main.cpp, is the reference driver built on it).
#include <functional>
#include <optional>
#include <string>

#include "bus/bus.hpp"
#include "driver/rig_contract.hpp"

namespace pbnbv::driver {

class RigDriver {
 public:
  struct Handlers {
    // Starts a move to the target (or a hold). Throws OutOfLimits for a target outside the
    // limits, std::invalid_argument for any other refusal; nothing moves then.
    std::function<void(const ArmTarget&)> move_arm;
    // The turntable's; empty for a rig without one (its commands are refused).
    std::function<void(const TurntableTarget&)> turn_table;
    // Captures the frame answering a trigger (depth_frame builds it); it is published as returned.
    std::function<depth_frame_t(const depth_trigger_t&)> capture;
  };
  struct Options {
    int arm_joints = 6;
    // Pass commands with a speed scale outside (0, 1] to the handlers (a driver that clamps it
    // itself, or the twin playing a faulty driver); the contract refuses them.
    bool any_speed_scale = false;
  };

  // Subscribes on `bus` (its serve_scan scope names the statuses' scan_id). The handlers are
  // called from bus.spin_once.
  RigDriver(bus::Bus& bus, Handlers handlers, Options options);

  // Publishes ARM_STATUS and, with a reading, TURNTABLE_STATUS, numbered from 0, with the faults
  // latched; returns the sequence number used.
  int64_t publish_statuses(const Stamp& stamp, const ArmReading& arm, const std::optional<TurntableReading>& turntable);

  const FaultLatch& arm_fault() const { return arm_fault_; }
  const FaultLatch& turntable_fault() const { return turntable_fault_; }
  int64_t statuses_published() const { return status_seq_; }

 private:
  void on_arm(const arm_command_t& c);
  void on_turntable(const turntable_command_t& c);

  bus::Bus& bus_;
  Handlers handlers_;
  Options options_;
  FaultLatch arm_fault_;
  FaultLatch turntable_fault_;
  int64_t status_seq_ = 0;
};

}  // namespace pbnbv::driver
