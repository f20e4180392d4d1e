// pbnbv-replay-rig: a recorded scan's rig, played back from its log: a rig driver like the twin
// that speaks only the rig channels, with recorded readings and frames instead of physics and
// rendering (core/scan/replay_rig.hpp):
//   in:  ARM_COMMAND, TURNTABLE_COMMAND, DEPTH_TRIGGER
//   out: ARM_STATUS, TURNTABLE_STATUS (every 10 ms: the recorded readings of the view the
//        commands are for, the commands' seq echoed), DEPTH_FRAME (the view's recorded frame,
//        the trigger's seq and scan id), HEARTBEAT
// A command no recorded view was given is refused (kFaultCommandRejected), as a driver refuses a
// target it cannot reach.
#include <memory>
#include <string>
#include <vector>

#include "bus/bus.hpp"
#include "bus/convert_rig.hpp"
#include "bus/rig_log.hpp"
#include "bus/service.hpp"
#include "core/base/log.hpp"
#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/depth_trigger_t.hpp"
#include "pbnbv/turntable_command_t.hpp"

using namespace pbnbv;

namespace {

constexpr double kStatusPeriodS = 0.01;  // 100 Hz, as the twin

class ReplayRigService {
 public:
  ReplayRigService(bus::Bus& bus, bus::RigLog log) : bus_(bus), log_(std::move(log)), rig_(bus::timeline_of(log_)) {
    bus_.subscribe<arm_command_t>(channels::kArmCommand, [this](const arm_command_t& c) {
      if (c.mode == arm_command_t::kModeHold) {
        rig_.on_arm_hold(c.seq);
      } else if (c.mode == arm_command_t::kModePosition && c.num_joints == 6) {
        rig_.on_arm_command(c.seq, bus::to_vector6(c.joint_position_rad, "ARM_COMMAND joint_position_rad"));
        if (!rig_.arm_fault().empty()) throw std::invalid_argument(rig_.arm_fault());
        log_info("ARM_COMMAND seq " + std::to_string(c.seq) + ": " +
                 (rig_.detour_stop() < 0 ? "recorded view " + std::to_string(rig_.view() + 1)
                                         : "stop " + std::to_string(rig_.detour_stop() + 1) + " of recorded view " +
                                               std::to_string(rig_.view() + 2) + "'s detour"));
      } else {
        throw std::invalid_argument("ARM_COMMAND seq " + std::to_string(c.seq) + ": unknown mode or num_joints");
      }
    });
    bus_.subscribe<turntable_command_t>(channels::kTurntableCommand, [this](const turntable_command_t& c) {
      rig_.on_turntable_command(c.seq, c.angle_rad);
      if (!rig_.turntable_fault().empty()) throw std::invalid_argument(rig_.turntable_fault());
    });
    bus_.subscribe<depth_trigger_t>(channels::kDepthTrigger, [this](const depth_trigger_t& t) {
      const std::optional<std::size_t> f = rig_.on_trigger();
      if (!f) {
        throw std::invalid_argument("DEPTH_TRIGGER seq " + std::to_string(t.seq) +
                                    (rig_.view() < 0 && rig_.detour_stop() < 0 ? " before any command"
                                                                               : " at a detour's stop") +
                                    ": no recorded view to show");
      }
      depth_frame_t frame = log_.frames[*f].msg;
      frame.trigger_seq = t.seq;
      frame.scan_id = t.scan_id;
      bus_.publish(channels::kDepthFrame, frame);
    });
    // Views whose readings at the exposure the log lost (StatusSpan): their pose cannot be the recording's.
    for (std::size_t v = 0; v < rig_.views().size(); ++v) {
      const RecordedView& r = rig_.views()[v];
      for (const auto& [what, span] : {std::pair{"ARM_STATUS", r.arm}, std::pair{"TURNTABLE_STATUS", r.turntable}}) {
        if (!span.nearest_reading_lost && !span.restamp_utime) continue;
        log_warn("recorded view " + std::to_string(v + 1) + ": the log lacks the " + what +
                 " nearest the frame's exposure (lost by lcm-logger); the camera pose will differ from the "
                 "recording's by what the rig moved between it and the nearest one logged");
      }
    }
    log_info("playing " + std::to_string(rig_.views().size()) + " recorded views (" +
             std::to_string(log_.arm_statuses.size()) + " arm statuses, " + std::to_string(log_.frames.size()) +
             " frames)");
  }

  // Every kStatusPeriodS: the statuses the player names, as recorded but for the command seq, the
  // fault and the scan.
  void tick() {
    const double now = bus::now_s();
    if (now < next_status_s_) return;
    next_status_s_ = now + kStatusPeriodS;
    const ReplayRig::Statuses s = rig_.tick();
    arm_status_t a = log_.arm_statuses[s.arm].msg;
    if (s.arm_utime) a.utime = *s.arm_utime;
    a.seq = seq_;
    a.scan_id = bus_.scope();
    a.command_seq = rig_.arm_command_seq();
    set_fault(a, rig_.arm_fault(), rig_.arm_fault_seq());
    bus_.publish(channels::kArmStatus, a);
    if (s.turntable) {
      turntable_status_t t = log_.turntable_statuses[*s.turntable].msg;
      if (s.turntable_utime) t.utime = *s.turntable_utime;
      t.seq = seq_;
      t.scan_id = bus_.scope();
      t.command_seq = rig_.turntable_command_seq();
      set_fault(t, rig_.turntable_fault(), rig_.turntable_fault_seq());
      bus_.publish(channels::kTurntableStatus, t);
    }
    ++seq_;
  }

 private:
  // A refused command as the twin reports it; no fault otherwise.
  template <class Status>
  static void set_fault(Status& s, const std::string& fault, int64_t seq) {
    if (fault.empty()) {
      if (s.mode == Status::kModeFault) s.mode = Status::kModeSettled;
      s.fault_code = Status::kFaultNone;
      s.fault_command_seq = -1;
      s.fault.clear();
      return;
    }
    s.mode = Status::kModeFault;
    s.fault_code = Status::kFaultCommandRejected;
    s.fault_command_seq = seq;
    s.fault = fault;
  }

  bus::Bus& bus_;
  bus::RigLog log_;
  ReplayRig rig_;
  double next_status_s_ = 0;
  int64_t seq_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbnbv-replay-rig: a recorded scan's rig (arm, turntable, depth camera) played back from its LCM log "
               "on the rig channels",
               "pbnbv-replay-rig"};
  cli::init(app);
  std::vector<std::string> logs;
  cli::add_words(app, "log", &logs, "the recorded scan's LCM logs, in order (scan.lcmlog,scan.lcmlog.00,...)")->required();
  std::string recorded;
  cli::add_text(app, "recorded-scan", &recorded, "the id of the recorded scan (its settings.json's scan_id)", "ID")
      ->required();
  return bus::run_service("replay-rig", app, argc, argv, 5, [&](bus::Bus& bus) -> std::function<void()> {
    auto service = std::make_shared<ReplayRigService>(bus, bus::read_rig_log(logs, recorded));
    return [service] { service->tick(); };
  });
}
