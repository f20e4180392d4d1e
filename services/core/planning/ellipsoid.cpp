// An ellipsoid's quadric and dual quadric (docs/method.md "Ellipsoids").
#include "core/planning/ellipsoid.hpp"

namespace pbnbv {

using Eigen::Matrix4d;

Eigen::Matrix4d Ellipsoid::quadric() const {
  // T = [R c; 0 1], T^-1 = [R^T, -R^T c; 0 1]; Q = T^-T diag(1/a^2, 1/b^2, 1/c^2, -1) T^-1.
  Matrix4d Tinv = Matrix4d::Identity();
  Tinv.topLeftCorner<3, 3>() = axes.transpose();
  Tinv.topRightCorner<3, 1>() = -axes.transpose() * centre;
  Eigen::Vector4d d;
  d << 1.0 / (semi_axes[0] * semi_axes[0]), 1.0 / (semi_axes[1] * semi_axes[1]),
      1.0 / (semi_axes[2] * semi_axes[2]), -1.0;
  return Tinv.transpose() * d.asDiagonal() * Tinv;
}

Eigen::Matrix4d Ellipsoid::dual_quadric() const {
  Matrix4d T = Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = axes;
  T.topRightCorner<3, 1>() = centre;
  Eigen::Vector4d d;
  d << semi_axes[0] * semi_axes[0], semi_axes[1] * semi_axes[1], semi_axes[2] * semi_axes[2], -1.0;
  return T * d.asDiagonal() * T.transpose();
}

}  // namespace pbnbv
