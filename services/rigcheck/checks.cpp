#include "rigcheck/checks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/base/format.hpp"
#include "core/base/units.hpp"

namespace pbnbv::rigcheck {

namespace {

CheckLine line(const std::string& check, bool passed, const std::string& figure, const std::string& detail = "") {
  return CheckLine{check, passed, figure, detail};
}

double largest_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double d = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) d = std::max(d, std::abs(a[i] - b[i]));
  return d;
}

std::string deg(double rad, int digits = 2) { return fixed(rad_to_deg(rad), digits) + " deg"; }

}  // namespace

DriverSample sample_of(const ArmReading& r, double received_s) {
  return DriverSample{received_s, std::vector<double>(r.joint_position_rad.data(), r.joint_position_rad.data() + 6),
                      r.command_seq, r.mode, r.fault_code, r.fault_command_seq, r.fault};
}

DriverSample sample_of(const TurntableReading& r, double received_s) {
  return DriverSample{received_s, {r.angle_rad}, r.command_seq, r.mode, r.fault_code, r.fault_command_seq, r.fault};
}

CheckLine check_status_rate(const std::string& channel, const std::vector<StatusSample>& samples) {
  const std::string check = channel + " rate";
  if (samples.size() < 2) {
    return line(check, false, fmt::format("{} messages", samples.size()), "too few statuses to measure a rate");
  }
  const std::size_t n = samples.size();
  const double driver_span = 1e-6 * static_cast<double>(samples.back().driver_utime - samples.front().driver_utime);
  const double host_span = samples.back().received_s - samples.front().received_s;
  if (!(driver_span > 0)) {
    return line(check, false, fmt::format("{} messages", n),
                "driver_utime does not advance over the window: no rate can be measured on the driver's clock");
  }
  double driver_gap = 0, host_gap = 0;
  for (std::size_t i = 1; i < n; ++i) {
    driver_gap = std::max(driver_gap, 1e-6 * static_cast<double>(samples[i].driver_utime - samples[i - 1].driver_utime));
    host_gap = std::max(host_gap, samples[i].received_s - samples[i - 1].received_s);
  }
  const double hz = static_cast<double>(n - 1) / driver_span;
  const std::string figure = fixed(hz, 1) + " Hz";
  const std::string measured = fmt::format("{} statuses over {} s of the driver's clock", n, fixed(driver_span, 2));
  if (hz < kMinStatusRateHz) {
    return line(check, false, figure,
                fmt::format("slow status: {} Hz is below the contract's {} Hz ({})", fixed(hz, 1),
                            fixed(kMinStatusRateHz, 0), measured));
  }
  if (driver_gap > kMaxStatusGapS) {
    return line(check, false, figure,
                fmt::format("a hole in the stream: {} ms between two statuses on the driver's clock (at most {} ms; {})",
                            fixed(1e3 * driver_gap, 0), fixed(1e3 * kMaxStatusGapS, 0), measured));
  }
  if (host_gap > kMaxStatusGapS) {
    return line(check, false, figure,
                fmt::format("a stalled stream: nothing received for {} ms (at most {} ms) although the driver's clock "
                            "shows no hole: the host or the network held the statuses back ({})",
                            fixed(1e3 * host_gap, 0), fixed(1e3 * kMaxStatusGapS, 0), measured));
  }
  std::string detail = fmt::format(">= {} Hz on the driver's clock ({})", fixed(kMinStatusRateHz, 0), measured);
  if (driver_gap > kNamedStatusGapS) {
    // A loaded host (a twin that falls behind and catches up) or a busy controller: the motion
    // executor's readings are that old at worst.
    detail += fmt::format("; longest hole {} ms on the driver's clock", fixed(1e3 * driver_gap, 0));
  }
  if (host_span < driver_span * 2.0 / 3.0) {
    detail += fmt::format("; received in bursts: they reached this host within {} s ({} Hz on its clock), so the "
                          "readings the motion executor acts on can be up to a burst old (longest wait {} ms); a "
                          "twin faster than real time (--speed) does this by design",
                          fixed(host_span, 2), fixed(host_span > 0 ? static_cast<double>(n - 1) / host_span : 0, 0),
                          fixed(1e3 * host_gap, 0));
  }
  return line(check, true, figure, detail);
}

CheckLine check_clocks_increase(const std::string& channel, const std::vector<StatusSample>& samples) {
  const std::string check = channel + " clocks increase";
  int utime_back = 0, driver_back = 0;
  int64_t worst_utime = 0, worst_driver = 0;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    const int64_t du = samples[i].utime - samples[i - 1].utime;
    const int64_t dd = samples[i].driver_utime - samples[i - 1].driver_utime;
    if (du <= 0) {
      ++utime_back;
      worst_utime = std::min(worst_utime, du);
    }
    if (dd <= 0) {
      ++driver_back;
      worst_driver = std::min(worst_driver, dd);
    }
  }
  const std::string figure = fmt::format("{} of {} steps", utime_back + driver_back, samples.size() > 0 ? samples.size() - 1 : 0);
  if (utime_back > 0) {
    return line(check, false, figure,
                fmt::format("utime not monotonic: it went backwards or stood still {} times (by up to {} ms)",
                            utime_back, fixed(-worst_utime / 1e3, 1)));
  }
  if (driver_back > 0) {
    return line(check, false, figure,
                fmt::format("driver_utime not monotonic: it went backwards or stood still {} times (by up to {} ms)",
                            driver_back, fixed(-worst_driver / 1e3, 1)));
  }
  return line(check, true, figure, "utime and driver_utime strictly increase");
}

CheckLine check_joint_names(const std::vector<std::string>& names, const RigModel& rig) {
  std::string got;
  for (const auto& n : names) got += (got.empty() ? "" : ",") + n;
  if (names != rig.joint_names) {
    std::string want;
    for (const auto& n : rig.joint_names) want += (want.empty() ? "" : ",") + n;
    return line("ARM_STATUS joint names", false, got.empty() ? "(none)" : got,
                fmt::format("joint names/count differ from the rig file's {} joints ({})", rig.joint_names.size(), want));
  }
  return line("ARM_STATUS joint names", true, got, "as the rig file");
}

CheckLine check_joints_within_limits(const Vector6d& q, const RigModel& rig) {
  for (int i = 0; i < 6; ++i) {
    if (q[i] < rig.q_lower[i] - 1e-6 || q[i] > rig.q_upper[i] + 1e-6) {
      return line("arm joints within limits", false, fmt::format("{} = {}", rig.joint_names[i], deg(q[i])),
                  fmt::format("joint {} reads {}, outside the rig file's limits [{}, {}]", rig.joint_names[i],
                              deg(q[i]), deg(rig.q_lower[i]), deg(rig.q_upper[i])));
    }
  }
  return line("arm joints within limits", true, "6 of 6", "");
}

CheckLine check_trigger_answered(const std::optional<DepthFrame>& frame, int64_t trigger_seq, int frames_seen,
                                 int64_t last_trigger_seq_seen, double answer_s, double deadline_s) {
  const std::string check = "DEPTH_FRAME answers DEPTH_TRIGGER";
  if (frame) return line(check, true, fixed(answer_s, 2) + " s", fmt::format("trigger_seq {} echoed", trigger_seq));
  if (frames_seen > 0) {
    return line(check, false, fmt::format("{} frames", frames_seen),
                fmt::format("no trigger id: {} DEPTH_FRAMEs came but none with trigger_seq {} (last: {}); the camera "
                            "driver must echo the trigger's seq",
                            frames_seen, trigger_seq, last_trigger_seq_seen));
  }
  return line(check, false, "no frame",
              fmt::format("no DEPTH_FRAME in {} s after DEPTH_TRIGGER {}: is the camera driver running and on this "
                          "LCM URL?",
                          fixed(deadline_s, 1), trigger_seq));
}

// "none", or "k1 -0.35 k2 0.15 p1 0.0012 p2 -0.0018 k3 -0.03".
static std::string distortion_text(const LensDistortion& d) {
  if (d.none()) return "none";
  return fmt::format("k1 {} k2 {} p1 {} p2 {} k3 {}", exact(d.k1), exact(d.k2), exact(d.p1), exact(d.p2), exact(d.k3));
}

// The frame's colour image, for the user to see what the pipeline will colour points with (colour
// is optional: never a failure).
static CheckLine colour_line(const DepthFrame& f) {
  if (!f.colour) return line("frame colour", true, "none", "depth only: clouds and meshes come out without colour");
  const ColourImage& c = *f.colour;
  const double baseline_mm = c.depth_T_colour.translation().norm() * 1e3;
  return line("frame colour", true, fmt::format("{}x{}", c.intrinsics.width, c.intrinsics.height),
              fmt::format("fx {} fy {} cx {} cy {}, lens {}, colour sensor {} mm from the depth sensor",
                          exact(c.intrinsics.fx), exact(c.intrinsics.fy), exact(c.intrinsics.cx),
                          exact(c.intrinsics.cy), distortion_text(c.distortion), fixed(baseline_mm, 1)));
}

std::vector<CheckLine> check_frame_against_camera(const DepthFrame& f, const std::optional<RigCamera>& camera) {
  const CameraIntrinsics& k = f.intrinsics;
  const std::string size = fmt::format("{}x{}", k.width, k.height);
  const std::string intrinsics = fmt::format("fx {} fy {} cx {} cy {}", exact(k.fx), exact(k.fy), exact(k.cx), exact(k.cy));
  const std::string range = fmt::format("{}..{} m", exact(f.range.min_m), exact(f.range.max_m));
  const std::string id = f.camera_id.empty() ? "(empty)" : f.camera_id;
  if (!camera) {
    const char* why = "the rig file states no camera (<custom> pbnbv_camera)";
    return {line("frame size", true, size, why), line("frame intrinsics", true, intrinsics, why),
            line("frame lens distortion", true, distortion_text(f.distortion), why),
            line("frame depth range", true, range, why), line("camera id", true, id, why), colour_line(f)};
  }
  const RigCamera& c = *camera;
  std::vector<CheckLine> out;
  if (k.width != c.intrinsics.width || k.height != c.intrinsics.height) {
    out.push_back(line("frame size", false, size,
                       fmt::format("frame size {} disagrees with the rig file's camera {}x{}", size,
                                   c.intrinsics.width, c.intrinsics.height)));
  } else {
    out.push_back(line("frame size", true, size, "as the rig file"));
  }
  // Intrinsics to 0.1 %: a calibration written to the rig file is the one the driver reports.
  const auto off = [](double a, double b) { return std::abs(a - b) > 1e-3 * std::max(std::abs(b), 1.0); };
  if (off(k.fx, c.intrinsics.fx) || off(k.fy, c.intrinsics.fy) || off(k.cx, c.intrinsics.cx) ||
      off(k.cy, c.intrinsics.cy)) {
    out.push_back(line("frame intrinsics", false, intrinsics,
                       fmt::format("intrinsics disagree with the rig file's fx {} fy {} cx {} cy {}",
                                   exact(c.intrinsics.fx), exact(c.intrinsics.fy), exact(c.intrinsics.cx),
                                   exact(c.intrinsics.cy))));
  } else {
    out.push_back(line("frame intrinsics", true, intrinsics, "as the rig file"));
  }
  // The lens: what the frames say they came through is what the rig file says the camera has (a
  // driver that rectifies sends zeros, and its rig file must say none).
  bool lens_off = false;
  for (int i = 0; i < 5; ++i) {
    const double a = f.distortion.coefficients()[static_cast<std::size_t>(i)];
    const double b = c.distortion.coefficients()[static_cast<std::size_t>(i)];
    lens_off = lens_off || std::abs(a - b) > 1e-6 + 1e-3 * std::abs(b);
  }
  if (lens_off) {
    out.push_back(line("frame lens distortion", false, distortion_text(f.distortion),
                       "the frames' lens disagrees with the rig file's pbnbv_camera_distortion " +
                           distortion_text(c.distortion) + ": the images would be undistorted with the wrong model"));
  } else {
    out.push_back(line("frame lens distortion", true, distortion_text(f.distortion), "as the rig file"));
  }
  if (off(f.range.min_m, c.range.min_m) || off(f.range.max_m, c.range.max_m)) {
    out.push_back(line("frame depth range", false, range,
                       fmt::format("depth range disagrees with the rig file's {}..{} m", exact(c.range.min_m),
                                   exact(c.range.max_m))));
  } else {
    out.push_back(line("frame depth range", true, range, "as the rig file"));
  }
  if (!c.id.empty() && f.camera_id != c.id) {
    out.push_back(line("camera id", false, id, "camera id differs from the rig file's " + c.id + ": another camera?"));
  } else {
    out.push_back(line("camera id", true, id, c.id.empty() ? "the rig file names none" : "as the rig file"));
  }
  out.push_back(colour_line(f));
  return out;
}

CheckLine check_depth_within_range(const DepthFrame& f) {
  std::size_t valid = 0, outside = 0;
  for (const float z : f.depth_m) {
    if (!(z > 0) || !std::isfinite(z)) continue;
    ++valid;
    if (z < f.range.min_m || z > f.range.max_m) ++outside;
  }
  const std::string check = "frame depths within its range";
  const std::string figure = fmt::format("{} of {} px outside", outside, valid);
  if (valid == 0) {
    return line(check, true, "0 valid px",
                fmt::format("no return within {}..{} m: nothing to compare (an empty scene; or is the lens covered?)",
                            exact(f.range.min_m), exact(f.range.max_m)));
  }
  // A few pixels at the range's edges round outside it; a wrong unit moves most of them.
  if (outside > valid / 100) {
    return line(check, false, figure,
                fmt::format("{} % of the depths lie outside the frame's {}..{} m (the contract reports them as 0): "
                            "wrong depth unit?",
                            fixed(100.0 * outside / valid, 1), exact(f.range.min_m), exact(f.range.max_m)));
  }
  return line(check, true, figure, "");
}

CheckLine check_exposure(const DepthFrame& f, int64_t status_before_utime, int64_t status_after_utime) {
  const std::string check = "exposure stamps on the status clock";
  const int64_t start = f.exposure_start_utime, end = f.exposure_start_utime + f.exposure_us;
  const int64_t slack = static_cast<int64_t>(kExposureSlackS * 1e6);
  const std::string figure = fmt::format("{} ms after the trigger", fixed((start - status_before_utime) / 1e3, 1));
  if (f.exposure_us < 0 || f.utime < start - 1 || f.utime > end + 1) {
    return line(check, false, figure,
                fmt::format("exposure inconsistent: utime {} is not within the exposure [{}, {} + {} us]", f.utime,
                            start, start, f.exposure_us));
  }
  if (end > status_after_utime + slack) {
    return line(check, false, figure,
                fmt::format("late exposure stamps: the exposure ends {} s after the newest status (utime {}) heard "
                            "with the frame",
                            fixed((end - status_after_utime) / 1e6, 3), status_after_utime));
  }
  if (start < status_before_utime - slack) {
    return line(check, false, figure,
                fmt::format("early exposure stamps: the exposure starts {} s before the status preceding the trigger "
                            "(utime {}): another clock?",
                            fixed((status_before_utime - start) / 1e6, 3), status_before_utime));
  }
  return line(check, true, figure, fmt::format("exposure {} us, between the statuses around the trigger", f.exposure_us));
}

CheckLine check_depth_against_geometry(const DepthFrame& f, const RigModel& rig, const Vector6d& q) {
  const std::string check = "depth unit against geometry";
  if (!rig.has_turntable) return line(check, true, "n/a", "the rig file has no turntable top to compare with");
  // The camera in the turntable-top frame (z up along the axis, origin at the top's centre).
  const Pose top_T_camera = rig.world_T_turntable.inverse() * camera_in_world(rig, q);
  const Eigen::Vector3d o = top_T_camera.translation();
  const CameraIntrinsics& k = f.intrinsics;
  std::vector<double> ratios;
  const int step = std::max(1, std::min(k.width, k.height) / 120);
  for (int v = 0; v < k.height; v += step) {
    for (int u = 0; u < k.width; u += step) {
      // Planar depth 1 along this pixel's ray; the ray meets z = 0 at planar depth t.
      const Eigen::Vector3d d = top_T_camera.linear() * back_project(k, u, v, 1.0);
      if (d.z() > -1e-6) continue;
      const double t = -o.z() / d.z();
      if (t <= 0) continue;
      const Eigen::Vector3d hit = o + t * d;
      if (hit.head<2>().norm() > kTurntableProbeRadiusM) continue;
      const float z = f.depth_m[static_cast<std::size_t>(v) * k.width + u];
      if (z > 0 && std::isfinite(z)) ratios.push_back(z / t);
    }
  }
  if (ratios.size() < 10) {
    return line(check, true, "n/a",
                fmt::format("the turntable top near its axis is not in view at this pose ({} px): not compared",
                            ratios.size()));
  }
  std::nth_element(ratios.begin(), ratios.begin() + ratios.size() / 2, ratios.end());
  const double median = ratios[ratios.size() / 2];
  const std::string figure = fmt::format("x{} ({} px)", fixed(median, 3), ratios.size());
  if (std::abs(median - 1) > kDepthRatioTolerance) {
    return line(check, false, figure,
                fmt::format("wrong depth unit: the turntable top reads {} times the depth the rig file's kinematics "
                            "predict (values in another unit than depth_unit_m says?), or the turntable is not empty",
                            fixed(median, 3)));
  }
  return line(check, true, figure, "turntable top at the depth forward kinematics predict");
}

CheckLine check_move(const std::string& check, const std::vector<DriverSample>& samples, int64_t seq,
                     const std::vector<double>& target, double tolerance_rad, double sent_s) {
  bool echoed = false, within = false;
  int64_t last_echo = -1;
  double best = 1e9;
  for (const DriverSample& s : samples) {
    if (s.received_s < sent_s) continue;
    last_echo = s.command_seq;
    if (s.mode == RigMode::kFault && s.fault_command_seq == seq) {
      return line(check, false, "fault", fmt::format("the driver refused command seq {} (fault code {}): {}", seq,
                                                     to_string(s.fault_code), s.fault));
    }
    if (s.command_seq != seq) continue;
    echoed = true;
    const double err = largest_difference(s.position, target);
    best = std::min(best, err);
    if (err > tolerance_rad) continue;
    within = true;
    if (s.mode == RigMode::kSettled || s.mode == RigMode::kIdle) {
      return line(check, true, fmt::format("{} s, error {}", fixed(s.received_s - sent_s, 2), deg(err, 3)),
                  fmt::format("seq {} echoed, reported settled", seq));
    }
  }
  if (!echoed) {
    return line(check, false, "not echoed",
                fmt::format("no seq echo: command_seq never became {} (last {}); a driver echoes the seq of the "
                            "command it accepted",
                            seq, last_echo));
  }
  if (!within) {
    return line(check, false, fmt::format("error {}", deg(best, 3)),
                fmt::format("target not reached within {}", deg(tolerance_rad, 3)));
  }
  return line(check, false, "not settled", "reached the target but never reported settled (mode kModeSettled)");
}

CheckLine check_refused(const std::string& check, const std::vector<DriverSample>& samples, int64_t seq,
                        const std::vector<double>& start) {
  double moved = 0;
  const DriverSample* fault = nullptr;
  for (const DriverSample& s : samples) {
    moved = std::max(moved, largest_difference(s.position, start));
    if (!fault && s.mode == RigMode::kFault && s.fault_command_seq == seq && s.fault_code != RigFault::kNone) {
      fault = &s;
    }
  }
  if (moved > kHoldToleranceRad) {
    return line(check, false, "moved " + deg(moved),
                fmt::format("ignores limits: it moved {} on command seq {}, which it must refuse{}", deg(moved), seq,
                            fault ? "" : " (and reported no fault)"));
  }
  if (!fault) {
    return line(check, false, "no fault",
                fmt::format("command seq {} was neither refused with a fault code nor executed (no kModeFault with "
                            "fault_command_seq {})",
                            seq, seq));
  }
  return line(check, true, std::string(to_string(fault->fault_code)),
              fmt::format("refused, held within {}: {}", deg(moved, 3), fault->fault));
}

std::string format_table(const std::vector<CheckLine>& lines) {
  std::size_t w_check = 5, w_figure = 6;
  for (const CheckLine& l : lines) {
    w_check = std::max(w_check, l.check.size());
    w_figure = std::max(w_figure, l.figure.size());
  }
  std::string out = fmt::format("{:<{}} | {:<4} | {:<{}} | {}\n", "check", w_check, "", "figure", w_figure, "detail");
  out += std::string(w_check, '-') + "-+------+-" + std::string(w_figure, '-') + "-+-------\n";
  for (const CheckLine& l : lines) {
    out += fmt::format("{:<{}} | {:<4} | {:<{}} | {}\n", l.check, w_check, l.passed ? "pass" : "FAIL", l.figure,
                       w_figure, l.detail);
  }
  return out;
}

bool all_passed(const std::vector<CheckLine>& lines) {
  return !lines.empty() && std::all_of(lines.begin(), lines.end(), [](const CheckLine& l) { return l.passed; });
}

}  // namespace pbnbv::rigcheck
