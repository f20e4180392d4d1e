#include "core/acquisition/capture_sequencer.hpp"

#include "core/perception/depth_filter.hpp"

#include <algorithm>
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "core/base/format.hpp"
#include "core/perception/depth_cloud.hpp"
#include "core/perception/depth_filter.hpp"

namespace pbnbv {

namespace {

// The reading nearest `utime` in a history (nullptr when empty); ties go to the older one.
template <class S>
const S* nearest(const std::deque<S>& history, int64_t utime) {
  const S* best = nullptr;
  for (const S& s : history) {
    if (!best || std::llabs(s.utime - utime) < std::llabs(best->utime - utime)) best = &s;
  }
  return best;
}

// How far the nearest reading is from the exposure, for a failure message.
template <class S>
std::string distance_text(const S* nearest_reading, int64_t utime) {
  if (!nearest_reading) return "none received";
  return fmt::format("the nearest is {} ms away", fixed(std::llabs(nearest_reading->utime - utime) * 1e-3, 3));
}

// Appends a reading and drops those more than kCaptureHistoryUs older than it.
template <class S>
void push(std::deque<S>& history, S s) {
  history.push_back(std::move(s));
  while (history.back().utime - history.front().utime > kCaptureHistoryUs) history.pop_front();
}

}  // namespace

CaptureSequencer::CaptureSequencer(const RigModel& rig, int64_t first_trigger_seq)
    : rig_(rig), next_trigger_seq_(first_trigger_seq) {}

void CaptureSequencer::on_arm_status(const ArmReading& r) {
  push(arm_, Stamped<Vector6d>{r.utime, r.joint_position_rad, r.joint_velocity_rad_s.cwiseAbs().maxCoeff()});
}

void CaptureSequencer::on_turntable_status(const TurntableReading& r) {
  push(turntable_, Stamped<double>{r.utime, r.angle_rad, std::abs(r.velocity_rad_s)});
}

void CaptureSequencer::on_request(const CaptureRequest& r) {
  const auto same = [&](const CaptureRequest& q) { return q.scan_id == r.scan_id && q.request_id == r.request_id; };
  if (job_ && same(job_->request)) return;
  for (const CaptureRequest& q : queue_) {
    if (same(q)) return;
  }
  queue_.push_back(r);
}

bool CaptureSequencer::awaits_frame(int64_t trigger_seq) const {
  return job_ && !job_->frame &&
         std::find(job_->triggers.begin(), job_->triggers.end(), trigger_seq) != job_->triggers.end();
}

// A new trigger for the job: a fresh sequence number (the job's deadline stays).
CaptureStep CaptureSequencer::trigger(double now_s) {
  job_->triggers.push_back(next_trigger_seq_++);
  job_->t_trigger = now_s;
  CaptureStep step;
  step.trigger_seq = job_->triggers.back();
  return step;
}

CaptureStep CaptureSequencer::on_frame(DepthFrame frame, double now_s) {
  if (!awaits_frame(frame.trigger_seq)) return {};  // not ours, or a late answer
  if (frame.utime < job_->request.not_before_utime) {
    CaptureStep step = trigger(now_s);
    step.warnings.push_back(fmt::format("frame {} exposed {} s before the rig settled: triggering again", frame.seq,
                                        fixed((job_->request.not_before_utime - frame.utime) * 1e-6, 3)));
    return step;
  }
  job_->frame = std::move(frame);
  job_->t_frame = now_s;
  return tick(now_s);
}

CaptureStep CaptureSequencer::on_unusable_frame(int64_t frame_seq, int64_t trigger_seq, const std::string& why,
                                                double now_s) {
  if (!awaits_frame(trigger_seq)) return {};
  CaptureStep step;
  step.result = blank(job_->request);
  step.result->message = fmt::format("frame {} unusable: {}", frame_seq, why);
  step.result->capture_s = now_s - job_->t_trigger;
  job_.reset();
  return step;
}

CaptureStep CaptureSequencer::tick(double now_s) {
  if (job_ && job_->frame) {
    // The pose at exposure needs readings from both sides of it: then the rig is known to
    // have been where it was (and still) when the frame was taken.
    const int64_t t = job_->frame->utime;
    const bool arm_after = !arm_.empty() && arm_.back().utime >= t;
    const bool turntable_after = !rig_.has_turntable || (!turntable_.empty() && turntable_.back().utime >= t);
    if ((arm_after && turntable_after) || now_s - job_->t_frame > kCaptureReadingWaitS) {
      const DepthFrame frame = std::move(*job_->frame);
      job_->frame.reset();
      // Statuses lost around the exposure (a flooded or lossy bus): another frame while the
      // request's deadline allows, not a lost view. (A lost message is asked for again.)
      const std::string missing = missing_reading(frame.utime);
      if (!missing.empty() && now_s < job_->deadline) {
        job_->last_unusable = fmt::format("frame {} unusable: {}", frame.seq, missing);
        CaptureStep step = trigger(now_s);
        step.warnings.push_back(job_->last_unusable + ": triggering again");
        return step;
      }
      return process(frame);  // ends the job
    }
    return {};
  }
  if (!job_ && !queue_.empty()) {
    job_ = Job{};
    job_->request = queue_.front();
    job_->t_start = now_s;
    job_->deadline = now_s + job_->request.timeout_s;
    queue_.pop_front();
    return trigger(now_s);
  }
  if (job_ && now_s > job_->deadline) {
    if (!job_->last_unusable.empty()) {
      return fail(fmt::format("no usable DEPTH_FRAME answered {} triggers within {} s (the last: {})",
                              job_->triggers.size(), exact(job_->request.timeout_s), job_->last_unusable),
                  now_s);
    }
    return fail(fmt::format("no usable DEPTH_FRAME answered {} triggers within {} s: is the camera driver (or the twin) "
                            "running?",
                            job_->triggers.size(), exact(job_->request.timeout_s)),
                now_s);
  }
  if (job_ && now_s - job_->t_trigger >= kCaptureRetriggerS) {
    const int64_t late = job_->triggers.back();
    CaptureStep step = trigger(now_s);
    step.warnings.push_back(
        fmt::format("no DEPTH_FRAME for trigger {} within {} s: triggering again", late, exact(kCaptureRetriggerS)));
    return step;
  }
  return {};
}

std::string CaptureSequencer::missing_reading(int64_t utime) const {
  const auto* arm = nearest(arm_, utime);
  if (!arm || std::llabs(arm->utime - utime) > kCaptureReadingMatchUs) {
    return "no ARM_STATUS within 50 ms of the frame's exposure time (" + distance_text(arm, utime) + ")";
  }
  if (rig_.has_turntable) {
    const auto* tt = nearest(turntable_, utime);
    if (!tt || std::llabs(tt->utime - utime) > kCaptureReadingMatchUs) {
      return "no TURNTABLE_STATUS within 50 ms of the frame's exposure time (" + distance_text(tt, utime) + ")";
    }
  }
  return "";
}

// The answer to the job from its frame: the pose from the readings nearest the exposure, the
// object-frame cloud; a failure naming the frame and why when there is no reading to use.
CaptureStep CaptureSequencer::process(const DepthFrame& f) {
  CaptureStep step;
  const auto t0 = std::chrono::steady_clock::now();
  const CaptureRequest& r = job_->request;
  CaptureResult out = blank(r);
  out.capture_s = job_->t_frame - job_->t_trigger;
  try {
    if (const std::string missing = missing_reading(f.utime); !missing.empty()) throw std::runtime_error(missing);
    const auto* arm = nearest(arm_, f.utime);
    double turntable = 0;
    double turntable_speed = 0;
    if (rig_.has_turntable) {
      const auto* tt = nearest(turntable_, f.utime);
      turntable = tt->value;
      turntable_speed = tt->speed;
    }
    if (arm->speed > kCaptureStillRadS || turntable_speed > kCaptureStillRadS) {
      step.warnings.push_back(fmt::format("the rig was moving at exposure (joint speed {}, turntable {} rad/s): "
                                          "the pose may be blurred",
                                          fixed(arm->speed, 3), fixed(turntable_speed, 3)));
    }
    const Pose object_T_camera = camera_in_object(rig_, arm->value, turntable, r.object_z_m);
    CloudCrop crop;
    crop.volume_m = r.crop;
    if (rig_.has_turntable) {
      crop.ground_z_m = -r.object_z_m;  // the turntable top in the object frame
      crop.ground_clearance_m = r.ground_clearance_m;
    }
    // Flying pixels and speckles out first (the mapping service removes the same from the frame).
    std::vector<float> depth = f.depth_m;
    const DepthFilterStats filtered = filter_depth(depth, f.intrinsics, filter_);
    CloudStats stats;
    out.points = depth_to_object_cloud(depth, f.intrinsics, f.range, object_T_camera, crop, r.voxel_m, &stats);
    out.normals = depth_normals(out.points, depth, f.intrinsics, object_T_camera);
    if (f.colour) out.colours = point_colours(out.points, *f.colour, object_T_camera);
    out.object_T_camera = object_T_camera;
    out.joint_position_rad = arm->value;
    out.turntable_angle_rad = turntable;
    out.depth_frame_seq = f.seq;
    out.depth_frame_utime = f.utime;
    out.num_valid_pixels = stats.num_valid_pixels;
    out.num_cropped = stats.num_cropped;
    out.ground_points = stats.ground_points;
    out.ground_z_m = crop.ground_z_m > -1e8 ? crop.ground_z_m : 0;
    out.ground_abc = stats.ground_abc;
    out.ground_sigma_m = stats.ground_sigma_m;
    out.ok = true;
    if (out.points.empty()) {
      out.message = fmt::format("no points left: {} valid pixels, {} cropped", stats.num_valid_pixels,
                                stats.num_cropped);
    } else if (filtered.flying + filtered.speckle_pixels > 0) {
      out.message = fmt::format("depth filter: {} flying pixels and {} pixels in {} speckles removed", filtered.flying,
                                filtered.speckle_pixels, filtered.speckles);
    }
  } catch (const std::exception& e) {
    out = blank(r);
    out.capture_s = job_->t_frame - job_->t_trigger;
    out.message = fmt::format("frame {} unusable: {}", f.seq, e.what());
  }
  out.process_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  job_.reset();
  step.result = std::move(out);
  return step;
}

// Ends the job with a failed answer.
CaptureStep CaptureSequencer::fail(const std::string& why, double now_s) {
  CaptureResult out = blank(job_->request);
  out.message = why;
  out.capture_s = now_s - job_->t_start;
  job_.reset();
  CaptureStep step;
  step.result = std::move(out);
  return step;
}

// A failed answer to `r` with nothing in it yet.
CaptureResult CaptureSequencer::blank(const CaptureRequest& r) const {
  CaptureResult m;
  m.scan_id = r.scan_id;
  m.iteration = r.iteration;
  m.request_id = r.request_id;
  m.ok = false;
  m.voxel_m = r.voxel_m;
  return m;
}

}  // namespace pbnbv
