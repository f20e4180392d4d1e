#pragma once
// A sphere as an ellipsoid of the given class (axes the identity, all three semi-axes r): the
// shape whose projection the tests work out by hand (a disc, or a circle's ellipse off axis).
#include "core/planning/ellipsoid.hpp"

namespace pbnbv::testing {

inline Ellipsoid sphere_ellipsoid(const Eigen::Vector3d& centre, double r,
                                  EllipsoidClass cls = EllipsoidClass::kOccupied) {
  Ellipsoid e;
  e.cls = cls;
  e.centre = centre;
  e.axes = Eigen::Matrix3d::Identity();
  e.semi_axes = Eigen::Vector3d::Constant(r);
  return e;
}

}  // namespace pbnbv::testing
