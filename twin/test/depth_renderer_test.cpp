// Depth renderer against analytic ray casts, pixel by pixel over the full image.
//
// Every scene puts a camera body at the world origin with an identity orientation, so the
// camera's optical frame (x right, y down, z forward) is the world frame; the MuJoCo camera
// inside it has quat="0 1 0 0" (MuJoCo cameras look along their -z with +y up). The ray through
// pixel centre (u, v) is then d = ((u - cx) / fx, (v - cy) / fy, 1), and the planar depth of a
// hit at t * d is t itself.
#include "twin/depth_renderer.hpp"
#include "twin/test/render_scene.hpp"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/geometry/camera_model.hpp"
#include "core/base/units.hpp"
#include "bus/colour_codec.hpp"
#include "bus/convert.hpp"
#include "bus/convert_rig.hpp"
#include "core/geometry/colour_image.hpp"
#include "driver/rig_contract.hpp"

namespace pbnbv::twin {
namespace {

namespace fs = std::filesystem;

Eigen::Vector3d ray(const CameraIntrinsics& k, int u, int v) {
  return Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
}

// Planar depth of the plane n.(x - p0) = 0 along the pixel's ray, or -1 when it is behind.
double plane_depth(const CameraIntrinsics& k, int u, int v, const Eigen::Vector3d& p0,
                   const Eigen::Vector3d& n) {
  const double denom = n.dot(ray(k, u, v));
  if (std::abs(denom) < 1e-12) return -1.0;
  const double t = n.dot(p0) / denom;
  return t > 0.0 ? t : -1.0;
}

// Planar depth of the first hit on a sphere, or -1 when the ray misses.
double sphere_depth(const CameraIntrinsics& k, int u, int v, const Eigen::Vector3d& c, double r) {
  const Eigen::Vector3d d = ray(k, u, v);
  const double a = d.squaredNorm();
  const double b = d.dot(c);
  const double disc = b * b - a * (c.squaredNorm() - r * r);
  if (disc < 0.0) return -1.0;
  return (b - std::sqrt(disc)) / a;
}

struct PlaneStats {
  double max_err_mm = 0.0;
  long checked = 0;
  long wrong_validity = 0;
};

// Every pixel: rendered == analytic (within tol) where the analytic depth is inside the range,
// and 0 where it is outside (pixels within 1 mm of a range limit are skipped).
PlaneStats check_plane(const DepthImage& img, const CameraIntrinsics& k, const DepthRange& r,
                       const Eigen::Vector3d& p0, const Eigen::Vector3d& n) {
  PlaneStats s;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const double t = plane_depth(k, u, v, p0, n);
      const double z = img.at(u, v);
      if (t > 0 && (std::abs(t - r.min_m) < 1e-3 || std::abs(t - r.max_m) < 1e-3)) continue;
      const bool expect = t >= r.min_m && t <= r.max_m;
      if (expect != (z > 0)) {
        ++s.wrong_validity;
        continue;
      }
      if (expect) {
        s.max_err_mm = std::max(s.max_err_mm, 1e3 * std::abs(z - t));
        ++s.checked;
      }
    }
  }
  return s;
}

CameraIntrinsics default_k() { return CameraIntrinsics{}; }

// ------------------------------------------------------------------------------------------------

TEST(EglContextTest, InitialisesAndDescribes) {
  const std::string d = egl().description();
  std::printf("EGL: %s\n", d.c_str());
  EXPECT_NE(d.find("EGL_PLATFORM_"), std::string::npos);
  EXPECT_NE(d.find("GL_RENDERER"), std::string::npos);
}

class FrontoParallelPlane : public ::testing::TestWithParam<double> {};

TEST_P(FrontoParallelPlane, EveryPixelAtTheDistance) {
  egl();
  const double dist = GetParam();
  Scene scene(mjcf(plane_box({0, 0, dist}, Eigen::Quaterniond::Identity())));
  const CameraIntrinsics k = default_k();
  const DepthRange range;
  DepthRenderer renderer(scene.model, "depth", k, range);
  const DepthImage img = renderer.render(scene.data);
  ASSERT_EQ(img.width, 1280);
  ASSERT_EQ(img.height, 720);
  ASSERT_EQ(img.depth_m.size(), 1280u * 720u);
  double max_err_mm = 0.0;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      max_err_mm = std::max(max_err_mm, 1e3 * std::abs(img.at(u, v) - dist));
    }
  }
  std::printf("plane at %.2f m: max |error| %.5f mm over %d pixels\n", dist, max_err_mm,
              k.width * k.height);
  EXPECT_LT(max_err_mm, 1.0);
}

INSTANTIATE_TEST_SUITE_P(Distances, FrontoParallelPlane, ::testing::Values(0.8, 1.5));

// A plane tilted by 40 degrees about an axis between x and y: depth changes by 1-6 mm per pixel
// in both image directions, so a half-pixel error of the projection would show.
struct Tilted {
  Eigen::Vector3d p0{0.05, -0.03, 1.0};
  Eigen::Quaterniond q{Eigen::AngleAxisd(40.0 * kPi / 180.0, Eigen::Vector3d(1, 0.5, 0).normalized())};
  Eigen::Vector3d n() const { return q * Eigen::Vector3d::UnitZ(); }
};

void run_tilted(const CameraIntrinsics& k, const char* label) {
  egl();
  const Tilted plane;
  Scene scene(mjcf(plane_box(plane.p0, plane.q)));
  const DepthRange range;
  DepthRenderer renderer(scene.model, "depth", k, range);
  const DepthImage img = renderer.render(scene.data);
  const PlaneStats s = check_plane(img, k, range, plane.p0, plane.n());
  std::printf("tilted plane (%s, cx=%g cy=%g): %ld pixels checked, max |error| %.5f mm, %ld "
              "validity mismatches\n",
              label, k.cx, k.cy, s.checked, s.max_err_mm, s.wrong_validity);
  EXPECT_GT(s.checked, k.width * k.height / 2);
  EXPECT_EQ(s.wrong_validity, 0);
  EXPECT_LT(s.max_err_mm, 1.0);
}

TEST(DepthRendererTest, TiltedPlaneMatchesRayPlaneIntersection) { run_tilted(default_k(), "centred"); }

TEST(DepthRendererTest, TiltedPlaneOffCentrePrincipalPoint) {
  CameraIntrinsics k;
  k.cx = 600;
  k.cy = 380;
  run_tilted(k, "off-centre");
}

TEST(DepthRendererTest, TiltedPlaneSmallOddImageFractionalPrincipalPoint) {
  CameraIntrinsics k;
  k.width = 641;
  k.height = 479;
  k.fx = k.fy = 500.0;
  k.cx = 300.3;
  k.cy = 250.8;
  run_tilted(k, "641x479");
}

// Sphere against the analytic sphere. MuJoCo draws a sphere as a latitude-longitude polyhedron
// whose vertices lie on the sphere (numslices azimuth steps, numstacks elevation bands over the
// whole sphere). It is convex and inscribed, so it lies between the true sphere (radius r) and
// the ball of radius r_in = r cos(theta), theta bounding the angular circumradius of a facet:
//   quads: sqrt((pi / numslices)^2 + (pi / (2 numstacks))^2); pole triangles: pi / numstacks.
// Hence for every pixel:
//   - ray misses the r-sphere        -> nothing may be rendered;
//   - ray hits the r_in-sphere       -> something must be rendered, with depth between the two
//                                       analytic first hits t_r <= z <= t_in;
//   - otherwise (rim annulus)        -> either; these are the only allowed silhouette
//                                       mismatches and lie within a pixel of the analytic rim.
// The 1 mm depth tolerance then holds wherever t_in - t_r < 1 mm, i.e. everywhere but a thin rim
// band where the rays graze the facets; those pixels are bounded by the bracket instead.
struct SphereStats {
  long both_hit = 0;
  long within_1mm = 0;
  long beyond_1mm_in_rim_band = 0;
  long beyond_1mm_elsewhere = 0;
  long outside_bracket = 0;
  long silhouette_mismatch = 0;
  long mismatch_not_near_rim = 0;
  long rendered_outside_sphere = 0;
  long missing_inside_inner = 0;
  double max_err_mm = 0.0;           // over all both-hit pixels
  double max_err_interior_mm = 0.0;  // over pixels with t_in - t_r < 1 mm
  double max_err_core_mm = 0.0;      // over pixels with t_in - t_r < 0.05 mm (away from the rim)
  long core = 0;
  long rim_pixels = 0;               // pixels on the analytic silhouette boundary
};

SphereStats check_sphere(const DepthImage& img, const CameraIntrinsics& k, const Eigen::Vector3d& c,
                         double r, int slices, int stacks) {
  const double theta = std::max(std::hypot(kPi / slices, kPi / (2.0 * stacks)), kPi / stacks);
  const double r_in = r * std::cos(theta);
  const double tol = 1e-4;  // 0.1 mm: depth quantisation and float vertex rounding
  SphereStats s;
  auto hits = [&](int u, int v) { return sphere_depth(k, u, v, c, r) > 0; };
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const double t_r = sphere_depth(k, u, v, c, r);
      const double t_in = sphere_depth(k, u, v, c, r_in);
      const double z = img.at(u, v);
      const bool rendered = z > 0;
      const bool hit = t_r > 0;
      bool near_rim = false;
      for (int dv = -1; dv <= 1 && !near_rim; ++dv) {
        for (int du = -1; du <= 1 && !near_rim; ++du) {
          const int uu = u + du, vv = v + dv;
          if (uu < 0 || vv < 0 || uu >= k.width || vv >= k.height) continue;
          near_rim = hits(uu, vv) != hit;
        }
      }
      if (near_rim && hit) ++s.rim_pixels;
      if (rendered != hit) {
        ++s.silhouette_mismatch;
        if (!near_rim) ++s.mismatch_not_near_rim;
      }
      if (rendered && !hit) ++s.rendered_outside_sphere;
      if (!rendered && t_in > 0) ++s.missing_inside_inner;
      if (!(rendered && hit)) continue;
      ++s.both_hit;
      const double err_mm = 1e3 * std::abs(z - t_r);
      s.max_err_mm = std::max(s.max_err_mm, err_mm);
      if (z < t_r - tol || (t_in > 0 && z > t_in + tol)) ++s.outside_bracket;
      const bool interior = t_in > 0 && t_in - t_r < 1e-3;
      if (interior) s.max_err_interior_mm = std::max(s.max_err_interior_mm, err_mm);
      if (t_in > 0 && t_in - t_r < 5e-5) {
        s.max_err_core_mm = std::max(s.max_err_core_mm, err_mm);
        ++s.core;
      }
      if (err_mm < 1.0) {
        ++s.within_1mm;
      } else if (interior) {
        ++s.beyond_1mm_elsewhere;
      } else {
        ++s.beyond_1mm_in_rim_band;
      }
    }
  }
  return s;
}

void run_sphere(const CameraIntrinsics& k, const Eigen::Vector3d& c, const char* label) {
  egl();
  const double r = 0.15;
  const int slices = 256, stacks = 256;
  const std::string quality = "  <visual><quality numslices=\"" + std::to_string(slices) +
                              "\" numstacks=\"" + std::to_string(stacks) + "\"/></visual>\n";
  Scene scene(mjcf("    <geom type=\"sphere\" size=\"" + fmt(r) + "\" pos=\"" + fmt(c.x()) + " " +
                       fmt(c.y()) + " " + fmt(c.z()) + "\"/>\n",
                   quality));
  const DepthRange range;
  DepthRenderer renderer(scene.model, "depth", k, range);
  const DepthImage img = renderer.render(scene.data);
  const SphereStats s = check_sphere(img, k, c, r, slices, stacks);
  std::printf(
      "sphere (%s, cx=%g cy=%g): %ld both-hit pixels, max |error| %.4f mm (interior %.4f mm; "
      "%ld core pixels %.4f mm), "
      "%ld beyond 1 mm (all in the rim band: %ld), %ld outside the tessellation bracket; "
      "silhouette mismatches %ld of %ld rim pixels (%ld not adjacent to the rim)\n",
      label, k.cx, k.cy, s.both_hit, s.max_err_mm, s.max_err_interior_mm, s.core,
      s.max_err_core_mm,
      s.beyond_1mm_in_rim_band + s.beyond_1mm_elsewhere, s.beyond_1mm_in_rim_band,
      s.outside_bracket, s.silhouette_mismatch, s.rim_pixels, s.mismatch_not_near_rim);
  EXPECT_GT(s.both_hit, 30000);
  EXPECT_EQ(s.beyond_1mm_elsewhere, 0);
  EXPECT_EQ(s.outside_bracket, 0);
  EXPECT_LT(s.max_err_interior_mm, 1.0);
  EXPECT_GT(s.core, s.both_hit * 9 / 10);
  EXPECT_LT(s.max_err_core_mm, 0.1);
  // Rim band pixels beyond 1 mm: rays grazing the facets; at most a thin ring.
  EXPECT_LE(s.beyond_1mm_in_rim_band, s.rim_pixels);
  // Silhouette: only pixels adjacent to the analytic rim may disagree, and only few of them
  // (the annulus between r_in and r is ~0.014 mm wide, ~1/80 pixel).
  EXPECT_EQ(s.mismatch_not_near_rim, 0);
  EXPECT_EQ(s.rendered_outside_sphere, 0);
  EXPECT_EQ(s.missing_inside_inner, 0);
  EXPECT_LE(s.silhouette_mismatch, s.rim_pixels / 20 + 2);
}

TEST(DepthRendererTest, SphereMatchesRaySphereIntersection) {
  run_sphere(default_k(), {0.0, 0.0, 0.9}, "centred");
}

TEST(DepthRendererTest, SphereOffAxisOffCentrePrincipalPoint) {
  CameraIntrinsics k;
  k.cx = 600;
  k.cy = 380;
  run_sphere(k, {0.25, -0.12, 0.9}, "off-centre");
}

TEST(DepthRendererTest, BackProjectedPixelsLieOnThePlane) {
  egl();
  const Tilted plane;
  Scene scene(mjcf(plane_box(plane.p0, plane.q)));
  CameraIntrinsics k;
  k.cx = 600;
  k.cy = 380;
  DepthRenderer renderer(scene.model, "depth", k, DepthRange{});
  const DepthImage img = renderer.render(scene.data);
  double max_dist_mm = 0.0;
  long n = 0;
  for (int v = 0; v < k.height; v += 3) {
    for (int u = 0; u < k.width; u += 3) {
      const double z = img.at(u, v);
      if (z <= 0) continue;
      const Eigen::Vector3d p = back_project(k, u, v, z);
      max_dist_mm = std::max(max_dist_mm, 1e3 * std::abs(plane.n().dot(p - plane.p0)));
      ++n;
    }
  }
  std::printf("back-projection: %ld points, max distance to the plane %.5f mm\n", n, max_dist_mm);
  EXPECT_GT(n, 10000);
  EXPECT_LT(max_dist_mm, 1.0);
}

// The driver library's camera for a test frame of `k` (range 0.1..3 m), as a driver sends it.
driver::DepthCamera contract_camera(const CameraIntrinsics& k) {
  driver::DepthCamera camera;
  camera.width = k.width;
  camera.height = k.height;
  camera.fx = k.fx;
  camera.fy = k.fy;
  camera.cx = k.cx;
  camera.cy = k.cy;
  camera.depth_min_m = 0.1;
  camera.depth_max_m = 3.0;
  return camera;
}

// A strongly distorted camera (k1 -0.35: a wide time-of-flight lens's order, stronger) in the twin:
// the pinhole image covering the lens rendered, resampled through it, sent as a DEPTH_FRAME that
// says so (0.1 mm counts), decoded as every service decodes it (undistorted): the tilted plane's
// back-projected points lie on it within 0.2 mm (the counts' 0.05 mm and the renderer's own 1 mm
// bound above, here much tighter). Back-projected without the lens, the same frame is 10s of mm off.
TEST(DepthRendererTest, ThroughAStrongLensThePipelineSeesAFlatPlane) {
  egl();
  const Tilted plane;
  Scene scene(mjcf(plane_box(plane.p0, plane.q)));
  CameraIntrinsics k;
  k.width = 640;
  k.height = 480;
  k.fx = k.fy = 520;  // the image's corner at 0.77 (normalised): inside where this lens is one
  k.cx = 320;
  k.cy = 240;
  const LensDistortion lens{-0.35, 0.15, 0.0012, -0.0018, -0.03};
  const CameraIntrinsics cover = pinhole_cover(k, lens);
  DepthRenderer renderer(scene.model, "depth", cover, DepthRange{});
  const DepthImage seen = through_lens(renderer.render(scene.data), cover, k, lens);
  driver::DepthCamera camera = contract_camera(k);
  camera.distortion = lens.coefficients();
  depth_trigger_t trigger{};
  trigger.seq = 1;
  const depth_frame_t frame = driver::depth_frame(camera, driver::depth_counts(seen.depth_m, 1e-4), driver::Exposure{}, 1, trigger);
  EXPECT_EQ(frame.distortion[0], -0.35);  // the frame says which lens
  const bus::DecodedFrame decoded = bus::decode_frame(frame);
  double worst_mm = 0, naive_mm = 0;
  long n = 0;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * k.width + u;
      if (decoded.depth_m[i] > 0) {
        const Eigen::Vector3d p = back_project(k, u, v, decoded.depth_m[i]);
        worst_mm = std::max(worst_mm, 1e3 * std::abs(plane.n().dot(p - plane.p0)));
        ++n;
      }
      if (seen.depth_m[i] > 0) {
        const Eigen::Vector3d q = back_project(k, u, v, seen.depth_m[i]);
        naive_mm = std::max(naive_mm, 1e3 * std::abs(plane.n().dot(q - plane.p0)));
      }
    }
  }
  std::printf("through the lens: %ld points, max %.4f mm from the plane (without undistorting: %.1f mm)\n", n, worst_mm,
              naive_mm);
  EXPECT_GT(n, static_cast<long>(0.95 * k.width * k.height));
  EXPECT_LT(worst_mm, 0.2);
  EXPECT_GT(naive_mm, 10.0);
}

// A two-coloured object, red for x > 0 and blue for x < 0 (two boxes side by side, 0.5 m ahead),
// seen by a colour sensor 15 mm to the right of the depth sensor, sent as a DEPTH_FRAME with its
// JPEG and decoded as the camera service does: every point more than 2 mm from the seam takes its
// own half's colour (those within 5 mm of the outline left out: JPEG's half-resolution chroma
// blurs the outline's pixels into the black background, as a real camera's does; raw R G B
// gives every point its colour). Ignoring where the colour sensor sits, the points within 15 mm
// left of the seam would read the red of the points 15 mm to their right (the test can fail).
TEST(DepthRendererTest, ATwoColouredObjectComesOutWithTheColoursOnTheRightHalves) {
  egl();
  const std::string boxes =
      "    <geom type=\"box\" size=\"0.05 0.05 0.01\" pos=\"0.05 0 0.51\" rgba=\"0.9 0.1 0.1 1\"/>\n"
      "    <geom type=\"box\" size=\"0.05 0.05 0.01\" pos=\"-0.05 0 0.51\" rgba=\"0.1 0.1 0.9 1\"/>\n";
  Scene scene(mjcf(boxes));
  CameraIntrinsics k;
  k.width = 320;
  k.height = 240;
  k.fx = k.fy = 300;
  k.cx = 160;
  k.cy = 120;
  DepthRenderer renderer(scene.model, "depth", k, DepthRange{});
  const DepthImage depth = renderer.render(scene.data);
  ColourImage colour;
  colour.intrinsics = k;
  colour.depth_T_colour.translation() = Eigen::Vector3d(0.015, 0, 0);
  colour.rgb = renderer.render_colour(scene.data, k, colour.depth_T_colour);
  driver::DepthCamera camera = contract_camera(k);
  depth_trigger_t trigger{};
  trigger.seq = 1;
  depth_frame_t frame = driver::depth_frame(camera, driver::depth_counts(depth.depth_m, 1e-4), driver::Exposure{}, 1, trigger);
  bus::set_colour(frame, colour, frame.utime, depth_frame_t::kColourJpeg);
  const DepthFrame decoded = bus::from_msg(frame);
  ASSERT_TRUE(decoded.colour);
  PointCloud points;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const float z = decoded.depth_m[static_cast<std::size_t>(v) * k.width + u];
      if (z > 0) points.push_back(back_project(k, u, v, z).cast<float>());
    }
  }
  const auto count = [&](const std::vector<Rgb>& c, auto&& in, auto&& ok) {
    long n = 0, good = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!in(points[i].x()) || std::abs(points[i].x()) > 0.095f || std::abs(points[i].y()) > 0.045f) continue;
      ++n;
      good += ok(c[i]) ? 1 : 0;
    }
    return std::make_pair(n, good);
  };
  const auto red = [](const Rgb& c) { return c[0] > 2 * c[2]; };
  const auto blue = [](const Rgb& c) { return c[2] > 2 * c[0]; };
  const std::vector<Rgb> c = point_colours(points, *decoded.colour, Pose::Identity());
  const auto [nr, r] = count(c, [](float x) { return x > 0.002f; }, red);
  const auto [nb, b] = count(c, [](float x) { return x < -0.002f; }, blue);
  std::printf("colour: %ld of %ld points right of the seam red, %ld of %ld left of it blue\n", r, nr, b, nb);
  EXPECT_GT(nr, 2800);  // 60 x 60 pixels a half, less the outline's
  EXPECT_GT(nb, 2800);
  EXPECT_EQ(r, nr);
  EXPECT_EQ(b, nb);
  // The colour sensor taken to be where the depth sensor is: the band left of the seam reads red.
  ColourImage misplaced = *decoded.colour;
  misplaced.depth_T_colour = Pose::Identity();
  const std::vector<Rgb> wrong = point_colours(points, misplaced, Pose::Identity());
  const auto [nband, red_band] = count(wrong, [](float x) { return x < -0.003f && x > -0.012f; }, red);
  EXPECT_GT(nband, 250);  // 9 mm = 5.4 pixels wide, 54 rows
  EXPECT_EQ(red_band, nband);
}

// ------------------------------------------------------------------------------------------------
// What must not be seen.

TEST(DepthRendererTest, PlaneBeyondMaxRangeGivesZeros) {
  egl();
  Scene scene(mjcf(plane_box({0, 0, 4.0}, Eigen::Quaterniond::Identity())));
  DepthRange range;  // 0.1 .. 3 m
  DepthRenderer renderer(scene.model, "depth", default_k(), range);
  const DepthImage img = renderer.render(scene.data);
  long nonzero = 0;
  for (float z : img.depth_m) nonzero += z != 0.0f;
  EXPECT_EQ(nonzero, 0);
}

TEST(DepthRendererTest, PlaneNearerThanMinRangeGivesZeros) {
  egl();
  Scene scene(mjcf(plane_box({0, 0, 0.8}, Eigen::Quaterniond::Identity())));
  DepthRange range;
  range.min_m = 1.0;
  DepthRenderer renderer(scene.model, "depth", default_k(), range);
  const DepthImage img = renderer.render(scene.data);
  long nonzero = 0;
  for (float z : img.depth_m) nonzero += z != 0.0f;
  EXPECT_EQ(nonzero, 0);
}

// Skybox, lights, sites, joints, group-3 geoms and alpha-0 geoms in front of a plane at 0.8 m
// must leave the plane depth untouched everywhere.
TEST(DepthRendererTest, OnlyGeomGroupsZeroToTwoAreRendered) {
  egl();
  const std::string assets =
      "  <asset><texture type=\"skybox\" builtin=\"gradient\" rgb1=\"1 1 1\" rgb2=\"0 0 0\" "
      "width=\"64\" height=\"64\"/></asset>\n"
      "  <visual><headlight active=\"1\"/></visual>\n";
  const std::string world =
      plane_box({0, 0, 0.8}, Eigen::Quaterniond::Identity()) +
      "    <light pos=\"0 0 0.3\" dir=\"0 0 1\"/>\n"
      "    <site name=\"big_site\" type=\"sphere\" size=\"0.2\" pos=\"0 0 0.5\" group=\"0\"/>\n"
      "    <geom name=\"helper\" type=\"box\" size=\"1 1 0.01\" pos=\"0 0 0.4\" group=\"3\"/>\n"
      "    <geom name=\"housing\" type=\"sphere\" size=\"0.2\" pos=\"0.1 0 0.5\" group=\"4\"/>\n"
      "    <geom name=\"hidden\" type=\"box\" size=\"1 1 0.01\" pos=\"0 0 0.3\" rgba=\"1 0 0 0\"/>\n"
      "    <body name=\"free\" pos=\"0 0 0.6\"><freejoint/>\n"
      "      <geom type=\"sphere\" size=\"0.05\" group=\"5\"/>\n"
      "      <site type=\"box\" size=\"0.2 0.2 0.01\"/></body>\n";
  Scene scene(mjcf(world, assets));
  DepthRenderer renderer(scene.model, "depth", default_k(), DepthRange{});
  const DepthImage img = renderer.render(scene.data);
  double max_err_mm = 0.0;
  for (float z : img.depth_m) max_err_mm = std::max(max_err_mm, 1e3 * std::abs(z - 0.8));
  std::printf("decorations/group 3-5 scene: max |error| vs plane %.5f mm\n", max_err_mm);
  EXPECT_LT(max_err_mm, 1.0);
}

TEST(DepthRendererTest, GroupTwoAndTranslucentGeomsAreRenderedSkyboxIsZero) {
  egl();
  const std::string assets =
      "  <asset><texture type=\"skybox\" builtin=\"gradient\" rgb1=\"1 1 1\" rgb2=\"0 0 0\" "
      "width=\"64\" height=\"64\"/></asset>\n";
  // A group-2 box covering the left half at 0.6 m and a translucent box covering the bottom-
  // right quadrant at 0.7 m; the top-right quadrant sees only the skybox.
  const std::string world =
      "    <geom type=\"box\" size=\"1 1 0.01\" pos=\"-1 0 0.61\" group=\"2\"/>\n"
      "    <geom type=\"box\" size=\"1 1 0.01\" pos=\"1 1 0.71\" rgba=\"0 1 0 0.3\"/>\n";
  Scene scene(mjcf(world, assets));
  const CameraIntrinsics k = default_k();
  DepthRenderer renderer(scene.model, "depth", k, DepthRange{});
  const DepthImage img = renderer.render(scene.data);
  EXPECT_NEAR(img.at(100, 100), 0.6, 1e-3);
  EXPECT_NEAR(img.at(100, 600), 0.6, 1e-3);
  EXPECT_NEAR(img.at(1000, 600), 0.7, 1e-3);
  EXPECT_EQ(img.at(1000, 100), 0.0f);
  EXPECT_EQ(img.at(1279, 0), 0.0f);
}

// ------------------------------------------------------------------------------------------------
// Errors.

TEST(DepthRendererTest, UnequalFocalLengthsThrowNamingThem) {
  egl();
  Scene scene(mjcf(plane_box({0, 0, 1.0}, Eigen::Quaterniond::Identity())));
  CameraIntrinsics k;
  k.fy = 700.0;
  try {
    DepthRenderer renderer(scene.model, "depth", k, DepthRange{});
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("fx"), std::string::npos) << msg;
    EXPECT_NE(msg.find("fy"), std::string::npos) << msg;
    EXPECT_NE(msg.find("696"), std::string::npos) << msg;
    EXPECT_NE(msg.find("700"), std::string::npos) << msg;
  }
}

TEST(DepthRendererTest, UnknownCameraThrowsNamingIt) {
  egl();
  Scene scene(mjcf(plane_box({0, 0, 1.0}, Eigen::Quaterniond::Identity())));
  try {
    DepthRenderer renderer(scene.model, "no_such_camera", default_k(), DepthRange{});
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_camera"), std::string::npos) << e.what();
  }
}

TEST(DepthRendererTest, BadIntrinsicsAndRangeThrow) {
  egl();
  Scene scene(mjcf(plane_box({0, 0, 1.0}, Eigen::Quaterniond::Identity())));
  CameraIntrinsics k;
  k.width = 0;
  EXPECT_THROW(DepthRenderer(scene.model, "depth", k, DepthRange{}), std::invalid_argument);
  k = CameraIntrinsics{};
  k.cx = -5;
  EXPECT_THROW(DepthRenderer(scene.model, "depth", k, DepthRange{}), std::invalid_argument);
  DepthRange range;
  range.max_m = 0.05;
  EXPECT_THROW(DepthRenderer(scene.model, "depth", CameraIntrinsics{}, range),
               std::invalid_argument);
  EXPECT_THROW(DepthRenderer(nullptr, "depth", CameraIntrinsics{}, DepthRange{}),
               std::invalid_argument);
}

TEST(DepthRendererTest, RendersRepeatedlyAndFollowsTheData) {
  egl();
  // The plane hangs from a slide joint along the optical axis.
  const std::string world =
      "    <body name=\"target\" pos=\"0 0 1.0\">\n"
      "      <joint name=\"slide\" type=\"slide\" axis=\"0 0 1\"/>\n"
      "      <geom type=\"box\" size=\"10 10 0.01\" pos=\"0 0 0.01\"/>\n"
      "    </body>\n";
  Scene scene(mjcf(world));
  DepthRenderer renderer(scene.model, "depth", default_k(), DepthRange{});
  EXPECT_NEAR(renderer.render(scene.data).at(640, 360), 1.0, 1e-4);
  scene.data->qpos[0] = 0.5;
  mj_forward(scene.model, scene.data);
  const DepthImage img = renderer.render(scene.data);
  EXPECT_NEAR(img.at(640, 360), 1.5, 1e-4);
  EXPECT_NEAR(img.at(0, 0), 1.5, 1e-4);
}

// ------------------------------------------------------------------------------------------------
// Noise (no rendering needed).

DepthImage constant_image(float z) {
  DepthImage img;
  img.width = 1280;
  img.height = 720;
  img.depth_m.assign(1280u * 720u, z);
  return img;
}

TEST(DepthNoiseTest, DepthProportionalSigma) {
  DepthImage img = constant_image(1.0f);
  std::mt19937_64 rng(42);
  apply_depth_noise(img, DepthNoise{0.01, 0.0}, rng);
  double sum = 0, sum2 = 0;
  for (float z : img.depth_m) {
    sum += z - 1.0;
    sum2 += (z - 1.0) * (z - 1.0);
  }
  const double n = static_cast<double>(img.depth_m.size());
  const double mean = sum / n;
  const double sd = std::sqrt(sum2 / n - mean * mean);
  std::printf("noise at 1 m: mean %.6f m, std %.6f m\n", mean, sd);
  EXPECT_NEAR(sd, 0.01, 0.05 * 0.01);
  EXPECT_NEAR(mean, 0.0, 1e-4);

  // Proportional: at 2 m the sigma doubles.
  DepthImage far = constant_image(2.0f);
  apply_depth_noise(far, DepthNoise{0.01, 0.0}, rng);
  double s2 = 0;
  for (float z : far.depth_m) s2 += (z - 2.0) * (z - 2.0);
  EXPECT_NEAR(std::sqrt(s2 / n), 0.02, 0.05 * 0.02);
}

TEST(DepthNoiseTest, DropoutFraction) {
  DepthImage img = constant_image(1.0f);
  std::mt19937_64 rng(7);
  apply_depth_noise(img, DepthNoise{0.0, 0.3}, rng);
  long dropped = 0;
  for (float z : img.depth_m) {
    if (z == 0.0f) {
      ++dropped;
    } else {
      EXPECT_EQ(z, 1.0f);
    }
  }
  const double fraction = static_cast<double>(dropped) / img.depth_m.size();
  std::printf("dropout 0.3: dropped fraction %.5f\n", fraction);
  EXPECT_NEAR(fraction, 0.3, 0.01);
}

TEST(DepthNoiseTest, DeterministicLeavesInvalidPixelsAndOffIsIdentity) {
  DepthImage a = constant_image(1.0f);
  for (std::size_t i = 0; i < a.depth_m.size(); i += 5) a.depth_m[i] = 0.0f;
  DepthImage b = a;
  const DepthImage original = a;
  std::mt19937_64 ra(123), rb(123);
  apply_depth_noise(a, DepthNoise{0.02, 0.1}, ra);
  apply_depth_noise(b, DepthNoise{0.02, 0.1}, rb);
  EXPECT_EQ(a.depth_m, b.depth_m);
  for (std::size_t i = 0; i < a.depth_m.size(); i += 5) EXPECT_EQ(a.depth_m[i], 0.0f);

  DepthImage c = original;
  std::mt19937_64 rc(1);
  apply_depth_noise(c, DepthNoise{}, rc);
  EXPECT_EQ(c.depth_m, original.depth_m);
  EXPECT_THROW(apply_depth_noise(c, DepthNoise{-1.0, 0.0}, rc), std::invalid_argument);
  EXPECT_THROW(apply_depth_noise(c, DepthNoise{0.0, 1.5}, rc), std::invalid_argument);
}

}  // namespace
}  // namespace pbnbv::twin
