#pragma once
// Ellipsoids and the minimum-volume enclosing ellipsoid of a point set (Khachiyan's algorithm
// with Todd-Yildirim away steps, on an active set; docs/method.md "Ellipsoids").
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

namespace pbnbv {

enum class EllipsoidClass : uint8_t { kOccupied = 0, kFrontier = 1 };

struct Ellipsoid {
  EllipsoidClass cls = EllipsoidClass::kOccupied;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // columns: principal directions (rotation)
  Eigen::Vector3d semi_axes = Eigen::Vector3d::Zero();  // along the columns of `axes`, m
  int num_points = 0;
  // The quadric Q (4x4, X^T Q X = 0 on the surface, X homogeneous) and its dual Q* = Q^-1.
  Eigen::Matrix4d quadric() const;
  Eigen::Matrix4d dual_quadric() const;
};

// Minimum-volume enclosing ellipsoid of the points (Khachiyan's algorithm, tolerance `tol`).
// Fewer than 4 affinely independent points (or degenerate, e.g. planar) sets get the principal
// frame of the points with semi-axes sqrt(3) x their half extents and thin directions 1e-9 m
// (fit_ellipsoids pads such clusters with voxel corners first).
Ellipsoid minimum_volume_ellipsoid(const std::vector<Eigen::Vector3d>& points, double tol = 1e-4);

}  // namespace pbnbv
