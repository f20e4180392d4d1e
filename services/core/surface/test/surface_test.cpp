// TSDF fusion and mesh topology on frames whose geometry is known exactly: a sphere seen from six
// directions (closed), a plane seen once (one open rim), and the topology of hand-made meshes.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/base/units.hpp"
#include "core/surface/mesh_topology.hpp"
#include "core/surface/surface.hpp"

namespace pbnbv {
namespace {

// A small camera (fast) that sees the test objects from 0.5 m.
CameraIntrinsics small_camera() {
  CameraIntrinsics k;
  k.width = 320;
  k.height = 240;
  k.fx = k.fy = 300;
  k.cx = 159.5;
  k.cy = 119.5;
  return k;
}

// The points a camera at object_T_camera sees on the sphere (centre 0, radius r): one per pixel.
SurfaceFrame sphere_frame(const CameraIntrinsics& k, const Pose& object_T_camera, double r) {
  SurfaceFrame f;
  f.object_T_camera = object_T_camera;
  const Eigen::Vector3d c = object_T_camera.inverse() * Eigen::Vector3d::Zero();  // centre, camera frame
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d d = back_project(k, u, v, 1.0).normalized();
      const double b = d.dot(c), disc = b * b - (c.squaredNorm() - r * r);
      if (disc < 0) continue;
      const Eigen::Vector3d q = (b - std::sqrt(disc)) * d;
      f.points.push_back((object_T_camera * q).cast<float>());
    }
  return f;
}

TEST(Tsdf, SphereFromSixDirectionsIsClosedAtItsRadius) {
  const double r = 0.1;
  SurfaceSettings s;
  s.camera = small_camera();
  s.voxel_m = 0.004;
  std::vector<SurfaceFrame> frames;
  for (const Eigen::Vector3d& eye : {Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d(-0.5, 0, 0), Eigen::Vector3d(0, 0.5, 0),
                                    Eigen::Vector3d(0, -0.5, 0), Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d(0, 0, -0.5)}) {
    frames.push_back(sphere_frame(s.camera, look_at_z_up(eye, Eigen::Vector3d::Zero()), r));
  }
  const TriangleMesh mesh = fuse_tsdf(frames, s);
  ASSERT_GT(mesh.triangles.size(), 1000u);
  for (const auto& p : mesh.vertices) ASSERT_NEAR(p.norm(), r, s.voxel_m) << p.transpose();
  const MeshTopology t = mesh_topology(mesh);
  EXPECT_EQ(t.boundary_edges, 0u);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(t.boundary_loops, 0u);
  EXPECT_TRUE(t.watertight);
  // 4/3 pi r^3 = 4.18879 l; outward triangles give a positive volume. Marching cubes cuts the
  // sphere's caps between grid points: 2 % is about 3 % of a voxel of radius error.
  const double volume = 4.0 / 3.0 * kPi * r * r * r;
  EXPECT_NEAR(t.volume_m3, volume, 0.02 * volume);
  EXPECT_NEAR(t.area_m2, 4 * kPi * r * r, 0.03 * 4 * kPi * r * r);
  // Vertex normals point outwards, along the radius.
  const auto n = vertex_normals(mesh);
  for (std::size_t i = 0; i < n.size(); i += 97) EXPECT_GT(n[i].dot(mesh.vertices[i].normalized()), 0.95);
}

TEST(Tsdf, PlaneSeenOnceIsOneOpenSheet) {
  // A 0.2 x 0.2 m square at z = 0 seen from 0.5 m above, filling part of the image.
  SurfaceSettings s;
  s.camera = small_camera();
  s.voxel_m = 0.004;
  SurfaceFrame f;
  f.object_T_camera = look_at(Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY());
  for (int v = 0; v < s.camera.height; ++v)
    for (int u = 0; u < s.camera.width; ++u) {
      const Eigen::Vector3d d = f.object_T_camera.linear() * back_project(s.camera, u, v, 1.0);
      const Eigen::Vector3d p = f.object_T_camera.translation() + d * (-0.5 / d.z());
      if (std::abs(p.x()) <= 0.1 && std::abs(p.y()) <= 0.1) f.points.push_back(p.cast<float>());
    }
  const TriangleMesh mesh = fuse_tsdf({f}, s);
  ASSERT_GT(mesh.triangles.size(), 500u);
  for (const auto& p : mesh.vertices) ASSERT_NEAR(p.z(), 0.0, 0.5 * s.voxel_m);
  const MeshTopology t = mesh_topology(mesh);
  EXPECT_FALSE(t.watertight);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(t.boundary_loops, 1u);
  // The rim runs round the square, within a voxel and a half of its edges (the last cube with
  // every corner seen), no longer than a staircase's 4 * 0.2 * 1.5.
  EXPECT_GT(t.boundary_length_m, 4 * (0.2 - 2 * 1.5 * s.voxel_m));
  EXPECT_LT(t.boundary_length_m, 4 * 0.2 * 1.5);
  // Area: the square within a voxel and a half of its edges.
  EXPECT_GT(t.area_m2, (0.2 - 3 * s.voxel_m) * (0.2 - 3 * s.voxel_m));
  EXPECT_LT(t.area_m2, (0.2 + 3 * s.voxel_m) * (0.2 + 3 * s.voxel_m));
  // The normals face the camera (+z).
  for (const auto& n : vertex_normals(mesh)) ASSERT_GT(n.z(), 0.9);
}

TEST(MeshTopology, ClosedBoxOpenBoxAndTwoHoles) {
  TriangleMesh box = make_box(Eigen::Vector3d(0.1, 0.2, 0.3));
  MeshTopology t = mesh_topology(box);
  EXPECT_TRUE(t.watertight);
  EXPECT_EQ(t.boundary_loops, 0u);
  EXPECT_NEAR(t.volume_m3, 0.1 * 0.2 * 0.3, 1e-12);
  EXPECT_NEAR(t.area_m2, 2 * (0.02 + 0.03 + 0.06), 1e-12);
  // Without the two triangles of one face: one hole, its rim the face's perimeter.
  TriangleMesh open = box;
  std::vector<Eigen::Vector3i> kept;
  for (const auto& tri : open.triangles) {
    bool top = true;
    for (int k = 0; k < 3; ++k) top = top && open.vertices[tri[k]].z() > 0;
    if (!top) kept.push_back(tri);
  }
  ASSERT_EQ(kept.size(), open.triangles.size() - 2);
  open.triangles = kept;
  t = mesh_topology(open);
  EXPECT_FALSE(t.watertight);
  EXPECT_EQ(t.boundary_loops, 1u);
  EXPECT_EQ(t.boundary_edges, 4u);
  EXPECT_NEAR(t.boundary_length_m, 2 * (0.1 + 0.2), 1e-12);
  // The hole filled (its rim 0.6 m): closed again, the same volume (the fan lies in the face).
  EXPECT_EQ(fill_small_holes(open, 0.5), 0u);
  EXPECT_EQ(fill_small_holes(open, 0.7), 1u);
  t = mesh_topology(open);
  EXPECT_TRUE(t.watertight);
  EXPECT_NEAR(t.volume_m3, 0.1 * 0.2 * 0.3, 1e-12);
  // Two separate triangles: two loops of three edges.
  TriangleMesh two;
  two.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 0, 0}, {6, 0, 0}, {5, 1, 0}};
  two.triangles = {{0, 1, 2}, {3, 4, 5}};
  t = mesh_topology(two);
  EXPECT_EQ(t.boundary_loops, 2u);
  EXPECT_NEAR(t.boundary_length_m, 2 * (2 + std::sqrt(2.0)), 1e-12);
  EXPECT_EQ(remove_small_components(two, 2), 2u);
  EXPECT_TRUE(two.triangles.empty());
}

// A 0.2 x 0.2 m square at z = 0 seen from a camera 0.5 m away, tilted 30 degrees from its normal;
// each reading pushed along its ray by Gaussian noise of `sigma` (seed `seed`).
SurfaceFrame tilted_plane_frame(const CameraIntrinsics& k, double sigma, unsigned seed) {
  SurfaceFrame f;
  const double tilt = 30 * kPi / 180;
  f.object_T_camera = look_at(Eigen::Vector3d(0, -0.5 * std::sin(tilt), 0.5 * std::cos(tilt)), Eigen::Vector3d::Zero(),
                              Eigen::Vector3d::UnitY());
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d ray = back_project(k, u, v, 1.0);  // camera frame, z = 1
      const Eigen::Vector3d d = f.object_T_camera.linear() * ray;
      const double t = -f.object_T_camera.translation().z() / d.z();  // depth along the camera's z
      const Eigen::Vector3d p = f.object_T_camera.translation() + d * t;
      if (std::abs(p.x()) > 0.1 || std::abs(p.y()) > 0.1) continue;
      f.points.push_back((f.object_T_camera * (ray * (t + noise(rng)))).cast<float>());
    }
  return f;
}

TEST(Tsdf, AFramesDepthNoiseIsMeasuredOnItsOwnImage) {
  SurfaceSettings s;
  s.camera = small_camera();
  s.voxel_m = 0.002;
  // Exact readings: the tilted plane's depth changes almost linearly across the image (its second
  // difference is 2 (tan 30 / 300)^2 x 0.5 m = 4 um at most), so the noise reads as nothing and the
  // normals take the next pixels.
  const FrameNoise exact = tsdf_frame_noise(tilted_plane_frame(s.camera, 0.0, 1), s);
  EXPECT_LT(exact.sigma_m, 0.02e-3);
  EXPECT_EQ(exact.normal_step, 1);
  // A pixel at the median depth (0.5 m) is 0.5 / 300 = 1.67 mm wide.
  EXPECT_NEAR(exact.pixel_m, 0.5 / 300, 0.1 / 300);
  // 2 mm of noise reads as 2 mm (the median of 6^(1/2) sigma |N(0,1)| over ~15,000 triples: within
  // 5 %), and the normals span 4 sigma = 8 mm: ceil(8 / 1.67) = 5 pixels.
  const FrameNoise noisy = tsdf_frame_noise(tilted_plane_frame(s.camera, 0.002, 1), s);
  EXPECT_NEAR(noisy.sigma_m, 0.002, 0.05 * 0.002);
  EXPECT_EQ(noisy.normal_step, int(std::ceil(4 * noisy.sigma_m / noisy.pixel_m)));
  EXPECT_EQ(noisy.normal_step, 5);
}

TEST(Tsdf, NoisyFramesOfAPlaneFuseIntoAFlatSheet) {
  // Eight frames of the tilted square, each with 2 mm of independent depth noise. Averaged over
  // eight readings the noise is 2 / 8^(1/2) = 0.71 mm along the ray, 0.61 mm across the plane
  // (cos 30). With normals 5 pixels wide the mesh's vertices lie within 3/4 of that of the plane
  // (RMS; measured 0.41 mm), none beyond 5 times it (2.5 mm, at the rim). With the neighbouring
  // pixels' normals (the step before the noise was measured) the RMS was 0.62 mm and a vertex lay
  // 10 mm off: the noise tilted the normals at random.
  SurfaceSettings s;
  s.camera = small_camera();
  s.voxel_m = 0.002;
  std::vector<SurfaceFrame> frames;
  for (unsigned seed = 1; seed <= 8; ++seed) frames.push_back(tilted_plane_frame(s.camera, 0.002, seed));
  SurfaceStats stats;
  const TriangleMesh mesh = fuse_tsdf(frames, s, &stats);
  ASSERT_GT(mesh.triangles.size(), 5000u);
  EXPECT_NEAR(stats.depth_noise_m, 0.002, 0.05 * 0.002);
  EXPECT_EQ(stats.normal_step, 5);
  double sum2 = 0;
  double worst = 0;
  for (const auto& p : mesh.vertices) {
    sum2 += p.z() * p.z();
    worst = std::max(worst, std::abs(p.z()));
  }
  const double rms = std::sqrt(sum2 / double(mesh.vertices.size()));
  const double across = 0.002 / std::sqrt(8.0) * std::cos(30 * kPi / 180);
  EXPECT_LT(rms, 0.75 * across) << "worst " << worst;
  EXPECT_LT(worst, 5 * across);
}

TEST(Tsdf, RejectsNoPointsAndBadSettings) {
  SurfaceSettings s;
  EXPECT_THROW(fuse_tsdf({SurfaceFrame{}}, s), std::invalid_argument);
  s.voxel_m = -1;
  SurfaceFrame f;
  f.points.push_back(Eigen::Vector3f(0, 0, 1));
  EXPECT_THROW(fuse_tsdf({f}, s), std::invalid_argument);
}

}  // namespace
}  // namespace pbnbv
