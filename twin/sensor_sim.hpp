#pragma once
// The twin's camera: a rendered (exact) depth image made into what a named depth camera reads
// (core/geometry/depth_sensor.hpp). What each artefact does, in the order applied:
//   - shadows: a pixel the second viewpoint (stereo right imager, projector) cannot see, because
//     a nearer surface in its row hides it from shadow_baseline_m along +x, has no reading (the
//     band on the left of near objects in a RealSense image);
//   - flying pixels: at a depth edge a fraction of the far side's edge pixels read a mix of the
//     two depths;
//   - grazing surfaces: past grazing_limit_deg a reading is lost with a probability rising to 1;
//   - multipath (time of flight): concave places read farther;
//   - noise: Gaussian, sigma(z) of the model; then the depth is rounded to its unit;
//   - dropout; readings outside the range are lost.
// All from the exact image (each artefact sees the true scene), deterministic for the rng's state.
#include <random>

#include "core/geometry/depth_sensor.hpp"
#include "twin/depth_renderer.hpp"

namespace pbnbv::twin {

// What the artefacts did to one image, pixels.
struct SensorSimStats {
  int valid_in = 0;   // readings in the exact image
  int shadowed = 0;
  int flying = 0;
  int grazing = 0;
  int multipath = 0;  // pushed back by more than a millimetre
  int dropped = 0;    // random dropout and out of range after noise
};

// `image` rendered with `k` (the model's own intrinsics or the user's). The exact model changes
// nothing.
SensorSimStats simulate_sensor(DepthImage& image, const CameraIntrinsics& k, const DepthSensorModel& model,
                               std::mt19937_64& rng);

}  // namespace pbnbv::twin
