#pragma once
// Headless depth rendering of a MuJoCo scene through EGL (device platform, which works on Mesa
// llvmpipe without a display and on NVIDIA; falls back to Mesa's surfaceless platform).
#include <mujoco/mujoco.h>

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/base/pose.hpp"
#include "core/geometry/camera_model.hpp"
#include "core/geometry/lens_distortion.hpp"

namespace pbnbv::twin {

// An EGL display + OpenGL context made current on the calling thread for its lifetime.
// Throws std::runtime_error saying which EGL step failed (with the EGL error code).
class EglContext {
 public:
  EglContext();
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;
  std::string description() const;  // platform, vendor, renderer strings
 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Planar depth image: row-major, row 0 at the top; metres along the optical axis;
// 0 where nothing was hit within the depth range.
struct DepthImage {
  int width = 0;
  int height = 0;
  std::vector<float> depth_m;
  float at(int u, int v) const { return depth_m[static_cast<std::size_t>(v) * width + u]; }
};

// Renders metric planar depth from a named MuJoCo camera with the given pinhole intrinsics.
// Requires a current EglContext. Only geoms in groups 0..2 are rendered (groups >= 3 hold
// collision-only helpers and the camera housing).
class DepthRenderer {
 public:
  // `model` must outlive the renderer and is adjusted for rendering (camera fovy, offscreen
  // buffer size, near/far planes). Throws std::invalid_argument when the camera does not
  // exist or the intrinsics cannot be rendered (fx != fy: MuJoCo 2.2.2 has square pixels).
  // A principal point off the image centre is rendered exactly by giving the scene camera an
  // off-centre frustum (MuJoCo 2.2.2 renders the frustum it is given).
  DepthRenderer(mjModel* model, const std::string& camera_name, const CameraIntrinsics& k,
                const DepthRange& range);
  ~DepthRenderer();
  DepthRenderer(const DepthRenderer&) = delete;
  DepthRenderer& operator=(const DepthRenderer&) = delete;

  // Renders the scene as in `data` (positions must be current: mj_forward or mj_kinematics).
  DepthImage render(mjData* data);

  // The colour image (R G B, row 0 at the top) a colour sensor with the pinhole `kc`, at
  // depth_T_colour from this camera's optical frame, takes of the scene as in `data`: the geoms'
  // own colours, materials and textures, lit by the model's lights and headlight, no shadows;
  // black where nothing is drawn. Throws std::invalid_argument when kc is larger than the depth
  // image (the offscreen buffer is sized for it) or fx != fy.
  std::vector<uint8_t> render_colour(mjData* data, const CameraIntrinsics& kc, const Pose& depth_T_colour);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The image of a camera `k` with the lens `d` from `pinhole`, rendered with `k_pinhole`
// (pinhole_cover(k, d): every ray the lens brings in), resampled by distort_depth.
DepthImage through_lens(const DepthImage& pinhole, const CameraIntrinsics& k_pinhole, const CameraIntrinsics& k,
                        const LensDistortion& d);

// Optional sensor noise, off by default: Gaussian with standard deviation
// sigma_per_m * depth (depth-proportional), and each valid pixel dropped (set to 0) with
// probability `dropout`.
struct DepthNoise {
  double sigma_per_m = 0.0;
  double dropout = 0.0;
  bool enabled() const { return sigma_per_m > 0.0 || dropout > 0.0; }
};
void apply_depth_noise(DepthImage& image, const DepthNoise& noise, std::mt19937_64& rng);

// Uniform in [0, 1) and standard normal draws, written out so that a given rng state gives the
// same noise with any standard library.
double uniform01(std::mt19937_64& rng);
double standard_normal(std::mt19937_64& rng);

}  // namespace pbnbv::twin
