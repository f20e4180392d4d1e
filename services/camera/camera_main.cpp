// pbnbv-camera: the camera service.
//   in:  CAPTURE_REQUEST, DEPTH_FRAME, ARM_STATUS, TURNTABLE_STATUS
//   out: DEPTH_TRIGGER, CLOUD, HEARTBEAT
// Triggers one frame, takes the camera pose from the joint and turntable readings at the
// frame's exposure time through forward kinematics and the hand-eye transform of the rig
// model (never from the twin), back-projects the valid pixels into the object frame, crops
// the turntable and everything outside the working volume, downsamples, and publishes the
// cloud with the pose used. A lost trigger or frame is retried (3 tries), then answered with
// a failed cloud: the requester never waits forever.
#include <deque>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

#include "bus/bus.hpp"
#include "bus/rig_options.hpp"
#include "bus/service.hpp"
#include "bus/convert.hpp"
#include "core/perception/depth_cloud.hpp"
#include "core/base/log.hpp"
#include "core/rig/rig.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/capture_request_t.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/depth_trigger_t.hpp"
#include "pbnbv/point_cloud_t.hpp"
#include "pbnbv/turntable_status_t.hpp"

using namespace pbnbv;

namespace {

constexpr int kTries = 3;
constexpr int64_t kStatusMatchUs = 50000;   // a status reading must be within 50 ms of exposure
constexpr int64_t kHistoryUs = 5000000;     // keep 5 s of readings
constexpr double kStillRadS = 0.01;         // joints faster than this blur the pose: warn
constexpr std::size_t kCloudsKept = 4;

template <class T>
struct Stamped {
  int64_t utime;
  T value;
  double speed;
};

template <class T>
const Stamped<T>* nearest(const std::deque<Stamped<T>>& history, int64_t utime) {
  const Stamped<T>* best = nullptr;
  for (const auto& s : history) {
    if (!best || std::llabs(s.utime - utime) < std::llabs(best->utime - utime)) best = &s;
  }
  return best;
}

struct Capture {
  capture_request_t request;
  int64_t trigger_seq = 0;
  int tries = 0;
  double t_start = 0, t_trigger = 0, deadline = 0;
  std::optional<depth_frame_t> frame;  // received, waiting for the readings at its exposure
  double t_frame = 0;
};

constexpr double kReadingWaitS = 1.0;  // wait this long for readings at/after the exposure

class CameraService {
 public:
  CameraService(bus::Bus& bus, const RigModel& rig) : bus_(bus), rig_(rig) {
    bus_.subscribe<arm_status_t>(channels::kArmStatus, [this](const arm_status_t& s) {
      const Vector6d q = bus::to_vector6(s.joint_position_rad, "ARM_STATUS joint_position_rad");
      const double speed = bus::to_vector6(s.joint_velocity_rad_s, "ARM_STATUS joint_velocity_rad_s").cwiseAbs().maxCoeff();
      push(arm_, {s.utime, q, speed});
    });
    if (rig_.has_turntable) {
      bus_.subscribe<turntable_status_t>(channels::kTurntableStatus, [this](const turntable_status_t& s) {
        bus::require_range(s.angle_rad, -1e6, 1e6, "TURNTABLE_STATUS angle_rad");
        push(turntable_, {s.utime, s.angle_rad, std::abs(s.velocity_rad_s)});
      });
    }
    bus_.subscribe<capture_request_t>(channels::kCaptureRequest, [this](const capture_request_t& r) { on_request(r); });
    bus_.subscribe<depth_frame_t>(channels::kDepthFrame, [this](const depth_frame_t& f) { on_frame(f); });
  }

  void tick() {
    if (job_ && job_->frame) {
      // The pose at exposure needs readings from both sides of it: then the rig is known to
      // have been where it was (and still) when the frame was taken.
      const int64_t t = job_->frame->utime;
      const bool arm_after = !arm_.empty() && arm_.back().utime >= t;
      const bool tt_after = !rig_.has_turntable || (!turntable_.empty() && turntable_.back().utime >= t);
      if ((arm_after && tt_after) || bus::now_s() - job_->t_frame > kReadingWaitS) {
        const depth_frame_t frame = std::move(*job_->frame);  // process() ends the job
        process(frame);
      }
      return;
    }
    if (!job_ && !queue_.empty()) {
      start(queue_.front());
      queue_.pop_front();
    }
    if (job_ && bus::now_s() > job_->deadline) {
      if (job_->tries < kTries) {
        log_warn("no DEPTH_FRAME for trigger " + std::to_string(job_->trigger_seq) + " within " +
                 std::to_string(job_->request.timeout_s) + " s: triggering again");
        trigger();
      } else {
        fail("no DEPTH_FRAME answered " + std::to_string(kTries) + " triggers of " +
             std::to_string(job_->request.timeout_s) + " s each: is the camera driver (or the twin) running?");
      }
    }
  }

 private:
  template <class T>
  void push(std::deque<Stamped<T>>& history, Stamped<T> s) {
    history.push_back(std::move(s));
    while (!history.empty() && history.back().utime - history.front().utime > kHistoryUs) history.pop_front();
  }

  void on_request(const capture_request_t& r) {
    bus_.set_scan(r.scan_id, r.iteration);
    for (const auto& c : done_) {
      if (c.scan_id == r.scan_id && c.request_id == r.request_id) {
        bus_.publish(channels::kCloud, c);  // a repeat: answer again
        return;
      }
    }
    if (job_ && job_->request.scan_id == r.scan_id && job_->request.request_id == r.request_id) return;
    bus::require_range(r.object_z_m, -1.0, 2.0, "CAPTURE_REQUEST object_z_m");
    bus::require_range(r.voxel_m, 0.0, 0.1, "CAPTURE_REQUEST voxel_m");
    bus::require_range(r.ground_clearance_m, 0.0, 0.5, "CAPTURE_REQUEST ground_clearance_m");
    bus::require_range(r.timeout_s, 0.1, 600.0, "CAPTURE_REQUEST timeout_s");
    for (int i = 0; i < 3; ++i) {
      bus::require_range(r.crop_min_m[i], -10, 10, "CAPTURE_REQUEST crop_min_m");
      bus::require_range(r.crop_max_m[i], r.crop_min_m[i], 10, "CAPTURE_REQUEST crop_max_m");
    }
    queue_.push_back(r);
  }

  void start(const capture_request_t& r) {
    job_ = Capture{};
    job_->request = r;
    job_->t_start = bus::now_s();
    bus_.set_state("capturing");
    trigger();
  }

  void trigger() {
    ++job_->tries;
    job_->trigger_seq = ++trigger_seq_;
    job_->t_trigger = bus::now_s();
    job_->deadline = job_->t_trigger + job_->request.timeout_s;
    depth_trigger_t t;
    t.utime = bus::now_utime();
    t.seq = job_->trigger_seq;
    bus_.publish(channels::kDepthTrigger, t);
  }

  void on_frame(const depth_frame_t& f) {
    if (!job_ || f.trigger_seq != job_->trigger_seq) return;  // not ours (or a late answer)
    if (f.utime < job_->request.not_before_utime) {
      log_warn("frame exposed before the rig settled: triggering again");
      trigger();
      return;
    }
    job_->frame = f;
    job_->t_frame = bus::now_s();
    tick();
  }

  void process(const depth_frame_t& f) {
    const double capture_s = job_->t_frame - job_->t_trigger;
    const double t0 = bus::now_s();
    point_cloud_t out = blank(job_->request);
    try {
      const bus::DecodedFrame frame = bus::decode_frame(f);

      const auto* arm = nearest(arm_, f.utime);
      if (!arm || std::llabs(arm->utime - f.utime) > kStatusMatchUs) {
        throw std::runtime_error("no ARM_STATUS within 50 ms of the frame's exposure time (newest reading " +
                                 std::to_string(arm_.empty() ? 0.0 : (f.utime - arm_.back().utime) * 1e-6) +
                                 " s before it)");
      }
      double turntable = 0;
      double turntable_speed = 0;
      if (rig_.has_turntable) {
        const auto* tt = nearest(turntable_, f.utime);
        if (!tt || std::llabs(tt->utime - f.utime) > kStatusMatchUs) {
          throw std::runtime_error("no TURNTABLE_STATUS within 50 ms of the frame's exposure time");
        }
        turntable = tt->value;
        turntable_speed = tt->speed;
      }
      if (arm->speed > kStillRadS || turntable_speed > kStillRadS) {
        log_warn("the rig was moving at exposure (joint speed " + std::to_string(arm->speed) +
                 ", turntable " + std::to_string(turntable_speed) + " rad/s): the pose may be blurred");
      }
      const capture_request_t& r = job_->request;
      const Pose object_T_camera = camera_in_object(rig_, arm->value, turntable, r.object_z_m);
      CloudCrop crop;
      crop.min_m = Eigen::Vector3d(r.crop_min_m[0], r.crop_min_m[1], r.crop_min_m[2]);
      crop.max_m = Eigen::Vector3d(r.crop_max_m[0], r.crop_max_m[1], r.crop_max_m[2]);
      if (rig_.has_turntable) {
        crop.ground_z_m = -r.object_z_m;  // the turntable top in the object frame
        crop.ground_clearance_m = r.ground_clearance_m;
      }
      CloudStats stats;
      const PointCloud cloud = depth_to_object_cloud(frame.depth_m, frame.intrinsics, frame.range, object_T_camera, crop,
                                                     r.voxel_m, &stats);

      out.object_T_camera = bus::to_msg(object_T_camera);
      out.joint_position_rad = bus::to_std(arm->value);
      out.turntable_angle_rad = turntable;
      out.depth_frame_seq = f.seq;
      out.depth_frame_utime = f.utime;
      out.num_valid_pixels = stats.num_valid_pixels;
      out.num_cropped = stats.num_cropped;
      out.voxel_m = r.voxel_m;
      out.num_points = static_cast<int32_t>(cloud.size());
      out.points_m.resize(cloud.size());
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        out.points_m[i] = {cloud[i].x(), cloud[i].y(), cloud[i].z()};
      }
      if (cloud.empty()) {
        out.message = "no points left: " + std::to_string(stats.num_valid_pixels) +
                      " valid pixels, " + std::to_string(stats.num_cropped) + " cropped";
      }
    } catch (const std::exception& e) {
      out.status = point_cloud_t::kFailed;
      out.message = std::string("frame ") + std::to_string(f.seq) + " unusable: " + e.what();
      bus_.note_error(out.message);
    }
    out.capture_s = capture_s;
    out.process_s = bus::now_s() - t0;
    complete(out);
  }

  void fail(const std::string& why) {
    point_cloud_t out = blank(job_->request);
    out.status = point_cloud_t::kFailed;
    out.message = why;
    out.capture_s = bus::now_s() - job_->t_start;
    bus_.note_error(why);
    complete(out);
  }

  void complete(point_cloud_t& out) {
    out.utime = bus::now_utime();
    bus_.publish(channels::kCloud, out);
    std::ostringstream os;
    os << "capture " << out.request_id << ": " << (out.status == point_cloud_t::kOk ? "ok" : "FAILED")
       << ", " << out.num_points << " points (capture " << out.capture_s << " s, cloud " << out.process_s << " s)";
    log_info(os.str());
    done_.push_back(out);
    if (done_.size() > kCloudsKept) done_.pop_front();
    job_.reset();
    bus_.set_state("idle");
  }

  point_cloud_t blank(const capture_request_t& r) const {
    point_cloud_t m;
    m.utime = bus::now_utime();
    m.scan_id = r.scan_id;
    m.iteration = r.iteration;
    m.request_id = r.request_id;
    m.status = point_cloud_t::kOk;
    m.frame = "object";
    m.object_T_camera = bus::to_msg(Pose::Identity());
    m.num_joints = 6;
    m.joint_position_rad.assign(6, 0.0);
    m.turntable_angle_rad = 0;
    m.depth_frame_seq = -1;
    m.depth_frame_utime = 0;
    m.num_valid_pixels = m.num_cropped = 0;
    m.voxel_m = r.voxel_m;
    m.capture_s = m.process_s = 0;
    m.num_points = 0;
    return m;
  }

  bus::Bus& bus_;
  const RigModel& rig_;
  std::deque<Stamped<Vector6d>> arm_;
  std::deque<Stamped<double>> turntable_;
  std::deque<capture_request_t> queue_;
  std::optional<Capture> job_;
  // Seeded from the clock so a restarted service never reuses a number a late frame could
  // still answer.
  int64_t trigger_seq_ = bus::now_utime();
  std::deque<point_cloud_t> done_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbnbv-camera: captures a depth frame per CAPTURE_REQUEST and answers the cloud in the object frame, "
               "posed by the rig's kinematics at exposure",
               "pbnbv-camera"};
  cli::init(app);
  bus::RigOptions rig_options;
  bus::add_rig_options(app, &rig_options);
  return bus::run_service("camera", app, argc, argv, 5, [&](bus::Bus& bus) -> std::function<void()> {
    auto rig = std::make_shared<RigModel>(bus::load_rig(rig_options));
    auto service = std::make_shared<CameraService>(bus, *rig);
    log_info("ready: hand-eye and kinematics from " + rig->model_path);
    return [rig, service] { service->tick(); };
  });
}
