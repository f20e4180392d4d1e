#pragma once
// Scoring candidate views by projecting ellipsoids (docs/method.md "Scoring a candidate view"
// and "Global partitioning", paper sections III-D and III-E).
#include <vector>

#include "core/geometry/camera_model.hpp"
#include "core/planning/ellipsoid.hpp"
#include "core/base/pose.hpp"

namespace pbnbv {

// The ellipse an ellipsoid projects to in a camera (dual conic C* = P Q* P^T).
struct ProjectedEllipse {
  bool valid = false;          // false: behind the camera, or the camera is inside/too close
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();   // pixels
  Eigen::Matrix2d shape = Eigen::Matrix2d::Zero();    // (x-c)^T shape^-1 (x-c) <= 1 inside
  Eigen::Vector2d semi_axes = Eigen::Vector2d::Zero();  // pixels, major first
  double area_px = 0;          // full ellipse area, pi a b
  double depth_m = 0;          // depth of the ellipsoid centre in the camera frame
};

// Projects with K and the optical-frame camera pose object_T_camera.
ProjectedEllipse project_ellipsoid(const Ellipsoid& e, const CameraIntrinsics& k,
                                   const Pose& object_T_camera);

// Area of the ellipse inside the image rectangle [0, width] x [0, height], pixels (exact to
// within 0.5% of the clipped area).
double clipped_ellipse_area(const ProjectedEllipse& ellipse, const CameraIntrinsics& k);

struct ViewScore {
  double quality = 0;          // F = sum over frontier of w L - sum over occupied of w L
  double frontier_sum = 0;
  double occupied_sum = 0;
  int visible = 0;             // ellipsoids in front of the camera
};

// F for one candidate: every ellipsoid in front of the camera is ranked by the depth of its
// centre (rank 0 nearest, all classes together), weight 0.5^rank, L = clipped area.
ViewScore score_view(const std::vector<Ellipsoid>& ellipsoids, const CameraIntrinsics& k,
                     const Pose& object_T_camera);

// Global partitioning: beta sectors by azimuth about the centre, sector 0 starting at azimuth
// `start_rad` (sector of azimuth a: floor(((a - start) mod 2pi) / (2pi / beta))).
int sector_of(const Eigen::Vector3d& eye, const Eigen::Vector3d& centre, int beta, double start_rad = 0.0);

// The sectors the next view may come from, given the scanned ones: while some sector is
// unscanned, the unscanned sectors adjacent (cyclically) to a scanned one; once all are
// scanned, all sectors.
std::vector<int> allowed_sectors(const std::vector<bool>& scanned);

}  // namespace pbnbv
