// Ellipsoid projection, clipped ellipse area, view scores and global partitioning
// (view_scoring.hpp).
#include "core/planning/view_scoring.hpp"
#include "core/base/units.hpp"
#include "sphere_ellipsoid.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <random>
#include <cstdio>

namespace pbnbv {
namespace {

using testing::sphere_ellipsoid;


CameraIntrinsics small_camera(double fy = 174.0) {
  CameraIntrinsics k;
  k.width = 320;
  k.height = 240;
  k.fx = 174.0;
  k.fy = fy;
  k.cx = 160.0;
  k.cy = 120.0;
  return k;
}

// Silhouette of the ellipsoid by casting ss x ss rays per pixel of the image rectangle
// [0, W] x [0, H]: area (pixels), centroid and second moments of the hit samples.
struct Silhouette {
  double area = 0;
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
};

Silhouette ray_cast(const Ellipsoid& e, const CameraIntrinsics& k, const Pose& object_T_camera,
                    int ss) {
  const Eigen::Matrix3d to_unit =
      e.semi_axes.cwiseInverse().asDiagonal() * e.axes.transpose();  // object -> unit sphere
  const Eigen::Vector3d o = to_unit * (object_T_camera.translation() - e.centre);
  double n = 0;
  Eigen::Vector2d s1 = Eigen::Vector2d::Zero();
  Eigen::Matrix2d s2 = Eigen::Matrix2d::Zero();
  for (int v = 0; v < k.height * ss; ++v) {
    for (int u = 0; u < k.width * ss; ++u) {
      const double x = (u + 0.5) / ss, y = (v + 0.5) / ss;
      const Eigen::Vector3d dir_cam((x - k.cx) / k.fx, (y - k.cy) / k.fy, 1.0);
      const Eigen::Vector3d d = to_unit * (object_T_camera.linear() * dir_cam);
      // |o + t d|^2 = 1 with t > 0.
      const double a = d.squaredNorm(), b = o.dot(d), c = o.squaredNorm() - 1.0;
      const double disc = b * b - a * c;
      if (disc < 0) continue;
      const double t_far = (-b + std::sqrt(disc)) / a;
      if (t_far <= 0) continue;
      n += 1;
      const Eigen::Vector2d p(x, y);
      s1 += p;
      s2 += p * p.transpose();
    }
  }
  Silhouette s;
  const double px = 1.0 / (ss * ss);
  s.area = n * px;
  s.centroid = s1 / n;
  s.covariance = s2 / n - s.centroid * s.centroid.transpose();
  return s;
}

void expect_matches_silhouette(const Ellipsoid& e, const CameraIntrinsics& k, const Pose& pose) {
  const ProjectedEllipse pe = project_ellipsoid(e, k, pose);
  ASSERT_TRUE(pe.valid);
  // Whole ellipse inside the image, so the silhouette is not clipped.
  ASSERT_GT(pe.centre.x() - std::sqrt(pe.shape(0, 0)), 1.0);
  ASSERT_LT(pe.centre.x() + std::sqrt(pe.shape(0, 0)), k.width - 1.0);
  ASSERT_GT(pe.centre.y() - std::sqrt(pe.shape(1, 1)), 1.0);
  ASSERT_LT(pe.centre.y() + std::sqrt(pe.shape(1, 1)), k.height - 1.0);
  ASSERT_GT(pe.semi_axes.y(), 10.0);  // big enough for a meaningful pixel count
  const Silhouette s = ray_cast(e, k, pose, 4);
  EXPECT_NEAR(pe.area_px, s.area, 0.01 * s.area);
  EXPECT_NEAR(pe.area_px, kPi * pe.semi_axes.x() * pe.semi_axes.y(), 1e-9 * pe.area_px);
  EXPECT_NEAR(clipped_ellipse_area(pe, k), pe.area_px, 1e-9 * pe.area_px);
  // A filled ellipse's centroid is its centre and its covariance is shape / 4.
  EXPECT_NEAR(pe.centre.x(), s.centroid.x(), 0.05);
  EXPECT_NEAR(pe.centre.y(), s.centroid.y(), 0.05);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(4.0 * s.covariance);
  EXPECT_NEAR(pe.semi_axes.x(), std::sqrt(es.eigenvalues()(1)), 0.005 * pe.semi_axes.x());
  EXPECT_NEAR(pe.semi_axes.y(), std::sqrt(es.eigenvalues()(0)), 0.005 * pe.semi_axes.y());
  EXPECT_LT((pe.shape - 4.0 * s.covariance).norm(), 0.01 * pe.shape.norm());
  EXPECT_GE(pe.semi_axes.x(), pe.semi_axes.y());
}

TEST(ProjectEllipsoid, SphereOnTheOpticalAxis) {
  const CameraIntrinsics k;  // 1280x720, f = 696
  for (double d : {0.5, 1.0, 2.5}) {
    const double r = 0.1;
    const ProjectedEllipse pe =
        project_ellipsoid(sphere_ellipsoid(Eigen::Vector3d(0, 0, d), r), k, Pose::Identity());
    ASSERT_TRUE(pe.valid);
    const double expected = 696.0 * r / std::sqrt(d * d - r * r);
    EXPECT_NEAR(pe.centre.x(), 640.0, 1e-9);
    EXPECT_NEAR(pe.centre.y(), 360.0, 1e-9);
    EXPECT_NEAR(pe.semi_axes.x(), expected, 1e-9 * expected);
    EXPECT_NEAR(pe.semi_axes.y(), expected, 1e-9 * expected);
    EXPECT_NEAR(pe.area_px, kPi * expected * expected, 1e-9 * pe.area_px);
    EXPECT_NEAR(pe.shape(0, 0), expected * expected, 1e-9 * expected * expected);
    EXPECT_NEAR(pe.shape(0, 1), 0.0, 1e-9 * expected * expected);
    EXPECT_DOUBLE_EQ(pe.depth_m, d);
  }
}

TEST(ProjectEllipsoid, SphereOnTheOpticalAxisOfALookAtCamera) {
  const CameraIntrinsics k;
  const Eigen::Vector3d c(0.1, -0.2, 0.05);
  const Eigen::Vector3d eye = c + Eigen::Vector3d(0.4, 0.5, 0.3);
  const double d = (eye - c).norm(), r = 0.07;
  const ProjectedEllipse pe = project_ellipsoid(sphere_ellipsoid(c, r), k, look_at_z_up(eye, c));
  ASSERT_TRUE(pe.valid);
  const double expected = 696.0 * r / std::sqrt(d * d - r * r);
  EXPECT_NEAR(pe.centre.x(), 640.0, 1e-9);
  EXPECT_NEAR(pe.centre.y(), 360.0, 1e-9);
  EXPECT_NEAR(pe.semi_axes.x(), expected, 1e-9 * expected);
  EXPECT_NEAR(pe.semi_axes.y(), expected, 1e-9 * expected);
  EXPECT_NEAR(pe.depth_m, d, 1e-12);
}

TEST(ProjectEllipsoid, OffAxisSphereMatchesRayCastSilhouette) {
  const CameraIntrinsics k = small_camera();
  const Pose pose = look_at_z_up(Eigen::Vector3d(0.3, -0.5, 0.2), Eigen::Vector3d::Zero());
  const Ellipsoid e = sphere_ellipsoid(Eigen::Vector3d(0.12, 0.06, -0.05), 0.09);
  const ProjectedEllipse pe = project_ellipsoid(e, k, pose);
  ASSERT_TRUE(pe.valid);
  // Off-axis: centre away from the principal point and the circle stretched to an ellipse.
  EXPECT_GT((pe.centre - Eigen::Vector2d(k.cx, k.cy)).norm(), 20.0);
  EXPECT_GT(pe.semi_axes.x() / pe.semi_axes.y(), 1.01);
  expect_matches_silhouette(e, k, pose);
}

TEST(ProjectEllipsoid, RotatedEllipsoidMatchesRayCastSilhouette) {
  Ellipsoid e;
  e.centre = Eigen::Vector3d(0.05, -0.04, 0.02);
  e.axes = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, -0.5).normalized()).toRotationMatrix();
  e.semi_axes = Eigen::Vector3d(0.15, 0.08, 0.05);
  const Pose pose = look_at_z_up(Eigen::Vector3d(-0.4, 0.45, 0.25), Eigen::Vector3d(0, 0.02, 0));
  expect_matches_silhouette(e, small_camera(), pose);
  expect_matches_silhouette(e, small_camera(150.0), pose);  // fx != fy
  const Pose pose2 = look_at_z_up(Eigen::Vector3d(0.1, 0.2, 0.65), Eigen::Vector3d(0, 0, 0));
  expect_matches_silhouette(e, small_camera(), pose2);
}

TEST(ProjectEllipsoid, BehindTheCameraContributesNothing) {
  const CameraIntrinsics k;
  const Ellipsoid e = sphere_ellipsoid(Eigen::Vector3d(0, 0, -1), 0.1, EllipsoidClass::kFrontier);
  const ProjectedEllipse pe = project_ellipsoid(e, k, Pose::Identity());
  EXPECT_FALSE(pe.valid);
  EXPECT_EQ(clipped_ellipse_area(pe, k), 0.0);
  const ViewScore s = score_view({e}, k, Pose::Identity());
  EXPECT_EQ(s.visible, 0);
  EXPECT_EQ(s.quality, 0.0);
  EXPECT_EQ(s.frontier_sum, 0.0);
  EXPECT_EQ(s.occupied_sum, 0.0);
}

TEST(ProjectEllipsoid, CameraInsideOrStraddlingIsInvalid) {
  const CameraIntrinsics k;
  // Camera inside the ellipsoid.
  EXPECT_FALSE(project_ellipsoid(sphere_ellipsoid(Eigen::Vector3d(0, 0, 0.05), 0.1), k, Pose::Identity())
                   .valid);
  // Centre in front, but the ellipsoid reaches behind the camera plane (camera outside it).
  Ellipsoid e = sphere_ellipsoid(Eigen::Vector3d(0.3, 0, 0.05), 0.1);
  e.semi_axes = Eigen::Vector3d(0.1, 0.1, 0.2);
  EXPECT_FALSE(project_ellipsoid(e, k, Pose::Identity()).valid);
  EXPECT_EQ(score_view({e}, k, Pose::Identity()).visible, 0);
}

ProjectedEllipse make_ellipse(const Eigen::Vector2d& c, double a, double b, double angle) {
  ProjectedEllipse e;
  e.valid = true;
  e.centre = c;
  const Eigen::Matrix2d r = Eigen::Rotation2Dd(angle).toRotationMatrix();
  e.shape = r * Eigen::Vector2d(a * a, b * b).asDiagonal() * r.transpose();
  e.semi_axes = Eigen::Vector2d(std::max(a, b), std::min(a, b));
  e.area_px = kPi * a * b;
  return e;
}

TEST(ClippedEllipseArea, InsideDisjointAndHalves) {
  const CameraIntrinsics k;  // [0, 1280] x [0, 720]
  const double full = kPi * 100 * 50;
  EXPECT_NEAR(clipped_ellipse_area(make_ellipse({640, 360}, 100, 50, 0.3), k), full, 1e-9 * full);
  EXPECT_EQ(clipped_ellipse_area(make_ellipse({-120, 360}, 100, 50, 0.0), k), 0.0);
  EXPECT_EQ(clipped_ellipse_area(make_ellipse({640, 900}, 100, 50, 1.0), k), 0.0);
  // Bounding boxes overlap the image but the ellipse does not: still 0 (the exact path).
  EXPECT_NEAR(clipped_ellipse_area(make_ellipse({-60, -60}, 100, 10, -kPi / 4), k), 0.0, 1e-9);
  // Centre on a border, axis-aligned: exactly half.
  EXPECT_NEAR(clipped_ellipse_area(make_ellipse({0, 360}, 100, 50, 0.0), k), full / 2,
              1e-6 * full);
  EXPECT_NEAR(clipped_ellipse_area(make_ellipse({1280, 360}, 100, 50, 0.0), k), full / 2,
              1e-6 * full);
  EXPECT_NEAR(clipped_ellipse_area(make_ellipse({640, 0}, 100, 50, 0.0), k), full / 2,
              1e-6 * full);
  EXPECT_NEAR(clipped_ellipse_area(make_ellipse({640, 720}, 100, 50, 0.0), k), full / 2,
              1e-6 * full);
  // A centred ellipse of any orientation is cut in half by a border through its centre.
  EXPECT_NEAR(clipped_ellipse_area(make_ellipse({0, 360}, 100, 50, 0.9), k), full / 2,
              1e-6 * full);
  // Centre on a corner, axis-aligned: a quarter.
  EXPECT_NEAR(clipped_ellipse_area(make_ellipse({0, 0}, 100, 50, 0.0), k), full / 4,
              1e-6 * full);
  // Covering the whole image: the image area.
  EXPECT_NEAR(clipped_ellipse_area(make_ellipse({640, 360}, 5000, 3000, 0.4), k), 1280.0 * 720.0,
              1e-6 * 1280.0 * 720.0);
  // Invalid ellipse: 0.
  ProjectedEllipse bad = make_ellipse({640, 360}, 100, 50, 0);
  bad.valid = false;
  EXPECT_EQ(clipped_ellipse_area(bad, k), 0.0);
}

// Brute force: midpoint sampling on an n x n grid over the bounding box ∩ image.
double grid_area(const ProjectedEllipse& e, const CameraIntrinsics& k, int n) {
  const double hx = std::sqrt(e.shape(0, 0)), hy = std::sqrt(e.shape(1, 1));
  const double x0 = std::max(0.0, e.centre.x() - hx), x1 = std::min<double>(k.width, e.centre.x() + hx);
  const double y0 = std::max(0.0, e.centre.y() - hy), y1 = std::min<double>(k.height, e.centre.y() + hy);
  if (x1 <= x0 || y1 <= y0) return 0;
  const Eigen::Matrix2d inv = e.shape.inverse();
  const double dx = (x1 - x0) / n, dy = (y1 - y0) / n;
  long hits = 0;
  for (int i = 0; i < n; ++i) {
    const double px = x0 + (i + 0.5) * dx - e.centre.x();
    const double a = inv(0, 0) * px * px;
    const double b = 2 * inv(0, 1) * px;
    for (int j = 0; j < n; ++j) {
      const double py = y0 + (j + 0.5) * dy - e.centre.y();
      if (a + b * py + inv(1, 1) * py * py <= 1.0) ++hits;
    }
  }
  return hits * dx * dy;
}

// Semi-analytic: per column x, the exact chord of the ellipse at x clipped to [0, H],
// integrated by the midpoint rule over n columns (error ~ n^-1.5).
double column_area(const ProjectedEllipse& e, const CameraIntrinsics& k, int n) {
  const double hx = std::sqrt(e.shape(0, 0));
  const double x0 = std::max(0.0, e.centre.x() - hx), x1 = std::min<double>(k.width, e.centre.x() + hx);
  if (x1 <= x0) return 0;
  const Eigen::Matrix2d inv = e.shape.inverse();
  const double dx = (x1 - x0) / n;
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    const double px = x0 + (i + 0.5) * dx - e.centre.x();
    // inv11 py^2 + 2 inv01 px py + inv00 px^2 - 1 = 0
    const double a = inv(1, 1), b = inv(0, 1) * px, c = inv(0, 0) * px * px - 1.0;
    const double disc = b * b - a * c;
    if (disc <= 0) continue;
    const double r = std::sqrt(disc);
    const double lo = std::max(0.0, e.centre.y() + (-b - r) / a);
    const double hi = std::min<double>(k.height, e.centre.y() + (-b + r) / a);
    if (hi > lo) sum += hi - lo;
  }
  return sum * dx;
}

TEST(ClippedEllipseArea, RandomStraddlingEllipsesMatchBruteForce) {
  CameraIntrinsics k;
  k.width = 640;
  k.height = 480;
  k.cx = 320;
  k.cy = 240;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  int tested = 0;
  double worst_grid = 0, worst_column = 0;
  while (tested < 40) {
    const double a = 5 + 400 * u01(rng), b = 2 + 200 * u01(rng);
    const Eigen::Vector2d c(-200 + 1040 * u01(rng), -200 + 880 * u01(rng));
    const ProjectedEllipse e = make_ellipse(c, a, b, 2 * kPi * u01(rng));
    const double hx = std::sqrt(e.shape(0, 0)), hy = std::sqrt(e.shape(1, 1));
    const bool inside = c.x() - hx >= 0 && c.x() + hx <= k.width && c.y() - hy >= 0 &&
                        c.y() + hy <= k.height;
    const bool disjoint = c.x() + hx <= 0 || c.x() - hx >= k.width || c.y() + hy <= 0 ||
                          c.y() - hy >= k.height;
    if (inside || disjoint) continue;  // only ellipses straddling the border
    const double exact = clipped_ellipse_area(e, k);
    const double grid = grid_area(e, k, 3000);
    const double column = column_area(e, k, 400000);
    if (column < 1e-3 * e.area_px) continue;  // barely touching: relative error meaningless
    ++tested;
    EXPECT_LT(exact, e.area_px * (1 + 1e-12));
    EXPECT_NEAR(exact, grid, 0.005 * grid) << "ellipse " << tested;
    EXPECT_NEAR(exact, column, 1e-5 * column) << "ellipse " << tested;
    worst_grid = std::max(worst_grid, std::abs(exact - grid) / grid);
    worst_column = std::max(worst_column, std::abs(exact - column) / column);
  }
  std::printf("worst relative difference: grid %.2e, column integral %.2e\n", worst_grid,
              worst_column);
}

TEST(ScoreView, RankWeightsFollowDepth) {
  const CameraIntrinsics k;
  // Listed out of depth order (3, 1, 2 m) so an argsort-for-rank mix-up would show.
  const std::vector<Eigen::Vector3d> centres = {
      {0.6, 0.1, 3.0}, {-0.3, 0.0, 1.0}, {0.0, -0.2, 2.0}};
  const std::vector<double> expected_weight = {0.25, 1.0, 0.5};
  const Pose pose = Pose::Identity();
  std::vector<double> area(3);
  for (int i = 0; i < 3; ++i) {
    const ProjectedEllipse pe = project_ellipsoid(sphere_ellipsoid(centres[i], 0.05), k, pose);
    ASSERT_TRUE(pe.valid);
    area[i] = clipped_ellipse_area(pe, k);
    EXPECT_NEAR(area[i], pe.area_px, 1e-9 * pe.area_px);  // whole ellipse in the image
  }
  for (int f = 0; f < 3; ++f) {  // sphere f frontier, the others occupied
    std::vector<Ellipsoid> es;
    for (int i = 0; i < 3; ++i) {
      es.push_back(sphere_ellipsoid(centres[i], 0.05,
                          i == f ? EllipsoidClass::kFrontier : EllipsoidClass::kOccupied));
    }
    const ViewScore s = score_view(es, k, pose);
    EXPECT_EQ(s.visible, 3);
    EXPECT_DOUBLE_EQ(s.frontier_sum / area[f], expected_weight[f]);
    double occ = 0;
    for (int i = 0; i < 3; ++i) {
      if (i != f) occ += expected_weight[i] * area[i];
    }
    EXPECT_NEAR(s.occupied_sum, occ, 1e-12 * occ);
    EXPECT_NEAR(s.quality, s.frontier_sum - s.occupied_sum, 1e-12 * occ);
  }
}

TEST(ScoreView, InvisibleEllipsoidsAreNotRankedAndAreaIsClipped) {
  const CameraIntrinsics k;
  const Pose pose = Pose::Identity();
  // A frontier sphere half out of the image at 1 m, an occupied one behind the camera.
  // Image x = 0 is at lateral offset -640/696 m at 1 m depth.
  const Ellipsoid half = sphere_ellipsoid({-640.0 / 696.0, 0.0, 1.0}, 0.05, EllipsoidClass::kFrontier);
  const Ellipsoid behind = sphere_ellipsoid({0.0, 0.0, -0.5}, 0.05, EllipsoidClass::kOccupied);
  const Ellipsoid far = sphere_ellipsoid({0.0, 0.0, 2.0}, 0.05, EllipsoidClass::kOccupied);
  const ProjectedEllipse ph = project_ellipsoid(half, k, pose);
  const ProjectedEllipse pf = project_ellipsoid(far, k, pose);
  const ViewScore s = score_view({far, behind, half}, k, pose);
  EXPECT_EQ(s.visible, 2);
  EXPECT_NEAR(s.frontier_sum, clipped_ellipse_area(ph, k), 1e-12 * ph.area_px);
  EXPECT_LT(s.frontier_sum, 0.6 * ph.area_px);
  EXPECT_GT(s.frontier_sum, 0.4 * ph.area_px);
  EXPECT_NEAR(s.occupied_sum, 0.5 * pf.area_px, 1e-12 * pf.area_px);
}

TEST(ScoreView, FrontierViewBeatsOccupiedOnlyView) {
  const CameraIntrinsics k;
  const std::vector<Ellipsoid> scene = {
      sphere_ellipsoid({0, 0, 0}, 0.1, EllipsoidClass::kOccupied),
      sphere_ellipsoid({-3, 0, 0}, 0.1, EllipsoidClass::kFrontier)};
  // A at x = -1 looks along +x: the occupied sphere ahead, the frontier one behind.
  const ViewScore a = score_view(scene, k, look_at_z_up({-1, 0, 0}, {0, 0, 0}));
  // B at x = -2 looks along -x: the frontier sphere ahead, the occupied one behind.
  const ViewScore b = score_view(scene, k, look_at_z_up({-2, 0, 0}, {-3, 0, 0}));
  EXPECT_EQ(a.visible, 1);
  EXPECT_EQ(b.visible, 1);
  EXPECT_EQ(a.frontier_sum, 0.0);
  EXPECT_GT(a.occupied_sum, 0.0);
  EXPECT_EQ(b.occupied_sum, 0.0);
  EXPECT_GT(b.frontier_sum, 0.0);
  EXPECT_LT(a.quality, 0.0);
  EXPECT_GT(b.quality, 0.0);
  EXPECT_LT(a.quality, b.quality);
}

TEST(Partition, SectorOfAzimuth) {
  const Eigen::Vector3d c(0.1, -0.2, 0.3);
  const int expected[] = {0, 1, 2, 3};
  const double az_deg[] = {10, 100, 190, 280};
  for (int i = 0; i < 4; ++i) {
    const double a = az_deg[i] * kPi / 180.0;
    const Eigen::Vector3d eye = c + Eigen::Vector3d(0.8 * std::cos(a), 0.8 * std::sin(a), 0.4);
    EXPECT_EQ(sector_of(eye, c, 4), expected[i]) << az_deg[i];
  }
  EXPECT_EQ(sector_of(c + Eigen::Vector3d(1, -1e-9, 0), c, 4), 3);
  EXPECT_EQ(sector_of(c + Eigen::Vector3d(1, 0, 0), c, 4), 0);
  EXPECT_EQ(sector_of(c + Eigen::Vector3d(-1, 0, 0), c, 8), 4);
}

TEST(Partition, AllowedSectors) {
  using V = std::vector<int>;
  EXPECT_EQ(allowed_sectors({true, false, false, false}), (V{1, 3}));
  EXPECT_EQ(allowed_sectors({true, true, false, false}), (V{2, 3}));
  EXPECT_EQ(allowed_sectors({true, true, true, false}), (V{3}));
  EXPECT_EQ(allowed_sectors({true, true, true, true}), (V{0, 1, 2, 3}));
  EXPECT_EQ(allowed_sectors({false, false, true, false}), (V{1, 3}));
  EXPECT_EQ(allowed_sectors({false, false, false, false}), (V{0, 1, 2, 3}));  // no constraint yet
}

TEST(Partition, RandomSequencesStayAdjacentUntilAllScanned) {
  std::mt19937 rng(3);
  for (int beta = 2; beta <= 9; ++beta) {
    for (int trial = 0; trial < 50; ++trial) {
      std::vector<bool> scanned(beta, false);
      scanned[std::uniform_int_distribution<int>(0, beta - 1)(rng)] = true;
      for (int step = 0; step < 3 * beta; ++step) {
        const std::vector<int> allowed = allowed_sectors(scanned);
        ASSERT_FALSE(allowed.empty());
        const bool all = std::count(scanned.begin(), scanned.end(), true) == beta;
        if (all) {
          EXPECT_EQ(static_cast<int>(allowed.size()), beta);
        } else {
          for (int s : allowed) {
            ASSERT_GE(s, 0);
            ASSERT_LT(s, beta);
            EXPECT_FALSE(scanned[s]);
            EXPECT_TRUE(scanned[(s + 1) % beta] || scanned[(s + beta - 1) % beta]);
          }
          // Every unscanned sector next to a scanned one is offered.
          for (int s = 0; s < beta; ++s) {
            if (!scanned[s] && (scanned[(s + 1) % beta] || scanned[(s + beta - 1) % beta])) {
              EXPECT_NE(std::find(allowed.begin(), allowed.end(), s), allowed.end());
            }
          }
        }
        scanned[allowed[std::uniform_int_distribution<size_t>(0, allowed.size() - 1)(rng)]] =
            true;
      }
      EXPECT_EQ(std::count(scanned.begin(), scanned.end(), true), beta);
    }
  }
}

}  // namespace
}  // namespace pbnbv
