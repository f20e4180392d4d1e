// `pbnbv calibrate` (commands.hpp): hand-eye and turntable calibration with the rig's drivers on
// the bus (the twin, started separately, or the real rig):
//   in:  ARM_STATUS, TURNTABLE_STATUS, DEPTH_FRAME
//   out: ARM_COMMAND, TURNTABLE_COMMAND, DEPTH_TRIGGER
// The arm looks at the calibration sphere from `views` poses around it (varied direction,
// distance, roll and place in the image; the turntable brings each to the arm), through the
// motion executor's and the camera service's sequencing run in this process (MotionSequencer,
// CaptureSequencer: re-sent commands, settle, deadlines); the sphere is fitted in each frame and
// the rig solved (core/rig/calibration.hpp).
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "bus/bus.hpp"
#include "bus/convert_rig.hpp"
#include "bus/rig_commands.hpp"
#include "core/base/format.hpp"
#include "core/base/signals.hpp"
#include "core/base/units.hpp"
#include "core/io/json.hpp"
#include "core/rig/calibration.hpp"
#include "core/acquisition/capture_sequencer.hpp"
#include "core/acquisition/motion_sequencer.hpp"
#include "launcher/commands.hpp"
#include "pbnbv/depth_trigger_t.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv::launcher {

namespace {

constexpr const char* kCalibrationScan = "calibrate";  // the scan id of our commands and triggers
constexpr int kMinFrames = 6;
constexpr double kMoveTimeoutS = 60;
constexpr double kCaptureTimeoutS = 10;
constexpr double kDeg = kPi / 180;

// The calibration views: camera poses in the object (mount) frame around the sphere's centre s.
// Directions cover the azimuths (the turntable turns each to the arm) at three elevations and
// distances; the sphere is put off the image centre and the camera rolled so that the hand-eye
// rotation is seen about every axis.
std::vector<Pose> calibration_views(const CalibrationSphere& sphere, int n) {
  const Eigen::Vector3d s = sphere.centre_in_mount();
  const double elevations_deg[3] = {35, 55, 70};
  const double distances_m[3] = {0.45, 0.55, 0.4};
  const double image_offsets[5][2] = {{0, 0}, {0.22, 0.12}, {-0.22, 0.12}, {-0.22, -0.12}, {0.22, -0.12}};
  const double rolls_deg[3] = {0, 25, -25};
  std::vector<Pose> views;
  for (int i = 0; i < n; ++i) {
    const double azimuth = 2 * kPi * i / n;
    const double e = elevations_deg[i % 3] * kDeg;
    const double d = distances_m[(i / 3) % 3];
    const Eigen::Vector3d eye = s + d * Eigen::Vector3d(std::cos(azimuth) * std::cos(e), std::sin(azimuth) * std::cos(e), std::sin(e));
    const Pose centred = look_at_z_up(eye, s);
    const double* off = image_offsets[i % 5];
    // Look past the sphere so it shows at (off[0], off[1]) x distance from the image centre.
    const Eigen::Vector3d target = s - d * (off[0] * centred.linear().col(0) + off[1] * centred.linear().col(1));
    Pose view = look_at_z_up(eye, target);
    view.linear() = view.linear() * Eigen::AngleAxisd(rolls_deg[(i / 5) % 3] * kDeg, Eigen::Vector3d::UnitZ());
    views.push_back(view);
  }
  return views;
}

// The rig's drivers and this process's two sequencers on the bus.
class CalibrationRun {
 public:
  CalibrationRun(bus::Bus& bus, const RigModel& rig)
      : bus_(bus), motion_(rig, bus::now_utime()), capture_(rig, bus::now_utime() + 1) {
    bus_.subscribe<arm_status_t>(channels::kArmStatus, [this](const arm_status_t& s) {
      const ArmReading r = bus::from_msg(s);
      motion_.on_arm_status(r, bus::now_s());
      capture_.on_arm_status(r);
      ++arm_statuses_;
    });
    bus_.subscribe<turntable_status_t>(channels::kTurntableStatus, [this](const turntable_status_t& s) {
      const TurntableReading r = bus::from_msg(s);
      motion_.on_turntable_status(r, bus::now_s());
      capture_.on_turntable_status(r);
      ++turntable_statuses_;
    });
    bus_.subscribe<depth_frame_t>(channels::kDepthFrame, [this](const depth_frame_t& f) {
      if (!capture_.awaits_frame(f.trigger_seq)) return;
      DepthFrame frame;
      try {
        frame = bus::from_msg(f);
      } catch (const std::exception& e) {
        apply(capture_.on_unusable_frame(f.seq, f.trigger_seq, e.what(), bus::now_s()));
        return;
      }
      apply(capture_.on_frame(std::move(frame), bus::now_s()));
    });
  }

  // Waits for both drivers' statuses; throws naming the silent ones.
  void wait_for_drivers(double wait_s) {
    const double deadline = bus::now_s() + wait_s;
    while ((arm_statuses_ == 0 || turntable_statuses_ == 0) && bus::now_s() < deadline && !stop_requested()) {
      bus_.spin_once(20);
    }
    std::vector<std::string> silent;
    if (arm_statuses_ == 0) silent.push_back("ARM_STATUS (the arm driver)");
    if (turntable_statuses_ == 0) silent.push_back("TURNTABLE_STATUS (the turntable driver)");
    if (!silent.empty()) {
      std::string what = silent[0] + (silent.size() > 1 ? " and " + silent[1] : "");
      throw std::runtime_error("no " + what + " within " + fixed(wait_s, 1) + " s on " + bus::lcm_url() +
                               ": start the rig's drivers or the twin (pbnbv-twin --calibration-sphere R) on this bus");
    }
  }

  // A move; when the drivers' statuses are stale (a driver busy or restarting: the twin sends
  // none while it renders), waits up to wait_s for them and asks again.
  MoveResult move(MoveRequest request, double wait_s) {
    MoveResult r = move_once(request);
    const double deadline = bus::now_s() + wait_s;
    while (r.status == MoveStatus::kRigSilent && bus::now_s() < deadline && !stop_requested()) {
      const long arm = arm_statuses_, turntable = turntable_statuses_;
      while ((arm_statuses_ == arm || turntable_statuses_ == turntable) && bus::now_s() < deadline && !stop_requested()) {
        bus_.spin_once(20);
      }
      ++request.request_id;
      r = move_once(request);
    }
    return r;
  }

  CaptureResult capture(const CaptureRequest& request) {
    capture_result_.reset();
    capture_.on_request(request);
    while (!capture_result_ && !stop_requested()) {
      bus_.spin_once(5);
      apply(capture_.tick(bus::now_s()));
    }
    if (!capture_result_) throw std::runtime_error("interrupted");
    return *capture_result_;
  }

 private:
  MoveResult move_once(const MoveRequest& request) {
    move_result_.reset();
    apply(motion_.on_request(request, bus::now_s()));
    while (!move_result_ && !stop_requested()) {
      bus_.spin_once(5);
      apply(motion_.tick(bus::now_s()));
    }
    if (!move_result_) throw std::runtime_error("interrupted");
    return *move_result_;
  }

  void apply(const MotionStep& step) {
    for (const std::string& w : step.warnings) std::cerr << "pbnbv calibrate: " << w << std::endl;
    bus::publish_rig_commands(bus_, step.arm_command, step.turntable_command, kCalibrationScan);
    if (step.result) move_result_ = step.result;
  }

  void apply(CaptureStep step) {
    for (const std::string& w : step.warnings) std::cerr << "pbnbv calibrate: " << w << std::endl;
    if (step.trigger_seq) {
      depth_trigger_t t;
      t.utime = bus::now_utime();
      t.seq = *step.trigger_seq;
      t.scan_id = kCalibrationScan;
      bus_.publish(channels::kDepthTrigger, t);
    }
    if (step.result) capture_result_ = std::move(step.result);
  }

  bus::Bus& bus_;
  MotionSequencer motion_;
  CaptureSequencer capture_;
  long arm_statuses_ = 0, turntable_statuses_ = 0;
  std::optional<MoveResult> move_result_;
  std::optional<CaptureResult> capture_result_;
};

std::string default_out() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", std::localtime(&t));
  return std::string("out/calibration-") + buf;
}

json vec6_json(const Vector6d& v) { return json(std::vector<double>(v.data(), v.data() + 6)); }

// A pose difference a -> b as millimetres and degrees.
std::pair<double, double> mm_deg(const Pose& a, const Pose& b) {
  return {(a.translation() - b.translation()).norm() * 1e3, rotation_angle_rad(a.linear(), b.linear()) / kDeg};
}

// View i of the calibration (0-based; view i + 1 in its record, console and report): moved to, captured, the sphere fitted in the camera frame; `frame`
// records what happened (and why a view was skipped). Throws when the rig's drivers or the camera
// fell silent.
std::optional<SphereObservation> observe_view(CalibrationRun& run, const CalibrateOptions& o, const Pose& view,
                                              std::size_t i, int64_t& request_id, json& frame) {
  const Eigen::Vector3d s = o.sphere.centre_in_mount();
  MoveRequest m;
  m.scan_id = kCalibrationScan;
  m.iteration = static_cast<int>(i);
  m.request_id = ++request_id;
  m.object_T_camera = view;
  m.speed_scale = o.speed_scale;
  m.timeout_s = kMoveTimeoutS;
  const MoveResult moved = run.move(m, o.status_wait_s);
  if (moved.status == MoveStatus::kRigSilent) {
    throw std::runtime_error("view " + std::to_string(i + 1) + ": the rig's drivers fell silent for more than " +
                             fixed(o.status_wait_s, 1) + " s (--status-wait): " + moved.reason);
  }
  if (moved.status != MoveStatus::kReached) {
    std::cerr << "pbnbv calibrate: view " << i + 1 << " skipped: " << to_string(moved.status) << ": " << moved.reason
              << std::endl;
    frame["skipped"] = std::string(to_string(moved.status)) + ": " + moved.reason;
    return std::nullopt;
  }
  CaptureRequest c;
  c.scan_id = kCalibrationScan;
  c.iteration = static_cast<int>(i);
  c.request_id = ++request_id;
  c.not_before_utime = moved.settled_utime;
  // Only what lies near the sphere as the model places it (its errors are millimetres), above
  // the platter.
  const double margin = o.sphere.radius_m + 0.05;
  c.crop = Eigen::AlignedBox3d(s - Eigen::Vector3d::Constant(margin), s + Eigen::Vector3d::Constant(margin));
  c.ground_clearance_m = 0.01;
  c.timeout_s = kCaptureTimeoutS;
  const CaptureResult cap = run.capture(c);
  if (!cap.ok) {
    if (cap.message.find("no frame") != std::string::npos || cap.depth_frame_seq < 0) {
      throw std::runtime_error("view " + std::to_string(i + 1) + ": no depth frame (DEPTH_FRAME from the camera driver): " +
                               cap.message);
    }
    std::cerr << "pbnbv calibrate: view " << i + 1 << " skipped: the sphere is not in the frame (" << cap.message << ")"
              << std::endl;
    frame["skipped"] = "capture: " + cap.message;
    return std::nullopt;
  }
  // Back to the camera frame: the points were placed with cap.object_T_camera.
  const Pose camera_T_object = cap.object_T_camera.inverse();
  std::vector<Eigen::Vector3d> points;
  points.reserve(cap.points.size());
  for (const Eigen::Vector3f& p : cap.points) points.push_back(camera_T_object * p.cast<double>());
  const SphereFit fit = fit_sphere_known_radius(points, o.sphere.radius_m);
  frame["joint_position_rad"] = vec6_json(cap.joint_position_rad);
  frame["turntable_angle_rad"] = cap.turntable_angle_rad;
  frame["depth_frame_seq"] = cap.depth_frame_seq;
  frame["points"] = points.size();
  frame["fit"] = {{"ok", fit.ok}, {"inliers", fit.inliers}, {"rms_mm", fit.rms_m * 1e3}, {"cap_spread", fit.cap_spread}};
  if (!fit.ok) {
    std::cerr << "pbnbv calibrate: view " << i + 1 << " skipped: the sphere is not seen (" << fit.why << ")" << std::endl;
    frame["skipped"] = "sphere fit: " + fit.why;
    return std::nullopt;
  }
  frame["fit"]["centre_in_camera_m"] = to_json(fit.centre);
  std::cout << fmt::format("  view {:2}: turntable {:7} deg, sphere fitted to {} points (rms {} mm)", i + 1,
                           fixed(cap.turntable_angle_rad / kDeg, 1), fit.inliers, fixed(fit.rms_m * 1e3, 3))
            << std::endl;
  return SphereObservation{cap.joint_position_rad, cap.turntable_angle_rad, fit.centre};
}

// The corrections the calibration found, as its outputs report them.
struct Corrections {
  double mount_mm = 0, mount_deg = 0;  // hand-eye: model -> calibrated
  double zero_deg = 0;                 // turntable zero
  double tilt_deg = 0;                 // the measured axis against the model's (reported, not in the file)
  Eigen::Vector3d axis_offset_m = Eigen::Vector3d::Zero();
  int used = 0;                        // frames used (the others: outliers)
};

Corrections corrections_of(const RigModel& rig, const RigCalibration& cal) {
  Corrections c;
  std::tie(c.mount_mm, c.mount_deg) = mm_deg(rig.flange_T_camera, cal.flange_T_camera);
  c.zero_deg = (cal.turntable_zero_rad - rig.turntable_zero_rad) / kDeg;
  c.tilt_deg = std::acos(std::clamp(cal.axis_direction_world.dot(rig.world_T_turntable.linear().col(2)), -1.0, 1.0)) / kDeg;
  c.axis_offset_m = cal.axis_point_world - rig.world_T_turntable.translation();
  c.used = static_cast<int>(std::count(cal.used.begin(), cal.used.end(), true));
  return c;
}

// Each fitted frame's sphere-centre residuals before and after, and whether the solve used it.
void add_residuals(const RigCalibration& cal, json& frames) {
  for (std::size_t k = 0, f = 0; f < frames.size(); ++f) {
    if (!frames[f].contains("observation")) continue;
    frames[f]["residual_before_mm"] = cal.residual_before_m[k] * 1e3;
    frames[f]["residual_after_mm"] = cal.residual_after_m[k] * 1e3;
    frames[f]["used"] = static_cast<bool>(cal.used[k]);
    ++k;
  }
}

// calibration.json: the corrections, the axis as measured and every frame with its residuals.
json calibration_json(const CalibrateOptions& o, const RigModel& rig, const RigModel& calibrated, const RigCalibration& cal,
                      const Corrections& c, const CalibrationSolveOptions& so, const fs::path& rig_out,
                      std::size_t num_views, std::size_t num_observations, const json& frames) {
  json j;
  j["rig_model"] = o.rig_model;
  j["calibrated_rig_model"] = rig_out.string();
  j["sphere"] = {{"radius_m", o.sphere.radius_m}, {"offset_m", o.sphere.offset_m},
                 {"centre_in_mount_m", to_json(o.sphere.centre_in_mount())}};
  j["views"] = num_views;
  j["frames_fitted"] = num_observations;
  j["frames_used"] = c.used;
  j["fit_axis"] = so.fit_axis;
  j["flange_T_camera"] = to_json(calibrated.flange_T_camera);
  j["model_flange_T_camera"] = to_json(rig.flange_T_camera);
  j["hand_eye_correction"] = {{"translation_mm", c.mount_mm}, {"rotation_deg", c.mount_deg},
                              {"model_T_calibrated", to_json(rig.flange_T_camera.inverse() * cal.flange_T_camera)}};
  j["turntable_zero_rad"] = calibrated.turntable_zero_rad;
  j["model_turntable_zero_rad"] = rig.turntable_zero_rad;
  j["turntable_zero_correction_deg"] = c.zero_deg;
  j["turntable_axis"] = {{"direction_world", to_json(cal.axis_direction_world)},
                         {"point_world_m", to_json(cal.axis_point_world)},
                         {"tilt_from_model_deg", c.tilt_deg},
                         {"offset_from_model_mm", to_json(Eigen::Vector3d(c.axis_offset_m * 1e3))},
                         {"in_rig_file", false}};
  j["rms_before_mm"] = cal.rms_before_m * 1e3;
  j["rms_after_mm"] = cal.rms_after_m * 1e3;
  j["iterations"] = cal.iterations;
  j["frames"] = frames;
  return j;
}

// report.md: the corrections and a row per view.
std::string calibration_report(const CalibrateOptions& o, const RigCalibration& cal, const Corrections& c,
                               const RigModel& calibrated, const fs::path& rig_out, std::size_t num_views,
                               std::size_t num_observations, const json& frames) {
  std::ostringstream r;
  r << "# Calibration of " << o.rig_model << "\n\n"
    << "Sphere of radius " << fixed(o.sphere.radius_m * 1e3, 1) << " mm, centre " << fixed(o.sphere.offset_m * 1e3, 1)
    << " mm from the turntable axis on the platter's +x axis. " << num_observations << " of " << num_views
    << " views fitted, " << c.used << " used.\n\n"
    << "| correction | value |\n|---|---|\n"
    << "| hand-eye (camera mount) | " << fixed(c.mount_mm, 3) << " mm, " << fixed(c.mount_deg, 4) << " deg |\n"
    << "| turntable zero | " << fixed(c.zero_deg, 4) << " deg (reading at the platter's zero: "
    << fixed(calibrated.turntable_zero_rad / kDeg, 4) << " deg) |\n"
    << "| turntable axis tilt (reported, not in the file) | " << fixed(c.tilt_deg, 4) << " deg |\n"
    << "| turntable axis offset (reported, not in the file) | " << fixed(c.axis_offset_m.x() * 1e3, 3) << ", "
    << fixed(c.axis_offset_m.y() * 1e3, 3) << ", " << fixed(c.axis_offset_m.z() * 1e3, 3) << " mm |\n"
    << "| sphere centre residual, rms | before " << fixed(cal.rms_before_m * 1e3, 3) << " mm, after "
    << fixed(cal.rms_after_m * 1e3, 3) << " mm |\n\n"
    << "| view | turntable, deg | fit points | fit rms, mm | residual before, mm | after, mm | used |\n"
    << "|---|---|---|---|---|---|---|\n";
  for (const json& f : frames) {
    if (!f.contains("observation")) {
      r << "| " << f["view"].get<int>() << " | | | | | | skipped: " << f.value("skipped", std::string()) << " |\n";
      continue;
    }
    r << "| " << f["view"].get<int>() << " | " << fixed(f["turntable_angle_rad"].get<double>() / kDeg, 2) << " | "
      << f["fit"]["inliers"].get<int>() << " | " << fixed(f["fit"]["rms_mm"].get<double>(), 3) << " | "
      << fixed(f["residual_before_mm"].get<double>(), 3) << " | " << fixed(f["residual_after_mm"].get<double>(), 3)
      << " | " << (f["used"].get<bool>() ? "yes" : "no (outlier)") << " |\n";
  }
  r << "\nThe calibrated rig file " << rig_out.string()
    << " is the input file with the camera_optical body's pose and pbnbv_turntable_zero replaced. "
    << "The world frame is the rig file's (the arm defines it); an axis tilt or offset beyond a few hundredths of "
    << "a degree or millimetre means the turntable stands differently from the file's description: correct the "
    << "file's platter and table geometry by hand.\n";
  return r.str();
}

}  // namespace

int run_calibrate(const CalibrateOptions& o) {
  const RigModel rig = load_rig(o.rig_model);
  if (rig.kind != RigKind::kArm || !rig.has_turntable) {
    throw std::invalid_argument("--rig-model " + o.rig_model + " is not an arm rig with a turntable");
  }
  const fs::path out = o.out.empty() ? fs::path(default_out()) : fs::path(o.out);
  fs::create_directories(out);
  install_stop_handlers();

  bus::Bus bus("calibrate");
  CalibrationRun run(bus, rig);
  run.wait_for_drivers(o.status_wait_s);

  const Eigen::Vector3d s = o.sphere.centre_in_mount();
  const std::vector<Pose> views = calibration_views(o.sphere, o.views);
  std::vector<SphereObservation> observations;
  json frames = json::array();
  std::cout << fmt::format("pbnbv calibrate: {} views of the {} mm sphere {} mm from the axis, rig {}", views.size(),
                           fixed(o.sphere.radius_m * 1e3, 1), fixed(o.sphere.offset_m * 1e3, 1), o.rig_model)
            << std::endl;
  int64_t request_id = bus::now_utime();
  for (std::size_t i = 0; i < views.size(); ++i) {
    json frame = {{"view", i + 1}, {"requested_object_T_camera", to_json(views[i])}};  // counted from 1
    if (const std::optional<SphereObservation> seen = observe_view(run, o, views[i], i, request_id, frame)) {
      frame["observation"] = observations.size();
      observations.push_back(*seen);
    }
    frames.push_back(frame);
  }
  if (static_cast<int>(observations.size()) < kMinFrames) {
    throw std::runtime_error(fmt::format("the sphere was fitted in {} of {} views, at least {} are needed (is the "
                                         "sphere of radius {} m on the platter mark, {} m from the axis?)",
                                         observations.size(), views.size(), kMinFrames, o.sphere.radius_m,
                                         o.sphere.offset_m));
  }
  CalibrationSolveOptions so;
  so.fit_axis = !o.fixed_axis;
  const RigCalibration cal = solve_rig_calibration(rig, s, observations, so);

  // Outputs: the calibrated rig file (checked by loading it), calibration.json, report.md.
  const fs::path rig_out = out / "rig_calibrated.xml";
  write_text_atomic(calibrated_rig_xml(read_text(o.rig_model), o.rig_model, cal.flange_T_camera, cal.turntable_zero_rad),
                    rig_out.string());
  const RigModel calibrated = load_rig(rig_out.string());
  const Corrections c = corrections_of(rig, cal);
  add_residuals(cal, frames);
  write_json_atomic(calibration_json(o, rig, calibrated, cal, c, so, rig_out, views.size(), observations.size(), frames),
                    (out / "calibration.json").string());
  write_text_atomic(calibration_report(o, cal, c, calibrated, rig_out, views.size(), observations.size(), frames),
                    (out / "report.md").string());

  std::cout << fmt::format("pbnbv calibrate: hand-eye corrected by {} mm / {} deg, turntable zero by {} deg; axis tilt "
                           "{} deg, offset {} mm (reported); residual rms {} mm -> {} mm over {} frames",
                           fixed(c.mount_mm, 3), fixed(c.mount_deg, 4), fixed(c.zero_deg, 4), fixed(c.tilt_deg, 4),
                           fixed(c.axis_offset_m.head<2>().norm() * 1e3, 3), fixed(cal.rms_before_m * 1e3, 3),
                           fixed(cal.rms_after_m * 1e3, 3), c.used)
            << "\n  " << rig_out.string() << ", " << (out / "calibration.json").string() << ", "
            << (out / "report.md").string() << std::endl;
  return 0;
}

}  // namespace pbnbv::launcher
