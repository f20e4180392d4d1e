#pragma once
// The camera service's sequencing, without a bus: capture requests are queued and served one at
// a time; each is a DEPTH_TRIGGER with a fresh sequence number, triggered again every
// kCaptureRetriggerS while no frame answers (a frame lost on the bus costs about a second, not the
// request's timeout), when the frame was exposed before the request's not_before_utime and when
// no arm or turntable reading lies within kCaptureReadingMatchUs of its exposure (statuses lost on
// a flooded or lossy bus; the request then fails at its timeout naming that frame); a frame
// answering any of the request's triggers is taken (a camera slower than kCaptureRetriggerS still
// succeeds). The request fails when no usable frame came within its timeout. The camera pose at exposure comes from the arm
// and turntable readings nearest the frame's exposure time (within kCaptureReadingMatchUs),
// through the rig model's kinematics and hand-eye transform (never from the twin); the frame is
// then back-projected into the object frame, cropped and downsampled. Every request is answered,
// on failure with the reason. Time is the caller's: calls that need it take `now_s`.
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "core/perception/depth_filter.hpp"
#include "core/rig/rig.hpp"
#include "core/scan/messages.hpp"
#include "core/scan/rig_readings.hpp"

namespace pbnbv {

inline constexpr double kCaptureRetriggerS = 1.0;        // trigger again after this long without a frame
inline constexpr int64_t kCaptureReadingMatchUs = 50000; // a reading within 50 ms of exposure
inline constexpr int64_t kCaptureHistoryUs = 5000000;    // readings kept: the last 5 s of rig time
inline constexpr double kCaptureStillRadS = 0.01;        // faster joints blur the pose: warn
inline constexpr double kCaptureReadingWaitS = 1.0;      // wait for readings after the exposure

// What one call asks the service to do: trigger the camera, publish an answer, log warnings.
struct CaptureStep {
  std::optional<int64_t> trigger_seq;  // publish a DEPTH_TRIGGER with this seq
  std::optional<CaptureResult> result;
  std::vector<std::string> warnings;
};

class CaptureSequencer {
 public:
  // `first_trigger_seq`: the first trigger's number; pass one a previous run cannot have used
  // (e.g. the wall clock in microseconds), so a late frame never answers a new trigger.
  CaptureSequencer(const RigModel& rig, int64_t first_trigger_seq);
  // The filter each frame goes through before it becomes a cloud (default: on).
  void set_depth_filter(const DepthFilterParams& p) { filter_ = p; }

  // A status reading; the last kCaptureHistoryUs of rig time are kept.
  void on_arm_status(const ArmReading& reading);
  void on_turntable_status(const TurntableReading& reading);

  // Queues a valid request. A request already queued or in progress is ignored (the service
  // answers one already answered from its cache).
  void on_request(const CaptureRequest& request);

  // Whether a frame answering `trigger_seq` is awaited (any other frame is not ours, or late).
  bool awaits_frame(int64_t trigger_seq) const;

  // A decoded frame. Ignored unless awaited; exposed before the request's not_before_utime:
  // triggers again; otherwise kept until readings on both sides of its exposure are in (or
  // kCaptureReadingWaitS has passed), then made into the answer.
  CaptureStep on_frame(DepthFrame frame, double now_s);
  // An awaited frame that could not be decoded: the request fails naming the frame and why.
  CaptureStep on_unusable_frame(int64_t frame_seq, int64_t trigger_seq, const std::string& why, double now_s);

  // Starts the next queued request, processes a frame whose readings are in, triggers again or
  // fails a request whose timeout passed.
  CaptureStep tick(double now_s);

  bool busy() const { return job_.has_value(); }

 private:
  DepthFilterParams filter_;
  template <class T>
  struct Stamped {
    int64_t utime;
    T value;
    double speed;  // largest joint speed, rad/s
  };
  struct Job {
    CaptureRequest request;
    std::vector<int64_t> triggers;   // every trigger of the request, the latest last
    double t_start = 0, t_trigger = 0, deadline = 0;
    std::optional<DepthFrame> frame;  // received, waiting for the readings at its exposure
    double t_frame = 0;
    std::string last_unusable;  // why the last frame could not be placed ("": none was refused)
  };

  CaptureStep trigger(double now_s);
  CaptureStep process(const DepthFrame& frame);
  // Why a frame exposed at `utime` cannot be placed: no arm (or turntable) reading within
  // kCaptureReadingMatchUs of it; "" when both are there.
  std::string missing_reading(int64_t utime) const;
  CaptureStep fail(const std::string& why, double now_s);
  CaptureResult blank(const CaptureRequest& r) const;

  const RigModel& rig_;
  std::deque<Stamped<Vector6d>> arm_;
  std::deque<Stamped<double>> turntable_;
  std::deque<CaptureRequest> queue_;
  std::optional<Job> job_;
  int64_t next_trigger_seq_;
};

}  // namespace pbnbv
