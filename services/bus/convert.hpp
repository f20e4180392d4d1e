#pragma once
// Conversions between the contract's messages and the core library's plain types, with the
// validation every handler applies to what it receives.
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bus/depth_codec.hpp"
#include "bus/message_guard.hpp"
#include "core/geometry/camera_model.hpp"
#include "core/geometry/lens_distortion.hpp"
#include "core/base/pose.hpp"
#include "pbnbv/depth_frame_t.hpp"
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
// A count of contact events and the last one's text (ARM_STATUS contacts / last_contact,
// MOVE_RESULT contacts / contact): throws naming the field when the count is below -1 (-1: the
// rig cannot tell) or a text comes with no event counted.
inline void contacts_from_msg(int32_t contacts, const std::string& text, const std::string& count_what,
                              const std::string& text_what) {
  if (contacts < -1) {
    throw std::invalid_argument(count_what + " = " + std::to_string(contacts) + " is below -1 (-1: the rig cannot tell)");
  }
  if (contacts <= 0 && !text.empty()) {
    throw std::invalid_argument(text_what + " is given with " + count_what + " = " + std::to_string(contacts) +
                                " (only with a contact counted)");
  }
}

inline void require_range(double x, double lo, double hi, const std::string& what) {
  if (!(std::isfinite(x) && x >= lo && x <= hi)) {
    std::ostringstream os;
    os << what << " = " << x << " is outside [" << lo << ", " << hi << "]";
    throw std::invalid_argument(os.str());
  }
}

// A DEPTH_FRAME as the core library takes it: its camera model, its range, planar depth in
// metres (0 = no return) as the pinhole camera `intrinsics` sees it (a distorted image resampled),
// and the lens the frame said it was taken through.
struct DecodedFrame {
  CameraIntrinsics intrinsics;
  DepthRange range;
  std::vector<float> depth_m;
  LensDistortion distortion;  // as sent; depth_m is already undistorted
};

// Throws std::invalid_argument naming the bad field (intrinsics, range, distortion, encoding,
// size, depth unit).
inline DecodedFrame decode_frame(const depth_frame_t& f) {
  DecodedFrame d;
  d.intrinsics = CameraIntrinsics{f.width, f.height, f.fx, f.fy, f.cx, f.cy};
  d.range = DepthRange{f.depth_min_m, f.depth_max_m};
  d.distortion = LensDistortion{f.distortion[0], f.distortion[1], f.distortion[2], f.distortion[3], f.distortion[4]};
  try {
    d.intrinsics.validate();
    d.range.validate();
    d.distortion.validate(d.intrinsics, "distortion");
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("DEPTH_FRAME " + std::to_string(f.seq) + ": " + e.what());
  }
  if (f.encoding == depth_frame_t::kEncodingRaw) {
    d.depth_m = decode_depth_u16(f.depth, f.width, f.height, f.depth_unit_m);
  } else if (f.encoding == depth_frame_t::kEncodingZlib) {
    // width and height passed validate(), so the image is within the contract's largest.
    const std::vector<uint8_t> raw = inflate_bytes(f.depth, static_cast<std::size_t>(f.width) * f.height * 2,
                                                   2 * static_cast<std::size_t>(kMaxFramePixels),
                                                   "DEPTH_FRAME " + std::to_string(f.seq) + " depth (zlib)");
    d.depth_m = decode_depth_u16(raw, f.width, f.height, f.depth_unit_m);
  } else {
    throw std::invalid_argument("DEPTH_FRAME " + std::to_string(f.seq) + " encoding = " + std::to_string(f.encoding) +
                                " is not one of its constants (0 raw, 1 zlib)");
  }
  if (!d.distortion.none()) d.depth_m = undistort_depth(d.depth_m, d.intrinsics, d.distortion);
  return d;
}

}  // namespace pbnbv::bus
