// Headless metric depth rendering of a MuJoCo 2.2.2 camera through EGL.
//
// Projection: MuJoCo's mjr_render builds its projection with
//   glFrustum(center - halfwidth, center + halfwidth, bottom, top, near, far),
//   halfwidth = 0.5 * viewport.width / viewport.height * (top - bottom),
// from the scene's mjvGLCamera. After mjv_updateScene we overwrite that frustum with one made
// from the pinhole intrinsics (asymmetric bottom/top and a shifted horizontal centre), so an
// off-centre principal point, including the half-pixel offset of the default cx = W/2,
// cy = H/2, is rendered exactly at the requested W x H: there is no oversized render and no
// crop (this is exact for any real cx, cy, not only multiples of half a pixel). Pixel (u, v)
// is sampled at its centre: multisampling is switched off (offsamples = 0), so there are no
// sub-pixel sample offsets.
//
// Depth: MuJoCo 2.2.2 uses the standard (not reversed) depth mapping, d = 0 at near, 1 at far;
// planar depth z = near * far / (far - d * (far - near)). near = 0.5 * min_m and far =
// 2 * max_m. The offscreen depth buffer is 32-bit float when ARB_depth_buffer_float is
// available (llvmpipe, NVIDIA) and 24-bit otherwise; either way one step of d is <= 2^-24, so
// the quantisation step of z is about z^2 / near * 2^-24: 1.2 um at 1 m and 11 um at 3 m with
// the default range (min 0.1 m).
#include "twin/depth_renderer.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>

namespace pbnbv::twin {
namespace {

std::string egl_error_name(EGLint code) {
  switch (code) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    default: break;
  }
  char buf[32];
  std::snprintf(buf, sizeof(buf), "EGL error 0x%04X", static_cast<unsigned>(code));
  return buf;
}

std::string egl_error_text(EGLint code) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "0x%04X", static_cast<unsigned>(code));
  return egl_error_name(code) + " (" + buf + ")";
}

[[noreturn]] void throw_egl(const std::string& step) {
  throw std::runtime_error("EglContext: " + step + " failed: " + egl_error_text(eglGetError()));
}

// EGL displays are per-process singletons and eglTerminate invalidates every context on the
// display, so terminate only when the last EglContext using the display goes away.
std::mutex g_display_mutex;
std::map<EGLDisplay, int> g_display_users;

void acquire_display(EGLDisplay d) {
  std::lock_guard<std::mutex> lock(g_display_mutex);
  ++g_display_users[d];
}

void release_display(EGLDisplay d) {
  std::lock_guard<std::mutex> lock(g_display_mutex);
  auto it = g_display_users.find(d);
  if (it == g_display_users.end()) return;
  if (--it->second == 0) {
    g_display_users.erase(it);
    eglTerminate(d);
  }
}

const char* gl_string(GLenum name) {
  const GLubyte* s = glGetString(name);
  return s ? reinterpret_cast<const char*>(s) : "?";
}

}  // namespace

// Uniform in [0, 1) from the top 53 bits, and a standard normal by the Marsaglia polar method:
// both written out so a given rng state gives the same noise with any standard library.
double uniform01(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0);
}

double standard_normal(std::mt19937_64& rng) {
  for (;;) {
    const double a = 2.0 * uniform01(rng) - 1.0;
    const double b = 2.0 * uniform01(rng) - 1.0;
    const double s = a * a + b * b;
    if (s > 0.0 && s < 1.0) return a * std::sqrt(-2.0 * std::log(s) / s);
  }
}

// ------------------------------------------------------------------------------------------------
// EglContext

struct EglContext::Impl {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  std::string platform;
};

EglContext::EglContext() : impl_(std::make_unique<Impl>()) {
  auto query_devices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));

  std::string attempts;  // what was tried, for the error message
  EGLDisplay display = EGL_NO_DISPLAY;

  // 1. Device platform: works without any window system (Mesa llvmpipe, NVIDIA).
  if (query_devices && get_platform_display) {
    EGLDeviceEXT devices[16];
    EGLint num_devices = 0;
    if (query_devices(16, devices, &num_devices) && num_devices > 0) {
      for (EGLint i = 0; i < num_devices && display == EGL_NO_DISPLAY; ++i) {
        EGLDisplay d = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (d == EGL_NO_DISPLAY) {
          attempts += "; eglGetPlatformDisplayEXT(device " + std::to_string(i) +
                      "): " + egl_error_text(eglGetError());
          continue;
        }
        EGLint major = 0, minor = 0;
        if (!eglInitialize(d, &major, &minor)) {
          attempts += "; eglInitialize(device " + std::to_string(i) +
                      "): " + egl_error_text(eglGetError());
          continue;
        }
        display = d;
        impl_->platform = "EGL_PLATFORM_DEVICE_EXT (device " + std::to_string(i) + " of " +
                          std::to_string(num_devices) + ")";
      }
    } else {
      attempts += "; eglQueryDevicesEXT: " +
                  (num_devices == 0 ? std::string("no devices") : egl_error_text(eglGetError()));
    }
  } else {
    attempts += "; eglQueryDevicesEXT/eglGetPlatformDisplayEXT not available";
  }

  // 2. Mesa's surfaceless platform.
  if (display == EGL_NO_DISPLAY && get_platform_display) {
    EGLDisplay d =
        get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (d == EGL_NO_DISPLAY) {
      attempts += "; eglGetPlatformDisplayEXT(surfaceless): " + egl_error_text(eglGetError());
    } else {
      EGLint major = 0, minor = 0;
      if (eglInitialize(d, &major, &minor)) {
        display = d;
        impl_->platform = "EGL_PLATFORM_SURFACELESS_MESA";
      } else {
        attempts += "; eglInitialize(surfaceless): " + egl_error_text(eglGetError());
      }
    }
  }
  if (display == EGL_NO_DISPLAY) {
    throw std::runtime_error("EglContext: no EGL display could be initialised" + attempts);
  }
  impl_->display = display;
  acquire_display(display);

  try {
    const EGLint config_attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT,   //
                                     EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,  //
                                     EGL_RED_SIZE, 8, EGL_GREEN_SIZE, 8, EGL_BLUE_SIZE, 8,
                                     EGL_ALPHA_SIZE, 8, EGL_DEPTH_SIZE, 24, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint num_configs = 0;
    if (!eglChooseConfig(display, config_attribs, &config, 1, &num_configs)) {
      throw_egl("eglChooseConfig");
    }
    if (num_configs < 1) {
      throw std::runtime_error(
          "EglContext: eglChooseConfig found no config with EGL_PBUFFER_BIT, EGL_OPENGL_BIT and "
          "a 24-bit depth buffer on " + impl_->platform);
    }
    if (!eglBindAPI(EGL_OPENGL_API)) throw_egl("eglBindAPI(EGL_OPENGL_API)");
    // No attributes: a compatibility-profile context, which MuJoCo 2.2.2's fixed-function
    // renderer needs.
    impl_->context = eglCreateContext(display, config, EGL_NO_CONTEXT, nullptr);
    if (impl_->context == EGL_NO_CONTEXT) throw_egl("eglCreateContext");
    if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, impl_->context)) {
      throw_egl("eglMakeCurrent(EGL_NO_SURFACE)");
    }
  } catch (...) {
    if (impl_->context != EGL_NO_CONTEXT) eglDestroyContext(display, impl_->context);
    release_display(display);
    throw;
  }
}

EglContext::~EglContext() {
  if (!impl_ || impl_->display == EGL_NO_DISPLAY) return;
  if (eglGetCurrentContext() == impl_->context) {
    eglMakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  }
  if (impl_->context != EGL_NO_CONTEXT) eglDestroyContext(impl_->display, impl_->context);
  release_display(impl_->display);
}

std::string EglContext::description() const {
  std::ostringstream out;
  const char* egl_vendor = eglQueryString(impl_->display, EGL_VENDOR);
  const char* egl_version = eglQueryString(impl_->display, EGL_VERSION);
  out << impl_->platform << "; EGL " << (egl_version ? egl_version : "?") << " ("
      << (egl_vendor ? egl_vendor : "?") << ")";
  if (eglGetCurrentContext() == impl_->context) {
    out << "; GL_VENDOR " << gl_string(GL_VENDOR) << "; GL_RENDERER " << gl_string(GL_RENDERER)
        << "; GL_VERSION " << gl_string(GL_VERSION);
  }
  return out.str();
}

// ------------------------------------------------------------------------------------------------
// DepthRenderer

struct DepthRenderer::Impl {
  mjModel* model = nullptr;
  int camera_id = -1;
  CameraIntrinsics k;
  DepthRange range;
  double near_m = 0.0;
  double far_m = 0.0;
  mjvOption option;
  mjvCamera camera;
  mjvPerturb perturb;
  mjvScene scene;
  mjrContext context;
  bool scene_made = false;
  bool context_made = false;
  std::vector<float> raw;  // bottom-up depth buffer as read back
};

namespace {

// The scene camera `cam` (its pose) with the pinhole frustum of `k` at the near plane, pixel
// centres at integer (u, v):
//   left = -n (cx + 0.5) / fx,  right = n (W - cx - 0.5) / fx,
//   top  =  n (cy + 0.5) / fy,  bottom = n (cy + 0.5 - H) / fy   (GL y up, image v down).
// mjr_render sets left/right = center -/+ 0.5 W / H (top - bottom) = center -/+ n W / (2 fx).
mjvGLCamera pinhole_camera(mjvGLCamera cam, const CameraIntrinsics& k, double near_m, double far_m) {
  const double n = near_m;
  cam.frustum_near = static_cast<float>(near_m);
  cam.frustum_far = static_cast<float>(far_m);
  cam.frustum_top = static_cast<float>(n * (k.cy + 0.5) / k.fy);
  cam.frustum_bottom = static_cast<float>(n * (k.cy + 0.5 - k.height) / k.fy);
  cam.frustum_center = static_cast<float>(n * (k.width - 1.0 - 2.0 * k.cx) / (2.0 * k.fx));
  return cam;
}

// The scene camera moved by depth_T_colour in its own optical frame (x right, y down, z forward:
// MuJoCo's camera looks along `forward` with `up` up, so right = forward x up).
mjvGLCamera moved_camera(mjvGLCamera cam, const Pose& depth_T_colour) {
  const Eigen::Vector3d pos(cam.pos[0], cam.pos[1], cam.pos[2]);
  const Eigen::Vector3d forward(cam.forward[0], cam.forward[1], cam.forward[2]);
  const Eigen::Vector3d up(cam.up[0], cam.up[1], cam.up[2]);
  Eigen::Matrix3d world_R_depth;
  world_R_depth.col(0) = forward.cross(up);
  world_R_depth.col(1) = -up;
  world_R_depth.col(2) = forward;
  const Eigen::Vector3d p = pos + world_R_depth * depth_T_colour.translation();
  const Eigen::Matrix3d world_R_colour = world_R_depth * depth_T_colour.linear();
  for (int i = 0; i < 3; ++i) {
    cam.pos[i] = static_cast<float>(p[i]);
    cam.forward[i] = static_cast<float>(world_R_colour(i, 2));
    cam.up[i] = static_cast<float>(-world_R_colour(i, 1));
  }
  return cam;
}

}  // namespace

DepthRenderer::DepthRenderer(mjModel* model, const std::string& camera_name,
                             const CameraIntrinsics& k, const DepthRange& range)
    : impl_(std::make_unique<Impl>()) {
  if (!model) throw std::invalid_argument("DepthRenderer: model is null");
  k.validate();
  range.validate();
  if (k.fx != k.fy) {
    std::ostringstream msg;
    msg << "DepthRenderer: fx (" << k.fx << ") != fy (" << k.fy
        << "): MuJoCo 2.2.2 renders square pixels only, fx must equal fy";
    throw std::invalid_argument(msg.str());
  }
  const int cam_id = mj_name2id(model, mjOBJ_CAMERA, camera_name.c_str());
  if (cam_id < 0) {
    throw std::invalid_argument("DepthRenderer: camera \"" + camera_name +
                                "\" does not exist in the model (" +
                                std::to_string(model->ncam) + " cameras)");
  }
  if (eglGetCurrentContext() == EGL_NO_CONTEXT) {
    throw std::runtime_error(
        "DepthRenderer: no EGL context is current on this thread (create an EglContext first)");
  }
  GLint max_dims[2] = {0, 0};
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, max_dims);
  if (max_dims[0] > 0 && (k.width > max_dims[0] || k.height > max_dims[1])) {
    std::ostringstream msg;
    msg << "DepthRenderer: image " << k.width << "x" << k.height
        << " exceeds the OpenGL maximum viewport " << max_dims[0] << "x" << max_dims[1];
    throw std::invalid_argument(msg.str());
  }
  if (!(model->stat.extent > 0.0)) {
    throw std::invalid_argument("DepthRenderer: model stat.extent must be > 0");
  }

  Impl& s = *impl_;
  s.model = model;
  s.camera_id = cam_id;
  s.k = k;
  s.range = range;
  s.near_m = 0.5 * range.min_m;
  s.far_m = 2.0 * range.max_m;

  // Model adjustments (documented in the header): the camera's vertical field of view for a
  // centred principal point (what other MuJoCo users of this camera see), no stereo offset,
  // the offscreen buffer at the image size without multisampling, the clip planes.
  model->cam_fovy[cam_id] = 2.0 * std::atan(0.5 * k.height / k.fy) * 180.0 / mjPI;
  model->cam_ipd[cam_id] = 0.0;
  model->vis.global.offwidth = k.width;
  model->vis.global.offheight = k.height;
  model->vis.quality.offsamples = 0;
  model->vis.map.znear = static_cast<float>(s.near_m / model->stat.extent);
  model->vis.map.zfar = static_cast<float>(s.far_m / model->stat.extent);

  // Only geoms of groups 0..2; nothing else (sites, joints, tendons, lights, frames, skins,
  // contact markers...) may reach the depth buffer.
  mjv_defaultOption(&s.option);
  for (int g = 0; g < mjNGROUP; ++g) {
    s.option.geomgroup[g] = g <= 2 ? 1 : 0;
    s.option.sitegroup[g] = 0;
    s.option.jointgroup[g] = 0;
    s.option.tendongroup[g] = 0;
    s.option.actuatorgroup[g] = 0;
    s.option.skingroup[g] = 0;
  }
  for (int f = 0; f < mjNVISFLAG; ++f) s.option.flags[f] = 0;
  s.option.flags[mjVIS_STATIC] = 1;  // geoms of bodies welded to the world are still geoms
  s.option.label = mjLABEL_NONE;
  s.option.frame = mjFRAME_NONE;

  mjv_defaultCamera(&s.camera);
  s.camera.type = mjCAMERA_FIXED;
  s.camera.fixedcamid = cam_id;
  mjv_defaultPerturb(&s.perturb);

  mjv_defaultScene(&s.scene);
  mjv_makeScene(model, &s.scene, 2 * model->ngeom + 100);
  s.scene_made = true;

  mjr_defaultContext(&s.context);
  mjr_makeContext(model, &s.context, mjFONTSCALE_100);
  s.context_made = true;
  if (!s.context.offFBO || s.context.offWidth != k.width || s.context.offHeight != k.height) {
    std::ostringstream msg;
    msg << "DepthRenderer: offscreen buffer is " << s.context.offWidth << "x"
        << s.context.offHeight << " (FBO " << s.context.offFBO << "), wanted " << k.width << "x"
        << k.height;
    mjr_freeContext(&s.context);
    mjv_freeScene(&s.scene);
    throw std::runtime_error(msg.str());
  }
  mjr_setBuffer(mjFB_OFFSCREEN, &s.context);
  s.raw.resize(static_cast<std::size_t>(k.width) * k.height);
}

DepthRenderer::~DepthRenderer() {
  if (!impl_) return;
  // Freeing GL objects needs the context that made them to be current; when it is gone the
  // objects went with it.
  if (impl_->context_made && eglGetCurrentContext() != EGL_NO_CONTEXT) {
    mjr_freeContext(&impl_->context);
  }
  if (impl_->scene_made) mjv_freeScene(&impl_->scene);
}

DepthImage DepthRenderer::render(mjData* data) {
  if (!data) throw std::invalid_argument("DepthRenderer::render: data is null");
  if (eglGetCurrentContext() == EGL_NO_CONTEXT) {
    throw std::runtime_error("DepthRenderer::render: no EGL context is current on this thread");
  }
  Impl& s = *impl_;
  const CameraIntrinsics& k = s.k;
  mjvScene& scn = s.scene;

  mjv_updateScene(s.model, data, &s.option, &s.perturb, &s.camera, mjCAT_STATIC | mjCAT_DYNAMIC,
                  &scn);

  // Keep model geoms only; make them opaque (transparent geoms are drawn without depth writes)
  // and untextured. Geoms with alpha 0 are hidden on purpose and stay hidden.
  int kept = 0;
  for (int i = 0; i < scn.ngeom; ++i) {
    mjvGeom g = scn.geoms[i];
    if (g.objtype != mjOBJ_GEOM || g.category == mjCAT_DECOR || g.rgba[3] <= 0.0f) continue;
    g.rgba[3] = 1.0f;
    g.transparent = 0;
    g.texid = -1;
    g.reflectance = 0.0f;
    g.label[0] = '\0';
    scn.geoms[kept++] = g;
  }
  scn.ngeom = kept;
  scn.nlight = 0;  // lighting only costs time here
  scn.stereo = mjSTEREO_NONE;
  scn.enabletransform = 0;
  scn.framewidth = 0;
  for (int f = 0; f < mjNRNDFLAG; ++f) scn.flags[f] = 0;
  scn.flags[mjRND_CULL_FACE] = 1;

  const mjvGLCamera cam = pinhole_camera(mjv_averageCamera(&scn.camera[0], &scn.camera[1]), k, s.near_m, s.far_m);
  scn.camera[0] = cam;
  scn.camera[1] = cam;
  const double n = s.near_m;

  const mjrRect viewport = {0, 0, k.width, k.height};
  mjr_setBuffer(mjFB_OFFSCREEN, &s.context);
  mjr_render(viewport, &scn, &s.context);
  mjr_readPixels(nullptr, s.raw.data(), viewport, &s.context);
  const GLenum gl_error = glGetError();
  if (gl_error != GL_NO_ERROR) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "OpenGL error 0x%04X", static_cast<unsigned>(gl_error));
    throw std::runtime_error(std::string("DepthRenderer::render: ") + buf);
  }

  DepthImage image;
  image.width = k.width;
  image.height = k.height;
  image.depth_m.assign(static_cast<std::size_t>(k.width) * k.height, 0.0f);
  const double f = s.far_m;
  const double fn = f * n;
  const double f_minus_n = f - n;
  const double lo = s.range.min_m;
  const double hi = s.range.max_m;
  for (int v = 0; v < k.height; ++v) {
    const float* src = s.raw.data() + static_cast<std::size_t>(k.height - 1 - v) * k.width;
    float* dst = image.depth_m.data() + static_cast<std::size_t>(v) * k.width;
    for (int u = 0; u < k.width; ++u) {
      const double d = src[u];
      if (!(d < 1.0)) continue;  // cleared: nothing drawn
      const double z = fn / (f - d * f_minus_n);
      if (z >= lo && z <= hi) dst[u] = static_cast<float>(z);
    }
  }
  return image;
}

std::vector<uint8_t> DepthRenderer::render_colour(mjData* data, const CameraIntrinsics& kc, const Pose& depth_T_colour) {
  if (!data) throw std::invalid_argument("DepthRenderer::render_colour: data is null");
  kc.validate();
  Impl& s = *impl_;
  if (kc.width > s.k.width || kc.height > s.k.height) {
    throw std::invalid_argument("DepthRenderer::render_colour: a " + std::to_string(kc.width) + "x" +
                                std::to_string(kc.height) + " colour image is larger than the " +
                                std::to_string(s.k.width) + "x" + std::to_string(s.k.height) + " depth image");
  }
  if (kc.fx != kc.fy) throw std::invalid_argument("DepthRenderer::render_colour: fx != fy (MuJoCo 2.2.2 renders square pixels)");
  if (eglGetCurrentContext() == EGL_NO_CONTEXT) {
    throw std::runtime_error("DepthRenderer::render_colour: no EGL context is current on this thread");
  }
  mjvScene& scn = s.scene;
  mjv_updateScene(s.model, data, &s.option, &s.perturb, &s.camera, mjCAT_STATIC | mjCAT_DYNAMIC, &scn);
  // Model geoms only, as they look (colour, material, texture); the lights kept, no shadows,
  // reflections or skybox (nothing there is black, as a camera sees an unlit background).
  int kept = 0;
  for (int i = 0; i < scn.ngeom; ++i) {
    mjvGeom g = scn.geoms[i];
    if (g.objtype != mjOBJ_GEOM || g.category == mjCAT_DECOR || g.rgba[3] <= 0.0f) continue;
    g.label[0] = '\0';
    g.reflectance = 0.0f;
    scn.geoms[kept++] = g;
  }
  scn.ngeom = kept;
  scn.stereo = mjSTEREO_NONE;
  scn.enabletransform = 0;
  scn.framewidth = 0;
  for (int f = 0; f < mjNRNDFLAG; ++f) scn.flags[f] = 0;
  scn.flags[mjRND_CULL_FACE] = 1;
  const mjvGLCamera cam =
      pinhole_camera(moved_camera(mjv_averageCamera(&scn.camera[0], &scn.camera[1]), depth_T_colour), kc, s.near_m, s.far_m);
  scn.camera[0] = cam;
  scn.camera[1] = cam;
  const mjrRect viewport = {0, 0, kc.width, kc.height};
  mjr_setBuffer(mjFB_OFFSCREEN, &s.context);
  mjr_render(viewport, &scn, &s.context);
  std::vector<uint8_t> bottom_up(static_cast<std::size_t>(kc.width) * kc.height * 3);
  mjr_readPixels(bottom_up.data(), nullptr, viewport, &s.context);
  const GLenum gl_error = glGetError();
  if (gl_error != GL_NO_ERROR) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "OpenGL error 0x%04X", static_cast<unsigned>(gl_error));
    throw std::runtime_error(std::string("DepthRenderer::render_colour: ") + buf);
  }
  const std::size_t row = static_cast<std::size_t>(kc.width) * 3;
  std::vector<uint8_t> rgb(bottom_up.size());
  for (int v = 0; v < kc.height; ++v) {
    std::memcpy(rgb.data() + static_cast<std::size_t>(v) * row,
                bottom_up.data() + static_cast<std::size_t>(kc.height - 1 - v) * row, row);
  }
  return rgb;
}

// ------------------------------------------------------------------------------------------------

DepthImage through_lens(const DepthImage& pinhole, const CameraIntrinsics& k_pinhole, const CameraIntrinsics& k,
                        const LensDistortion& d) {
  DepthImage out;
  out.width = k.width;
  out.height = k.height;
  out.depth_m = distort_depth(pinhole.depth_m, k_pinhole, k, d);
  return out;
}

void apply_depth_noise(DepthImage& image, const DepthNoise& noise, std::mt19937_64& rng) {
  if (!(noise.sigma_per_m >= 0.0) || !std::isfinite(noise.sigma_per_m)) {
    throw std::invalid_argument("apply_depth_noise: sigma_per_m must be finite and >= 0");
  }
  if (!(noise.dropout >= 0.0 && noise.dropout <= 1.0)) {
    throw std::invalid_argument("apply_depth_noise: dropout must be in [0, 1]");
  }
  if (!noise.enabled()) return;
  for (float& z : image.depth_m) {
    if (!(z > 0.0f)) continue;
    if (noise.dropout > 0.0 && uniform01(rng) < noise.dropout) {
      z = 0.0f;
      continue;
    }
    if (noise.sigma_per_m > 0.0) {
      const double noisy = z + noise.sigma_per_m * z * standard_normal(rng);
      z = noisy > 0.0 ? static_cast<float>(noisy) : 0.0f;
    }
  }
}

}  // namespace pbnbv::twin
