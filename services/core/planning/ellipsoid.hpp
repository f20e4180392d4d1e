#pragma once
// An ellipsoid of the scene (Occupied or Frontier), as the fitter makes it and the view scorer
// projects it: centre, principal axes and semi-axes, and its quadric (docs/method.md "Ellipsoids").
#include <Eigen/Geometry>
#include <cstdint>

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

}  // namespace pbnbv
