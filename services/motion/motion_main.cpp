// pbnbv-motion: the motion executor.
//   in:  MOVE_REQUEST (a camera pose in the object frame), ARM_STATUS, TURNTABLE_STATUS
//   out: ARM_COMMAND, TURNTABLE_COMMAND, MOVE_RESULT, HEARTBEAT
// Wires the bus to core/scan's MotionSequencer (which splits the pose into a turntable angle and
// an arm configuration, commands the rig, re-sends unacknowledged commands and answers reached /
// unreachable / timed out with the reason). Requests are idempotent by request_id: a repeat is
// answered again from the reply cache.
#include <fmt/format.h>

#include <memory>
#include <string>
#include <utility>

#include "bus/bus.hpp"
#include "bus/convert_rig.hpp"
#include "bus/convert_scan.hpp"
#include "bus/reply_cache.hpp"
#include "bus/rig_commands.hpp"
#include "bus/rig_options.hpp"
#include "bus/service.hpp"
#include "core/base/format.hpp"
#include "core/base/log.hpp"
#include "core/rig/rig.hpp"
#include "core/acquisition/motion_sequencer.hpp"
#include "pbnbv/stop_request_t.hpp"

using namespace pbnbv;

namespace {

constexpr std::size_t kResultsKept = 256;

class MotionService {
 public:
  MotionService(bus::Bus& bus, const RigModel& rig) : bus_(bus), rig_(rig), sequencer_(rig, bus::now_utime()) {
    bus_.subscribe<arm_status_t>(channels::kArmStatus, [this](const arm_status_t& s) {
      const ArmReading reading = bus::from_msg(s);
      warn_of_contacts(reading);
      sequencer_.on_arm_status(reading, bus::now_s());
    });
    if (rig_.has_turntable) {
      bus_.subscribe<turntable_status_t>(channels::kTurntableStatus, [this](const turntable_status_t& s) {
        sequencer_.on_turntable_status(bus::from_msg(s), bus::now_s());
      });
    }
    bus_.subscribe<move_request_t>(channels::kMoveRequest, [this](const move_request_t& r) { on_request(r); });
    bus_.subscribe<stop_request_t>(channels::kStop, [this](const stop_request_t& s) {
      log_warn("STOP (" + s.reason + "): holding the rig where it is");
      apply(sequencer_.halt("STOP (" + s.reason + ")", bus::now_s(), s.scan_id));
    });
  }

  void tick() { apply(sequencer_.tick(bus::now_s())); }

 private:
  // The log says at once when the rig counts a contact, during a move (its MOVE_RESULT carries it
  // too) or while none is in progress (nothing else records it then).
  void warn_of_contacts(const ArmReading& r) {
    if (contacts_seen_ >= 0 && r.contacts > contacts_seen_) {
      log_warn(fmt::format("the rig reports {} new contact{} ({} since its driver started), {}: {}", r.contacts - contacts_seen_,
                           r.contacts - contacts_seen_ == 1 ? "" : "s", r.contacts,
                           sequencer_.moving() ? "during the move in progress" : "while no move is in progress",
                           r.last_contact));
    }
    contacts_seen_ = r.contacts;
  }

  void on_request(const move_request_t& m) {
    bus_.set_scan(m.scan_id, m.iteration);
    if (const move_result_t* done = results_.find({m.scan_id, m.request_id})) {
      bus_.publish(channels::kMoveResult, *done);  // a repeat: answer again
      return;
    }
    MoveRequest request;
    try {
      request = bus::from_msg(m);
    } catch (const std::exception& e) {
      move_result_t result = bus::to_msg(sequencer_.rejected(m.scan_id, m.iteration, m.request_id, e.what()));
      result.requested_object_T_camera = result.reached_object_T_camera = m.object_T_camera;  // as received
      answer(std::move(result), true);
      throw;  // counted and logged by the bus as a rejection
    }
    scan_ = m.scan_id;  // the scan the rig's commands belong to from now on
    apply(sequencer_.on_request(request, bus::now_s()));
  }

  // Publishes what a step of the sequencer asks for.
  void apply(const MotionStep& step) {
    for (const std::string& w : step.warnings) log_warn(w);
    bus::publish_rig_commands(bus_, step.arm_command, step.turntable_command, scan_);
    if (step.result) {
      const MoveResult& r = *step.result;
      if (r.status == MoveStatus::kUnreachable || r.status == MoveStatus::kReached || r.status == MoveStatus::kTimedOut) {
        log_info(fmt::format("request {}: {}{} (position error {} mm, move {} s, settle {} s)", r.request_id,
                             to_string(r.status), r.reason.empty() ? "" : ": " + r.reason,
                             fixed(r.position_error_m * 1e3, 2), fixed(r.move_s, 2), fixed(r.settle_s, 2)));
      }
      answer(bus::to_msg(r), step.keep_result);
    }
    bus_.set_state(sequencer_.moving() ? "moving" : "idle");
  }

  // Publishes an answer; a final one is kept to answer a repeat of its request.
  void answer(move_result_t result, bool keep) {
    result.utime = bus::now_utime();
    if (keep) results_.put({result.scan_id, result.request_id}, result);
    bus_.publish(channels::kMoveResult, result);
  }

  bus::Bus& bus_;
  const RigModel& rig_;
  MotionSequencer sequencer_;
  std::string scan_;  // of the request being executed
  int32_t contacts_seen_ = -1;  // the rig's contact count in the last ARM_STATUS (-1: none, or it cannot tell)
  bus::ReplyCache<std::pair<std::string, int64_t>, move_result_t> results_{kResultsKept};
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbnbv-motion: moves the arm and the turntable to each MOVE_REQUEST's camera pose", "pbnbv-motion"};
  cli::init(app);
  bus::RigOptions rig_options;
  bus::add_rig_options(app, &rig_options);
  return bus::run_service("motion", app, argc, argv, 5, [&](bus::Bus& bus) -> std::function<void()> {
    auto rig = std::make_shared<RigModel>(bus::load_rig(rig_options));
    auto service = std::make_shared<MotionService>(bus, *rig);
    log_info("ready: " + rig->arm_name + " from " + rig->model_path);
    return [rig, service] { service->tick(); };
  });
}
