#pragma once
// The scan-level settings, each defined once (core/base/setting.hpp): default, allowed range,
// unit and meaning. With the settings of the lower layers (core/geometry/camera_options.hpp,
// core/mapping/map_options.hpp, core/perception/perception_options.hpp,
// core/planning/planning_options.hpp, kRig in core/geometry/rig_kind.hpp) they are the table of scan
// options: ScanSettings takes its defaults from them, and `pbnbv scan`, `bench`, `ablate`, the
// services and the twin declare their options and help text from them.
#include <array>
#include <cstdint>

#include "core/base/setting.hpp"
#include "core/geometry/mesh.hpp"

namespace pbnbv {

// Registration on or off (`--registration on|off`).
enum class OnOff : uint8_t { kOff, kOn };
template <>
struct EnumNames<OnOff> {
  static constexpr std::string_view what = "switch";
  static constexpr std::array<NamedValue<OnOff>, 2> names{{{OnOff::kOn, "on"}, {OnOff::kOff, "off"}}};
};

// The object.
inline constexpr Setting<double> kObjectSize{"size", 0.3, 0.01, 2.0, "m",
                                             "shortest bounding-box edge after normalisation"};
inline constexpr ChoiceSetting<UpAxis> kUp{"up", UpAxis::kZ,
                                           "which axis of the mesh file points up (default: the object's own: "
                                           "each known object's, docs/benchmark.md; z for a mesh file)"};

// The views.
inline constexpr Setting<int> kViews{"views", 10, 1, 1000, "", "at most this many views"};

// When a scan is done (core/scan/stop_rule.hpp): the surface rule stops it when the last
// --stop-window views each added less than --stop-new-surface percent new surface (points farther
// than --stop-radius from the model before them, relative to the model), after at least
// --stop-min-views views. Defaults tuned on half the default object set, arm rig, 20 views: the
// largest saving with every object within 0.5 points of its 20-view coverage (docs/scan.md "When a
// scan stops": 7 views in a row under 0.05 %; a shorter window stops before late gains).
// The rule in seconds stops it when the last --stop-rate-views views added less than
// --stop-gain-per-second percent of the model per second of the rig time they took.
enum class StopRule : uint8_t { kOff, kSurface, kSeconds };
template <>
struct EnumNames<StopRule> {
  static constexpr std::string_view what = "stop rule";
  static constexpr std::array<NamedValue<StopRule>, 3> names{
      {{StopRule::kSurface, "surface"}, {StopRule::kSeconds, "seconds"}, {StopRule::kOff, "off"}}};
};
inline constexpr ChoiceSetting<StopRule> kStopRule{
    "stop-rule", StopRule::kSurface,
    "surface: stop when the last views added (almost) no new surface; seconds: stop when they added too little "
    "per second of rig time; off: use the whole --views budget"};
inline constexpr Setting<int> kStopWindow{"stop-window", 7, 1, 100, "",
                                          "surface rule: this many views in a row must each add too little"};
inline constexpr Setting<double> kStopNewSurface{"stop-new-surface", 0.05, 0.0, 100.0, "%",
                                                 "surface rule: too little = new points under this percent of the model"};
inline constexpr Setting<int> kStopRateViews{"stop-rate-views", 2, 1, 100, "",
                                            "seconds rule: the gain per second is measured over this many views"};
inline constexpr Setting<double> kStopGainPerSecond{
    "stop-gain-per-second", 0.003, 0.0, 100.0, "%/s",
    "seconds rule: too little = new surface under this percent of the model per second of rig time"};
inline constexpr Setting<int> kStopMinViews{"stop-min-views", 3, 1, 1000, "", "surface rule: never stop before this many views"};
inline constexpr Setting<double> kStopRadius{"stop-radius", 0.005, 0.0005, 0.1, "m",
                                             "surface rule: a point is new farther than this from the model (the coverage scale)"};
// The ring's elevation (ring planner's views, and the first view of a planned scan): 30 deg on
// the arm rig; 0 deg on the free rig (kRingElevationFreeDeg).
inline constexpr Setting<double> kRingElevation{"ring-elevation", 30.0, -89.0, 89.0, "deg",
                                                "ring views and first view: elevation above the object centre"};
inline constexpr double kRingElevationFreeDeg = 0.0;

// Registration: on by default on the arm rig, off on the free rig (the paper's idealised
// comparison setup, whose kinematic poses are exact).
inline constexpr ChoiceSetting<OnOff> kRegistration{
    "registration", OnOff::kOn, "refine every view's pose by ICP against the model (default: on arm, off free)"};

// The depth filter (core/perception/depth_filter.hpp) in the camera and mapping services.
inline constexpr ChoiceSetting<OnOff> kDepthFilter{
    "depth-filter", OnOff::kOn,
    "remove flying pixels and speckles from each depth frame (default: on, off for the twin's ideal camera, which "
    "makes neither)"};

// The rig's motion and the twin.
inline constexpr Setting<double> kSpeedScale{"speed-scale", 1.0, 0.01, 1.0, "", "fraction of the joint speed limits"};
inline constexpr Setting<double> kSimSpeed{"sim-speed", 4.0, 0.1, 100.0, "",
                                           "twin simulation speed, multiple of real time"};
inline constexpr Setting<double> kDepthNoise{"noise-sigma", 0.0, 0.0, 0.1, "",
                                             "twin depth noise, std = K * depth (0: off)"};
inline constexpr Setting<double> kDropout{"dropout", 0.0, 0.0, 1.0, "", "twin pixel dropout probability (0: off)"};
// The twin's pose-error model: kinematic poses wrong the way a real rig's are (all 0: off).
inline constexpr Setting<double> kHandEyeErrorMm{"hand-eye-error-mm", 0.0, 0.0, 100.0, "mm",
                                                 "twin: the true camera mount is off the model's by this much "
                                                 "(random direction)"};
inline constexpr Setting<double> kHandEyeErrorDeg{"hand-eye-error-deg", 0.0, 0.0, 20.0, "deg",
                                                  "twin: ... and turned by this much (random axis)"};
inline constexpr Setting<double> kTurntableErrorDeg{"turntable-error-deg", 0.0, -20.0, 20.0, "deg",
                                                    "twin: the turntable reports its angle off by this much"};
inline constexpr Setting<double> kJointErrorDeg{"joint-error-deg", 0.0, 0.0, 5.0, "deg",
                                                "twin: each joint reports its angle off by N(0, this), new per move"};
inline constexpr Setting<int64_t> kErrorSeed{"error-seed", 7, 0, int64_t{1} << 40, "",
                                             "seed of the twin's error directions and draws"};
inline constexpr Setting<double> kTurntableBacklashDeg{
    "turntable-backlash-deg", 0.0, 0.0, 5.0, "deg",
    "twin: the platter stops this much short of where its encoder says, against the direction it turned"};

// The twin's rig errors by name, each a set of the figures above (docs/configuration.md "Cameras and rig errors"):
//   none          exact kinematics;
//   calibrated    what `pbnbv calibrate` leaves on an arm with 0.02 deg joint encoder noise (the
//                 mount 0.47 mm / 0.11 deg off, its measured residual after 24 views), that
//                 noise, a 0.01 deg turntable zero and 0.05 deg of turntable backlash;
//   uncalibrated  the rig file's mount 5 mm / 1 deg off and the turntable zero 0.5 deg, with the
//                 same joint noise and backlash.
enum class RigErrors { kNone, kCalibrated, kUncalibrated };
template <>
struct EnumNames<RigErrors> {
  static constexpr std::string_view what = "rig errors";
  static constexpr std::array<NamedValue<RigErrors>, 3> names{
      {{RigErrors::kNone, "none"}, {RigErrors::kCalibrated, "calibrated"}, {RigErrors::kUncalibrated, "uncalibrated"}}};
};
inline constexpr ChoiceSetting<RigErrors> kRigErrors{
    "rig-errors", RigErrors::kNone,
    "twin: the rig's kinematic errors by name (none, calibrated, uncalibrated); the error options override its figures"};

struct RigErrorFigures {
  double hand_eye_mm = 0, hand_eye_deg = 0, turntable_deg = 0, joint_deg = 0, backlash_deg = 0;
};
constexpr RigErrorFigures rig_error_figures(RigErrors e) {
  switch (e) {
    case RigErrors::kCalibrated:
      return {0.47, 0.11, 0.01, 0.02, 0.05};
    case RigErrors::kUncalibrated:
      return {5.0, 1.0, 0.5, 0.02, 0.05};
    case RigErrors::kNone:
      break;
  }
  return {};
}

}  // namespace pbnbv
