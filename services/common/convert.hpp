#pragma once
// Conversions between the contract's messages and the core library's plain types, with the
// validation every handler applies to what it receives.
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/camera_model.hpp"
#include "core/depth_cloud.hpp"
#include "core/ellipsoids.hpp"
#include "core/geometry.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/ellipsoid_t.hpp"
#include "pbnbv/pose_t.hpp"

namespace pbnbv::bus {

inline pose_t to_msg(const Pose& pose) {
  pose_t m;
  pose_to_arrays(pose, m.position_m, m.quat_wxyz);
  return m;
}

// Throws std::invalid_argument naming `what` for a non-finite position or a non-unit quaternion.
inline Pose from_msg(const pose_t& m, const std::string& what) {
  return pose_from_arrays(m.position_m, m.quat_wxyz, what);
}

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

inline Vector6d to_vector6(const std::vector<double>& v, const std::string& what) {
  if (v.size() != 6) {
    throw std::invalid_argument(what + ": expected 6 joints, got " + std::to_string(v.size()));
  }
  Vector6d q;
  for (int i = 0; i < 6; ++i) {
    if (!std::isfinite(v[i])) {
      std::ostringstream os;
      os << what << ": joint " << i << " value " << v[i] << " is not finite";
      throw std::invalid_argument(os.str());
    }
    q[i] = v[i];
  }
  return q;
}

inline std::vector<double> to_std(const Vector6d& q) { return std::vector<double>(q.data(), q.data() + 6); }

// Throws std::invalid_argument when x is not finite or outside [lo, hi].
inline void require_range(double x, double lo, double hi, const std::string& what) {
  if (!(std::isfinite(x) && x >= lo && x <= hi)) {
    std::ostringstream os;
    os << what << " = " << x << " is outside [" << lo << ", " << hi << "]";
    throw std::invalid_argument(os.str());
  }
}

// A DEPTH_FRAME as the core library takes it: its camera model, its range, planar depth in
// metres (0 = no return).
struct DecodedFrame {
  CameraIntrinsics intrinsics;
  DepthRange range;
  std::vector<float> depth_m;
};

// Throws std::invalid_argument naming the bad field (intrinsics, range, size, depth unit).
inline DecodedFrame decode_frame(const depth_frame_t& f) {
  DecodedFrame d;
  d.intrinsics = CameraIntrinsics{f.width, f.height, f.fx, f.fy, f.cx, f.cy};
  d.intrinsics.validate();
  d.range = DepthRange{f.depth_min_m, f.depth_max_m};
  d.range.validate();
  d.depth_m = decode_depth_u16(f.depth, f.width, f.height, f.depth_unit_m);
  return d;
}

}  // namespace pbnbv::bus
