#pragma once
// Depth cameras by name: what a scan's camera is (its image, range and how its depth is wrong).
// Each named model carries the figures of the camera's published datasheet (docs/cameras.md
// cites them) and the artefacts its measuring principle makes. The twin renders them
// (twin/sensor_sim.hpp); the pipeline reads the intrinsics, the range and the axial noise
// (registration's residual floor, the depth filter's allowance).
#include <array>
#include <functional>
#include <string>
#include <string_view>

#include "core/base/setting.hpp"
#include "core/geometry/camera_model.hpp"

namespace pbnbv {

enum class CameraKind {
  kIdeal,            // today's twin camera: the paper's simulated D435 geometry, exact depth
  kD405,             // Intel RealSense D405: short-range active stereo, 18 mm baseline
  kD435,             // Intel RealSense D435: active stereo, 50 mm baseline
  kAzureKinectNfov,  // Microsoft Azure Kinect DK, NFOV unbinned: continuous-wave time of flight
  kStructuredLight,  // a metrology-grade structured-light camera (after the Photoneo PhoXi M)
};
template <>
struct EnumNames<CameraKind> {
  static constexpr std::string_view what = "camera";
  static constexpr std::array<NamedValue<CameraKind>, 5> names{{{CameraKind::kIdeal, "ideal"},
                                                                {CameraKind::kD405, "d405"},
                                                                {CameraKind::kD435, "d435"},
                                                                {CameraKind::kAzureKinectNfov, "azure-kinect-nfov"},
                                                                {CameraKind::kStructuredLight, "structured-light"}}};
};
inline constexpr ChoiceSetting<CameraKind> kCamera{
    "camera", CameraKind::kIdeal,
    "the depth camera the twin plays (its image, range and depth errors; docs/cameras.md); the intrinsics options "
    "override its image"};

enum class DepthPrinciple { kExact, kActiveStereo, kTimeOfFlight, kStructuredLight };

// One camera: its image and range, and how its depth reading departs from the true depth.
struct DepthSensorModel {
  CameraKind kind = CameraKind::kIdeal;
  std::string_view label;  // "Intel RealSense D435 (active stereo)"
  DepthPrinciple principle = DepthPrinciple::kExact;
  CameraIntrinsics intrinsics;  // principal point at the image centre
  DepthRange range;

  // Axial noise, 1 sigma: sigma(z) = noise_m + noise_per_m * z + noise_per_m2 * z^2 (z in m). A
  // stereo camera's is the disparity noise carried to depth: z^2 * subpixel / (f * baseline).
  double noise_m = 0;
  double noise_per_m = 0;
  double noise_per_m2 = 0;
  // The depth's step (its output unit): readings are rounded to it (0: continuous).
  double depth_unit_m = 0;
  // The second viewpoint (the right imager of a stereo pair, a structured-light projector) sits
  // this far along the camera's +x axis: what it cannot see has no reading (0: none).
  double shadow_baseline_m = 0;
  // At a depth edge (a neighbour nearer by more than 2 % of the depth), this fraction of the
  // far side's edge pixels read a mix of both surfaces (flying pixels).
  double flying_pixels = 0;
  // Beyond this angle between the view ray and the surface normal a reading is lost, with a
  // probability rising to 1 at 90 degrees (90: never).
  double grazing_limit_deg = 90;
  // Time of flight: light that comes back over two surfaces lengthens the path in concave
  // corners; the reading is pushed back by this fraction of how far the pixel lies behind its
  // neighbourhood's mean depth (0: none).
  double multipath_gain = 0;
  double dropout = 0;  // each reading lost with this probability besides

  // sigma(z) of the model's noise alone, m.
  double axial_sigma_m(double z_m) const { return noise_m + noise_per_m * z_m + noise_per_m2 * z_m * z_m; }
  // What a plane's readings scatter by at depth z: the noise and the rounding to depth_unit_m
  // together (sqrt(sigma^2 + unit^2 / 12)), m.
  double reading_sigma_m(double z_m) const;
  bool exact() const { return principle == DepthPrinciple::kExact; }
};

// The named model. Never throws: every CameraKind has one.
const DepthSensorModel& depth_sensor_model(CameraKind kind);

// The model's image and range where a command line leaves them: each of width, height, fx, fy,
// depth-min and depth-max (the options' names, camera_options.hpp) for which `given(name)` is
// false. The principal point is the caller's (the image centre unless given).
void take_model_defaults(const DepthSensorModel& model, const std::function<bool(std::string_view)>& given,
                         CameraIntrinsics& k, DepthRange& range);

}  // namespace pbnbv
