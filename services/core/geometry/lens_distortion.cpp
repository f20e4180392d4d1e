// Brown-Conrady lens distortion and the resampling of depth images through it. See
// lens_distortion.hpp.
#include "core/geometry/lens_distortion.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace pbnbv {

namespace {

// 1 + k1 r^2 + k2 r^4 + k3 r^6.
double radial(const LensDistortion& d, double r2) { return 1 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3)); }

// Depth at the continuous pixel (u, v) of `depth` (pixel centres at whole numbers): inverse depth
// interpolated between four readings within 2 % of each other, else the nearest reading; 0
// outside the image.
float sample(const std::vector<float>& depth, int width, int height, double u, double v) {
  if (!(u > -0.5 && v > -0.5 && u < width - 0.5 && v < height - 0.5)) return 0.0f;
  const int u0 = static_cast<int>(std::floor(u)), v0 = static_cast<int>(std::floor(v));
  if (u0 >= 0 && v0 >= 0 && u0 + 1 < width && v0 + 1 < height) {
    const std::size_t i = static_cast<std::size_t>(v0) * width + u0;
    const float z00 = depth[i], z10 = depth[i + 1], z01 = depth[i + width], z11 = depth[i + width + 1];
    const float lo = std::min({z00, z10, z01, z11}), hi = std::max({z00, z10, z01, z11});
    if (lo > 0 && hi <= 1.02f * lo) {
      const double a = u - u0, b = v - v0;
      const double inv = (1 - a) * (1 - b) / z00 + a * (1 - b) / z10 + (1 - a) * b / z01 + a * b / z11;
      return static_cast<float>(1.0 / inv);
    }
  }
  const int ui = std::clamp(static_cast<int>(std::lround(u)), 0, width - 1);
  const int vi = std::clamp(static_cast<int>(std::lround(v)), 0, height - 1);
  return depth[static_cast<std::size_t>(vi) * width + ui];
}

void check_size(const std::vector<float>& depth, const CameraIntrinsics& k, const char* what) {
  if (depth.size() != static_cast<std::size_t>(k.width) * static_cast<std::size_t>(k.height)) {
    throw std::invalid_argument(std::string(what) + ": " + std::to_string(depth.size()) + " depths for a " +
                                std::to_string(k.width) + " x " + std::to_string(k.height) + " image");
  }
}

}  // namespace

void LensDistortion::validate(const CameraIntrinsics& k, const std::string& what) const {
  const std::array<double, 5> c = coefficients();
  const char* names[5] = {"k1", "k2", "p1", "p2", "k3"};
  for (int i = 0; i < 5; ++i) {
    const double limit = (i == 2 || i == 3) ? 1.0 : 10.0;
    if (!std::isfinite(c[i]) || std::abs(c[i]) > limit) {
      std::ostringstream os;
      os << what << ": distortion " << names[i] << " = " << c[i] << " is not a lens's (finite, |" << names[i]
         << "| <= " << limit << ")";
      throw std::invalid_argument(os.str());
    }
  }
  if (none()) return;
  // The distorted radius must grow with the pinhole radius over the whole image: up to its
  // farthest corner, with 2 % to spare.
  const double corner = std::hypot(std::max(k.cx, k.width - 1 - k.cx) / k.fx, std::max(k.cy, k.height - 1 - k.cy) / k.fy);
  double last = 0;
  for (double r = 1e-3;; r += 1e-3) {
    const double rd = r * radial(*this, r * r);
    if (rd <= last) {
      std::ostringstream os;
      os << what << ": distortion k1 k2 k3 = " << k1 << " " << k2 << " " << k3 << " fold the image over at radius "
         << last << " (normalised), inside the image's " << corner << ": not this camera's lens";
      throw std::invalid_argument(os.str());
    }
    last = rd;
    if (rd > 1.02 * corner || r > 100) break;
  }
}

Eigen::Vector2d distort_normalised(const LensDistortion& d, const Eigen::Vector2d& p) {
  const double x = p.x(), y = p.y(), r2 = x * x + y * y, s = radial(d, r2);
  return {x * s + 2 * d.p1 * x * y + d.p2 * (r2 + 2 * x * x), y * s + d.p1 * (r2 + 2 * y * y) + 2 * d.p2 * x * y};
}

Eigen::Vector2d undistort_normalised(const LensDistortion& d, const Eigen::Vector2d& target) {
  if (d.none()) return target;
  Eigen::Vector2d p = target;
  for (int it = 0; it < 50; ++it) {
    const double x = p.x(), y = p.y(), r2 = x * x + y * y, s = radial(d, r2);
    const double ds = 2 * (d.k1 + r2 * (2 * d.k2 + 3 * r2 * d.k3));  // d(radial)/d(r^2) * 2
    Eigen::Matrix2d J;
    J(0, 0) = s + x * ds * x + 2 * d.p1 * y + 6 * d.p2 * x;
    J(0, 1) = x * ds * y + 2 * d.p1 * x + 2 * d.p2 * y;
    J(1, 0) = y * ds * x + 2 * d.p1 * x + 2 * d.p2 * y;
    J(1, 1) = s + y * ds * y + 6 * d.p1 * y + 2 * d.p2 * x;
    const Eigen::Vector2d step = J.partialPivLu().solve(distort_normalised(d, p) - target);
    p -= step;
    if (step.norm() < 1e-13) break;
  }
  return p;
}

std::vector<float> undistort_depth(const std::vector<float>& depth_m, const CameraIntrinsics& k, const LensDistortion& d) {
  check_size(depth_m, k, "undistort_depth");
  if (d.none()) return depth_m;
  std::vector<float> out(depth_m.size(), 0.0f);
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector2d xd = distort_normalised(d, {(u - k.cx) / k.fx, (v - k.cy) / k.fy});
      out[static_cast<std::size_t>(v) * k.width + u] =
          sample(depth_m, k.width, k.height, k.fx * xd.x() + k.cx, k.fy * xd.y() + k.cy);
    }
  }
  return out;
}

CameraIntrinsics pinhole_cover(const CameraIntrinsics& k, const LensDistortion& d) {
  d.validate(k, "pinhole_cover");  // a lens that folds the image over has no inverse to cover
  // The image's own pinhole extent, widened to every border pixel's ray.
  double x0 = -k.cx / k.fx, x1 = (k.width - 1 - k.cx) / k.fx, y0 = -k.cy / k.fy, y1 = (k.height - 1 - k.cy) / k.fy;
  if (!d.none()) {
    auto widen = [&](double u, double v) {
      const Eigen::Vector2d p = undistort_normalised(d, {(u - k.cx) / k.fx, (v - k.cy) / k.fy});
      x0 = std::min(x0, p.x());
      x1 = std::max(x1, p.x());
      y0 = std::min(y0, p.y());
      y1 = std::max(y1, p.y());
    };
    for (int u = 0; u < k.width; ++u) {
      widen(u, 0);
      widen(u, k.height - 1);
    }
    for (int v = 0; v < k.height; ++v) {
      widen(0, v);
      widen(k.width - 1, v);
    }
  }
  CameraIntrinsics c = k;
  c.cx = 1 + std::ceil(-x0 * k.fx);  // a pixel of margin, and whole pixels: the same pixel centres
  c.cy = 1 + std::ceil(-y0 * k.fy);
  c.width = static_cast<int>(c.cx + std::ceil(x1 * k.fx)) + 2;
  c.height = static_cast<int>(c.cy + std::ceil(y1 * k.fy)) + 2;
  c.cx += k.cx - std::floor(k.cx);  // keep the principal point's fraction of a pixel
  c.cy += k.cy - std::floor(k.cy);
  return c;
}

std::vector<float> distort_depth(const std::vector<float>& pinhole, const CameraIntrinsics& k_pinhole,
                                 const CameraIntrinsics& k, const LensDistortion& d) {
  check_size(pinhole, k_pinhole, "distort_depth");
  std::vector<float> out(static_cast<std::size_t>(k.width) * k.height, 0.0f);
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector2d p = undistort_normalised(d, {(u - k.cx) / k.fx, (v - k.cy) / k.fy});
      out[static_cast<std::size_t>(v) * k.width + u] = sample(pinhole, k_pinhole.width, k_pinhole.height,
                                                              k_pinhole.fx * p.x() + k_pinhole.cx,
                                                              k_pinhole.fy * p.y() + k_pinhole.cy);
    }
  }
  return out;
}

}  // namespace pbnbv
