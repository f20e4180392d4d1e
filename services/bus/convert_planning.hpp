#pragma once
// Conversions between the planning messages and the planning library's types.
#include <Eigen/Geometry>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "bus/convert.hpp"
#include "core/planning/mvee.hpp"
#include "pbnbv/ellipsoid_t.hpp"

namespace pbnbv::bus {

// An ellipsoid as a message: the principal axes become a proper rotation (a reflected frame
// has its third axis flipped, which describes the same ellipsoid).
inline ellipsoid_t to_msg(const Ellipsoid& e) {
  ellipsoid_t m;
  m.cls = e.cls == EllipsoidClass::kFrontier ? ellipsoid_t::kFrontier : ellipsoid_t::kOccupied;
  Eigen::Matrix3d r = e.axes;
  if (r.determinant() < 0) r.col(2) = -r.col(2);
  const Eigen::Quaterniond q(r);
  m.quat_wxyz[0] = q.w();
  m.quat_wxyz[1] = q.x();
  m.quat_wxyz[2] = q.y();
  m.quat_wxyz[3] = q.z();
  for (int k = 0; k < 3; ++k) {
    m.centre_m[k] = e.centre[k];
    m.semi_axes_m[k] = e.semi_axes[k];
  }
  m.num_voxels = e.num_points;
  return m;
}

// Throws std::invalid_argument naming `what` for an unknown class, a non-finite centre, a
// semi-axis that is not positive and finite, or a non-unit quaternion.
inline Ellipsoid from_msg(const ellipsoid_t& m, const std::string& what) {
  if (m.cls != ellipsoid_t::kOccupied && m.cls != ellipsoid_t::kFrontier) {
    throw std::invalid_argument(what + ".cls = " + std::to_string(m.cls) + " is neither kOccupied (0) nor kFrontier (1)");
  }
  Ellipsoid e;
  e.cls = m.cls == ellipsoid_t::kFrontier ? EllipsoidClass::kFrontier : EllipsoidClass::kOccupied;
  const Pose p = pose_from_arrays(m.centre_m, m.quat_wxyz, what);
  e.centre = p.translation();
  e.axes = p.linear();
  for (int k = 0; k < 3; ++k) {
    if (!(std::isfinite(m.semi_axes_m[k]) && m.semi_axes_m[k] > 0)) {
      std::ostringstream os;
      os << what << ".semi_axes_m[" << k << "] = " << m.semi_axes_m[k] << " is not a positive length";
      throw std::invalid_argument(os.str());
    }
    e.semi_axes[k] = m.semi_axes_m[k];
  }
  e.num_points = m.num_voxels;
  return e;
}

}  // namespace pbnbv::bus
