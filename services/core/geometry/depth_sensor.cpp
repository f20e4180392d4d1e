#include "core/geometry/depth_sensor.hpp"

#include <cmath>

namespace pbnbv {

namespace {

// A square-pixel pinhole (MuJoCo renders square pixels only: fx = fy), principal point at the
// image centre.
CameraIntrinsics pinhole(int width, int height, double focal_px) {
  CameraIntrinsics k;
  k.width = width;
  k.height = height;
  k.fx = k.fy = focal_px;
  k.cx = width / 2.0;
  k.cy = height / 2.0;
  return k;
}

// The focal length, px, that spreads `pixels` over `fov_deg`.
double focal_for_fov(int pixels, double fov_deg) {
  return 0.5 * pixels / std::tan(0.5 * fov_deg * 3.14159265358979323846 / 180.0);
}

DepthRange range(double min_m, double max_m) {
  DepthRange r;
  r.min_m = min_m;
  r.max_m = max_m;
  return r;
}

// An Intel RealSense D4xx depth module at 1280 x 720, 87 deg wide (the D400 datasheet): RMS error
// z^2 * subpixel / (f * baseline) with subpixel 0.08; the right imager, `baseline_m` right of the
// left (the depth's reference), casts the shadows; flying pixels, grazing loss and dropout ours.
DepthSensorModel active_stereo(CameraKind kind, std::string_view label, double baseline_m, const DepthRange& r,
                               double depth_unit_m) {
  DepthSensorModel s;
  s.kind = kind;
  s.label = label;
  s.principle = DepthPrinciple::kActiveStereo;
  s.intrinsics = pinhole(1280, 720, focal_for_fov(1280, 87.0));
  s.range = r;
  s.noise_per_m2 = 0.08 / (s.intrinsics.fx * baseline_m);
  s.depth_unit_m = depth_unit_m;
  s.shadow_baseline_m = baseline_m;
  s.flying_pixels = 0.3;
  s.grazing_limit_deg = 75;
  s.dropout = 0.005;
  return s;
}

// The figures and where they come from: docs/cameras.md.
std::array<DepthSensorModel, 5> make_models() {
  std::array<DepthSensorModel, 5> m;

  DepthSensorModel& ideal = m[0];
  ideal.kind = CameraKind::kIdeal;
  ideal.label = "ideal (the paper's simulated D435 image, exact depth)";
  ideal.principle = DepthPrinciple::kExact;  // intrinsics and range: camera_options.hpp's defaults

  // Intel RealSense D405: 1280 x 720, 18 mm baseline, Min-Z 100 mm at 1280 x 720, ideal range
  // 7-50 cm (D400 datasheet 337029); the D435's 87 deg field of view (not confirmed for the D405).
  // Stereo RMS error = z^2 * subpixel / (f * baseline), subpixel 0.08 (Intel's tuning paper and
  // its author); depth unit 0.1 mm (librealsense's default for the D405).
  m[1] = active_stereo(CameraKind::kD405, "Intel RealSense D405 (active stereo, 18 mm baseline)", 0.018, range(0.10, 1.0),
                       1e-4);

  // Intel RealSense D435: 1280 x 720 at 87 x 58 deg, 50 mm baseline, Min-Z 280 mm at 1280 x 720,
  // ideal range 0.3-3 m (datasheet 337029); the same RMS formula; depth unit 1 mm (librealsense).
  m[2] = active_stereo(CameraKind::kD435, "Intel RealSense D435 (active stereo, 50 mm baseline)", 0.050, range(0.28, 3.0),
                       1e-3);

  // Microsoft Azure Kinect DK, NFOV unbinned (hardware specification: 640 x 576, 75 x 65 deg,
  // 0.5-3.86 m, random error std. dev. <= 17 mm, systematic < 11 mm + 0.1 % of distance; depth in
  // mm). Square pixels from the vertical field of view. The noise, well inside the datasheet's
  // bound, is ours (1 mm + 0.1 % of the distance); the multipath and mixed pixels the
  // specification names are made here (the Kinect's own filter invalidates some of them).
  DepthSensorModel& tof = m[3];
  tof.kind = CameraKind::kAzureKinectNfov;
  tof.label = "Microsoft Azure Kinect DK, NFOV unbinned (time of flight)";
  tof.principle = DepthPrinciple::kTimeOfFlight;
  tof.intrinsics = pinhole(640, 576, focal_for_fov(576, 65.0));
  tof.range = range(0.5, 3.86);
  tof.noise_m = 1e-3;
  tof.noise_per_m = 1e-3;
  tof.depth_unit_m = 1e-3;
  tof.flying_pixels = 0.8;
  tof.grazing_limit_deg = 80;
  tof.multipath_gain = 0.3;
  tof.dropout = 0.002;

  // A metrology-grade structured-light camera, after the Zivid 2+ M60: its 2 x 2 subsampled image
  // 1224 x 1024 (Zivid's specification terms), 570 x 460 mm at the 600 mm focus distance (focal
  // length from the width), point precision 0.08 mm there, growing with z^2 (triangulation). The
  // range 0.35-1.1 m and the 0.15 m projector baseline are ours (not in the sources we could read).
  DepthSensorModel& sl = m[4];
  sl.kind = CameraKind::kStructuredLight;
  sl.label = "structured light, metrology grade (after the Zivid 2+ M60)";
  sl.principle = DepthPrinciple::kStructuredLight;
  sl.intrinsics = pinhole(1224, 1024, 612.0 / (0.285 / 0.6));
  sl.range = range(0.35, 1.1);
  sl.noise_per_m2 = 0.08e-3 / (0.6 * 0.6);
  sl.depth_unit_m = 2e-5;
  sl.shadow_baseline_m = 0.15;
  sl.grazing_limit_deg = 80;
  return m;
}

}  // namespace

double DepthSensorModel::reading_sigma_m(double z_m) const {
  const double s = axial_sigma_m(z_m);
  return std::sqrt(s * s + depth_unit_m * depth_unit_m / 12.0);
}

const DepthSensorModel& depth_sensor_model(CameraKind kind) {
  static const std::array<DepthSensorModel, 5> models = make_models();
  for (const DepthSensorModel& m : models) {
    if (m.kind == kind) return m;
  }
  return models[0];
}

void take_model_defaults(const DepthSensorModel& model, const std::function<bool(std::string_view)>& given,
                         CameraIntrinsics& k, DepthRange& r) {
  if (!given(kImageWidth.name)) k.width = model.intrinsics.width;
  if (!given(kImageHeight.name)) k.height = model.intrinsics.height;
  if (!given(kFocalX.name)) k.fx = model.intrinsics.fx;
  if (!given(kFocalY.name)) k.fy = model.intrinsics.fy;
  if (!given(kDepthMin.name)) r.min_m = model.range.min_m;
  if (!given(kDepthMax.name)) r.max_m = model.range.max_m;
}

}  // namespace pbnbv
