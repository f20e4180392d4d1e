// pbnbv-camera: the camera service.
//   in:  CAPTURE_REQUEST, DEPTH_FRAME, ARM_STATUS, TURNTABLE_STATUS
//   out: DEPTH_TRIGGER, CLOUD, DEPTH_FRAME_RESENT (with a repeated answer), HEARTBEAT
// Wires the bus to core/scan's CaptureSequencer: it triggers one frame per request (3 tries),
// takes the camera pose from the joint and turntable readings at the frame's exposure time
// through the rig model's kinematics and hand-eye transform (never from the twin), and makes
// the object-frame cloud; every request is answered, a failed one with the reason. Requests are
// idempotent by request_id: a repeat is answered again from the reply cache, and the frame the
// cloud came from is sent again on DEPTH_FRAME_RESENT (the mapping service may have lost it).
#include <fmt/format.h>

#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "bus/bus.hpp"
#include "bus/convert_rig.hpp"
#include "bus/convert_scan.hpp"
#include "bus/reply_cache.hpp"
#include "bus/rig_options.hpp"
#include "bus/service.hpp"
#include "core/base/format.hpp"
#include "core/base/log.hpp"
#include "core/rig/rig.hpp"
#include "core/acquisition/capture_sequencer.hpp"
#include "pbnbv/depth_trigger_t.hpp"

using namespace pbnbv;

namespace {

constexpr std::size_t kCloudsKept = 8;  // answers kept (with their frames) for repeated requests
constexpr std::size_t kFramesKept = 8;  // frames that answered a trigger, until their cloud is made

// A capture's answer and the frame it was made from, sent again for a repeated request.
struct Answer {
  point_cloud_t cloud;
  std::optional<depth_frame_t> frame;
};

class CameraService {
 public:
  // Trigger numbers start at the wall clock, so a restarted service never reuses a number a
  // late frame could still answer.
  CameraService(bus::Bus& bus, const RigModel& rig, bool depth_filter)
      : bus_(bus), rig_(rig), sequencer_(rig, bus::now_utime()) {
    DepthFilterParams filter;
    filter.enabled = depth_filter;
    sequencer_.set_depth_filter(filter);
    bus_.subscribe<arm_status_t>(channels::kArmStatus,
                                 [this](const arm_status_t& s) { sequencer_.on_arm_status(bus::from_msg(s)); });
    if (rig_.has_turntable) {
      bus_.subscribe<turntable_status_t>(channels::kTurntableStatus, [this](const turntable_status_t& s) {
        sequencer_.on_turntable_status(bus::from_msg(s));
      });
    }
    bus_.subscribe<capture_request_t>(channels::kCaptureRequest, [this](const capture_request_t& r) { on_request(r); });
    bus_.subscribe<depth_frame_t>(channels::kDepthFrame, [this](const depth_frame_t& f) { on_frame(f); });
  }

  void tick() { apply(sequencer_.tick(bus::now_s())); }

 private:
  void on_request(const capture_request_t& m) {
    bus_.set_scan(m.scan_id, m.iteration);
    if (const Answer* done = answers_.find({m.scan_id, m.request_id})) {
      bus_.publish(channels::kCloud, done->cloud);  // a repeat: answer again, with the frame it came from
      if (done->frame) bus_.publish(channels::kDepthFrameResent, *done->frame);
      return;
    }
    sequencer_.on_request(bus::from_msg(m));  // a malformed request throws: rejected by the bus
    scan_ = m.scan_id;  // the scan the triggers belong to from now on
  }

  void on_frame(const depth_frame_t& f) {
    if (!sequencer_.awaits_frame(f.trigger_seq)) return;  // not ours (or a late answer): not decoded
    frames_.push_back(f);  // kept with its cloud, to send again with a repeated answer
    if (frames_.size() > kFramesKept) frames_.pop_front();
    DepthFrame frame;
    try {
      frame = bus::from_msg(f);
    } catch (const std::exception& e) {
      apply(sequencer_.on_unusable_frame(f.seq, f.trigger_seq, e.what(), bus::now_s()));
      return;
    }
    apply(sequencer_.on_frame(std::move(frame), bus::now_s()));
  }

  // Publishes what a step of the sequencer asks for.
  void apply(CaptureStep step) {
    for (const std::string& w : step.warnings) log_warn(w);
    if (step.trigger_seq) {
      depth_trigger_t t;
      t.utime = bus::now_utime();
      t.seq = *step.trigger_seq;
      t.scan_id = scan_;
      bus_.publish(channels::kDepthTrigger, t);
    }
    if (step.result) {
      const CaptureResult& c = *step.result;
      if (!c.ok) bus_.note_error(c.message);
      log_info(fmt::format("capture {}: {}, {} points (capture {} s, cloud {} s){}", c.request_id, c.ok ? "ok" : "FAILED",
                           c.points.size(), fixed(c.capture_s, 2), fixed(c.process_s, 2),
                           c.ok && !c.message.empty() ? ": " + c.message : std::string()));
      point_cloud_t out = bus::to_msg(c);
      out.utime = bus::now_utime();
      bus_.publish(channels::kCloud, out);
      Answer a{std::move(out), std::nullopt};
      for (const depth_frame_t& f : frames_) {
        if (f.seq == a.cloud.depth_frame_seq) a.frame = f;
      }
      const std::pair<std::string, int64_t> key{a.cloud.scan_id, a.cloud.request_id};  // before `a` is moved
      answers_.put(key, std::move(a));
    }
    bus_.set_state(sequencer_.busy() ? "capturing" : "idle");
  }

  bus::Bus& bus_;
  const RigModel& rig_;
  CaptureSequencer sequencer_;
  std::string scan_;  // of the request being captured
  bus::ReplyCache<std::pair<std::string, int64_t>, Answer> answers_{kCloudsKept};
  std::deque<depth_frame_t> frames_;  // the last frames that answered a trigger, as received
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbnbv-camera: captures a depth frame per CAPTURE_REQUEST and answers the cloud in the object frame, "
               "posed by the rig's kinematics at exposure",
               "pbnbv-camera"};
  cli::init(app);
  bus::RigOptions rig_options;
  bus::add_rig_options(app, &rig_options);
  bool no_depth_filter = false;
  cli::add_flag(app, "no-depth-filter", &no_depth_filter,
                "make clouds of the frames as they come, flying pixels and speckles included (pbnbv-mapping's "
                "--no-depth-filter must agree)");
  return bus::run_service("camera", app, argc, argv, 5, [&](bus::Bus& bus) -> std::function<void()> {
    auto rig = std::make_shared<RigModel>(bus::load_rig(rig_options));
    auto service = std::make_shared<CameraService>(bus, *rig, !no_depth_filter);
    log_info("ready: hand-eye and kinematics from " + rig->model_path);
    return [rig, service] { service->tick(); };
  });
}
