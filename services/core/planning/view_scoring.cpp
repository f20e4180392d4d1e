// Scoring candidate views by projecting ellipsoids (view_scoring.hpp).
//
// Projection. With camera_T_object = (R, t) and the ellipsoid's centre m = R c + t and covariance
// -like matrix E = R A diag(a^2) A^T R^T in the optical frame, the dual quadric in the optical
// frame is Q*_cam = [[E - m m^T, -m], [-m^T, -1]] (= T diag(a^2, b^2, c^2, -1) T^T with T the
// homogeneous [R A | m]). With P = K [I | 0] the dual conic is C* = K (E - m m^T) K^T, i.e. up to
// the (irrelevant) sign, C* ~ K N K^T with N = m m^T - E. We work with N in normalised image
// coordinates and apply K (an affine map of the image plane) afterwards: for a normalised dual
// conic with N(2,2) = 1 the ellipse centre is (N(0,2), N(1,2)) and its shape matrix
// S = c c^T - N[0:2, 0:2].
//
// Clipping. The ellipse {x : (x-c)^T S^-1 (x-c) <= 1} is the image of the unit disc under
// x = c + L u (S = L L^T, Cholesky). The image rectangle maps to a parallelogram in u; the area of
// unit disc ∩ convex polygon is the sum over the polygon's edges of the signed area of
// disc ∩ triangle(origin, edge), each of which is closed form (triangle pieces inside the disc,
// circular sectors outside). The clipped area is that times det L. Exact up to rounding.
#include "core/planning/view_scoring.hpp"
#include "core/base/units.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace pbnbv {
namespace {


// Signed area of (unit disc) ∩ (triangle origin, a, b); positive when a -> b turns
// counter-clockwise about the origin.
double disc_triangle_signed_area(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  auto cross = [](const Eigen::Vector2d& p, const Eigen::Vector2d& q) {
    return p.x() * q.y() - p.y() * q.x();
  };
  auto tri = [&](const Eigen::Vector2d& p, const Eigen::Vector2d& q) { return 0.5 * cross(p, q); };
  auto sector = [&](const Eigen::Vector2d& p, const Eigen::Vector2d& q) {
    return 0.5 * std::atan2(cross(p, q), p.dot(q));
  };
  const Eigen::Vector2d d = b - a;
  const double qa = d.squaredNorm();
  if (!(qa > 0)) return 0.0;
  // |a + s d|^2 = 1  <=>  qa s^2 + 2 qb s + qc = 0.
  const double qb = a.dot(d);
  const double qc = a.squaredNorm() - 1.0;
  const double disc = qb * qb - qa * qc;
  if (disc <= 0) return sector(a, b);  // the line misses (or touches) the disc
  const double root = std::sqrt(disc);
  // Numerically stable roots.
  double s1, s2;
  const double q = -(qb + std::copysign(root, qb));
  if (q != 0) {
    s1 = q / qa;
    s2 = qc / q;
  } else {  // qb == 0 and root == 0 cannot happen here (disc > 0); qb == -root only if qc == 0
    s1 = (-qb - root) / qa;
    s2 = (-qb + root) / qa;
  }
  if (s1 > s2) std::swap(s1, s2);
  s1 = std::clamp(s1, 0.0, 1.0);
  s2 = std::clamp(s2, 0.0, 1.0);
  const Eigen::Vector2d p1 = a + s1 * d;
  const Eigen::Vector2d p2 = a + s2 * d;
  double area = tri(p1, p2);
  if (s1 > 0) area += sector(a, p1);
  if (s2 < 1) area += sector(p2, b);
  return area;
}

// Eigen-decomposition of a symmetric 2x2 matrix: eigenvalues (largest first).
void sym2_eigenvalues(double s00, double s01, double s11, double* l_max, double* l_min) {
  const double mean = 0.5 * (s00 + s11);
  const double half_diff = 0.5 * (s00 - s11);
  const double r = std::sqrt(half_diff * half_diff + s01 * s01);  // (hypot is slow)
  *l_max = mean + r;
  // Stable smaller eigenvalue: det / l_max.
  const double det = s00 * s11 - s01 * s01;
  *l_min = (*l_max > 0) ? det / *l_max : mean - r;
}

// True when the point u (ellipsoid principal frame, relative to the centre) lies strictly outside
// the ellipsoid with semi-axes a: Q(x) = sum (u_i / a_i)^2 - 1 > 0. A zero semi-axis (flat
// ellipsoid) counts as outside unless the point lies in its plane.
bool outside(const Eigen::Vector3d& u, const Eigen::Vector3d& a) {
  double s = 0;
  for (int i = 0; i < 3; ++i) {
    if (u[i] == 0) continue;
    if (!(a[i] > 0)) return true;
    const double q = u[i] / a[i];
    s += q * q;
  }
  return s > 1.0;
}

// r = rotation of camera_T_object, cam = camera centre in the object frame.
ProjectedEllipse project_in_camera(const Ellipsoid& el, const CameraIntrinsics& k,
                                   const Eigen::Matrix3d& r, const Eigen::Vector3d& cam) {
  ProjectedEllipse out;
  const Eigen::Vector3d rel = el.centre - cam;
  const Eigen::Vector3d m = r * rel;  // centre in the optical frame
  out.depth_m = m.z();
  if (!(m.z() > 0)) return out;
  // Camera centre in the ellipsoid's principal frame.
  if (!outside(-(el.axes.transpose() * rel), el.semi_axes)) return out;
  // E = M M^T with M = R A diag(a): the ellipsoid's "covariance" in the optical frame.
  Eigen::Matrix3d mm = r * el.axes;
  mm.col(0) *= el.semi_axes[0];
  mm.col(1) *= el.semi_axes[1];
  mm.col(2) *= el.semi_axes[2];
  const Eigen::Vector3d r0 = mm.row(0), r1 = mm.row(1), r2 = mm.row(2);
  const double e00 = r0.squaredNorm(), e01 = r0.dot(r1), e02 = r0.dot(r2);
  const double e11 = r1.squaredNorm(), e12 = r1.dot(r2), e22 = r2.squaredNorm();
  // N = m m^T - E (the dual conic in normalised coordinates, up to sign and scale).
  const double n22 = m.z() * m.z() - e22;
  if (!(n22 > 0)) return out;  // part of the ellipsoid is level with or behind the camera
  const double inv = 1.0 / n22;
  const double n00 = (m.x() * m.x() - e00) * inv;
  const double n01 = (m.x() * m.y() - e01) * inv;
  const double n11 = (m.y() * m.y() - e11) * inv;
  const double cx = (m.x() * m.z() - e02) * inv;
  const double cy = (m.y() * m.z() - e12) * inv;
  // Normalised shape, then to pixels: S = F (c c^T - N) F, F = diag(fx, fy).
  const double s00 = (cx * cx - n00) * k.fx * k.fx;
  const double s01 = (cx * cy - n01) * k.fx * k.fy;
  const double s11 = (cy * cy - n11) * k.fy * k.fy;
  if (!(s00 > 0) || !(s11 > 0)) return out;
  const double det = s00 * s11 - s01 * s01;
  if (!(det > 0) || !std::isfinite(det)) return out;
  double l_max, l_min;
  sym2_eigenvalues(s00, s01, s11, &l_max, &l_min);
  if (!(l_min > 0)) return out;
  out.valid = true;
  out.centre = Eigen::Vector2d(k.fx * cx + k.cx, k.fy * cy + k.cy);
  out.shape << s00, s01, s01, s11;
  out.semi_axes = Eigen::Vector2d(std::sqrt(l_max), std::sqrt(l_min));
  out.area_px = kPi * std::sqrt(det);
  return out;
}

}  // namespace

ProjectedEllipse project_ellipsoid(const Ellipsoid& e, const CameraIntrinsics& k,
                                   const Pose& object_T_camera) {
  const Eigen::Matrix3d r = object_T_camera.linear().transpose();
  return project_in_camera(e, k, r, object_T_camera.translation());
}

double clipped_ellipse_area(const ProjectedEllipse& ellipse, const CameraIntrinsics& k) {
  if (!ellipse.valid) return 0.0;
  const double w = k.width, h = k.height;
  const Eigen::Matrix2d& s = ellipse.shape;
  const Eigen::Vector2d& c = ellipse.centre;
  const double hx = std::sqrt(s(0, 0)), hy = std::sqrt(s(1, 1));  // bounding-box half sizes
  const double full = kPi * std::sqrt(s(0, 0) * s(1, 1) - s(0, 1) * s(1, 0));
  if (c.x() - hx >= 0 && c.x() + hx <= w && c.y() - hy >= 0 && c.y() + hy <= h) return full;
  if (c.x() + hx <= 0 || c.x() - hx >= w || c.y() + hy <= 0 || c.y() - hy >= h) return 0.0;
  // Cholesky S = L L^T, L = [[l00, 0], [l10, l11]].
  const double l00 = hx;
  const double l10 = s(1, 0) / l00;
  const double l11_sq = s(1, 1) - l10 * l10;
  if (!(l11_sq > 0)) return 0.0;
  const double l11 = std::sqrt(l11_sq);
  auto to_disc = [&](double x, double y) {
    const double u0 = (x - c.x()) / l00;
    const double u1 = (y - c.y() - l10 * u0) / l11;
    return Eigen::Vector2d(u0, u1);
  };
  const std::array<Eigen::Vector2d, 4> corners = {to_disc(0, 0), to_disc(w, 0), to_disc(w, h),
                                                  to_disc(0, h)};
  double sum = 0;
  for (int i = 0; i < 4; ++i) sum += disc_triangle_signed_area(corners[i], corners[(i + 1) % 4]);
  const double area = std::abs(sum) * l00 * l11;
  return std::min(area, full);
}

ViewScore score_view(const std::vector<Ellipsoid>& ellipsoids, const CameraIntrinsics& k,
                     const Pose& object_T_camera) {
  ViewScore score;
  const Eigen::Matrix3d r = object_T_camera.linear().transpose();
  const Eigen::Vector3d cam = object_T_camera.translation();
  struct Item {
    double depth;
    double area;
    bool frontier;
  };
  // Small scenes (the usual case) stay on the stack.
  constexpr size_t kStack = 64;
  Item stack_items[kStack];
  std::vector<Item> heap_items;
  Item* items = stack_items;
  if (ellipsoids.size() > kStack) {
    heap_items.resize(ellipsoids.size());
    items = heap_items.data();
  }
  size_t n = 0;
  for (const Ellipsoid& e : ellipsoids) {
    const ProjectedEllipse pe = project_in_camera(e, k, r, cam);
    if (!pe.valid) continue;
    // Insertion by depth (stable: equal depths keep their input order).
    const Item it{pe.depth_m, clipped_ellipse_area(pe, k), e.cls == EllipsoidClass::kFrontier};
    size_t j = n++;
    while (j > 0 && items[j - 1].depth > it.depth) {
      items[j] = items[j - 1];
      --j;
    }
    items[j] = it;
  }
  // The item at sorted position i has rank i and weight 0.5^i.
  double w = 1.0;
  for (size_t i = 0; i < n; ++i) {
    if (items[i].frontier) {
      score.frontier_sum += w * items[i].area;
    } else {
      score.occupied_sum += w * items[i].area;
    }
    w *= 0.5;
  }
  score.visible = static_cast<int>(n);
  score.quality = score.frontier_sum - score.occupied_sum;
  return score;
}

int sector_of(const Eigen::Vector3d& eye, const Eigen::Vector3d& centre, int beta, double start_rad) {
  if (beta <= 1) return 0;
  double a = std::fmod(std::atan2(eye.y() - centre.y(), eye.x() - centre.x()) - start_rad, 2 * kPi);
  if (a < 0) a += 2 * kPi;
  if (a >= 2 * kPi) a = 0;
  const int s = static_cast<int>(std::floor(a / (2 * kPi / beta)));
  return std::clamp(s, 0, beta - 1);
}

std::vector<int> allowed_sectors(const std::vector<bool>& scanned) {
  const int beta = static_cast<int>(scanned.size());
  std::vector<int> out;
  const bool any = std::find(scanned.begin(), scanned.end(), true) != scanned.end();
  const bool all = std::find(scanned.begin(), scanned.end(), false) == scanned.end();
  if (all || !any) {  // nothing scanned yet: no constraint
    for (int i = 0; i < beta; ++i) out.push_back(i);
    return out;
  }
  for (int i = 0; i < beta; ++i) {
    if (scanned[i]) continue;
    if (scanned[(i + 1) % beta] || scanned[(i + beta - 1) % beta]) out.push_back(i);
  }
  return out;
}

}  // namespace pbnbv
