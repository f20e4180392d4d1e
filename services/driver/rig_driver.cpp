#include "driver/rig_driver.hpp"

#include <stdexcept>
#include <utility>

#include "bus/channels.hpp"

namespace pbnbv::driver {

namespace {

// Runs `act`; a refusal is latched in `fault` ("rejected <CHANNEL> seq N: <why>", kOutOfLimits for
// OutOfLimits) and thrown on for the bus to count and log; an acceptance clears the latch.
template <class Act>
void latched(FaultLatch& fault, const char* channel, int64_t seq, Act&& act) {
  try {
    act();
    fault.clear();
  } catch (const std::exception& e) {
    const bool limits = dynamic_cast<const OutOfLimits*>(&e) != nullptr;
    fault.set(limits ? FaultCode::kOutOfLimits : FaultCode::kCommandRejected, seq,
              std::string("rejected ") + channel + " seq " + std::to_string(seq) + ": " + e.what());
    throw std::invalid_argument(fault.text());
  }
}

}  // namespace

RigDriver::RigDriver(bus::Bus& bus, Handlers handlers, Options options)
    : bus_(bus), handlers_(std::move(handlers)), options_(options) {
  if (!handlers_.move_arm && !handlers_.turn_table && !handlers_.capture) {
    throw std::invalid_argument("RigDriver: a driver needs at least one handler (arm, turntable or capture)");
  }
  if (handlers_.turn_table && options_.no_turntable) {
    throw std::invalid_argument("RigDriver: a turntable handler for a rig with no turntable (Options::no_turntable)");
  }
  if (owns_arm()) {
    bus_.subscribe<arm_command_t>(channels::kArmCommand, [this](const arm_command_t& c) { on_arm(c); });
  }
  if (owns_turntable()) {
    bus_.subscribe<turntable_command_t>(channels::kTurntableCommand,
                                        [this](const turntable_command_t& c) { on_turntable(c); });
  }
  if (owns_camera()) {
    bus_.subscribe<depth_trigger_t>(channels::kDepthTrigger, [this](const depth_trigger_t& t) {
      const depth_frame_t frame = handlers_.capture(t);
      bus_.publish(channels::kDepthFrame, frame);
    });
  }
}

void RigDriver::set_arm_drive_fault(const std::string& text) {
  if (text.empty()) {
    arm_drive_fault_.clear();
  } else {
    arm_drive_fault_.set(FaultCode::kDriver, -1, text);
  }
}

void RigDriver::set_arm_contact(int64_t command_seq, const std::string& text) {
  if (text.empty()) throw std::invalid_argument("RigDriver::set_arm_contact: a contact needs its text");
  arm_fault_.set(FaultCode::kContact, command_seq, text);
}

void RigDriver::on_arm(const arm_command_t& c) {
  latched(arm_fault_, "ARM_COMMAND", c.seq,
          [&] { handlers_.move_arm(arm_target(c, options_.arm_joints, options_.any_speed_scale)); });
}

void RigDriver::on_turntable(const turntable_command_t& c) {
  latched(turntable_fault_, "TURNTABLE_COMMAND", c.seq, [&] {
    if (!handlers_.turn_table) throw std::invalid_argument("this rig has no turntable");
    handlers_.turn_table(turntable_target(c, options_.any_speed_scale));
  });
}

int64_t RigDriver::publish_statuses(const Stamp& stamp, const std::optional<ArmReading>& arm,
                                    const std::optional<TurntableReading>& turntable) {
  if (arm && !owns_arm()) throw std::invalid_argument("RigDriver: an arm reading, but this driver does not own the arm");
  if (turntable && !handlers_.turn_table) {
    throw std::invalid_argument("RigDriver: a turntable reading, but this driver does not own a turntable");
  }
  const int64_t seq = status_seq_++;
  if (arm) {
    const FaultLatch& fault = arm_drive_fault_.active() ? arm_drive_fault_ : arm_fault_;
    bus_.publish(channels::kArmStatus, arm_status(stamp, seq, bus_.scope(), *arm, fault));
  }
  if (turntable) {
    bus_.publish(channels::kTurntableStatus, turntable_status(stamp, seq, bus_.scope(), *turntable, turntable_fault_));
  }
  return seq;
}

}  // namespace pbnbv::driver
