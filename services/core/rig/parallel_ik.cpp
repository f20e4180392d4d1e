// Closed-form IK of the parallel-axes layout (the Universal Robots arms): joints 2, 3 and 4 turn
// about parallel axes, the axes of joints 4 and 5 meet, and so do those of joints 5 and 6. See
// rig.hpp (IkMethod::kParallelAxes).
//
// Written on the chain's screw axes at q = 0 (product of exponentials), not on DH parameters, so
// that it reads the MJCF body tree as it is: joint i turns the rest of the chain about the line
// (w_i, r_i), and base_T_flange(q) = E1(q1) ... E6(q6) M with M the flange at q = 0. With
// g = target M^-1 = E1 ... E6, every step is one of two subproblems: "the angle about w that
// makes v . R(w, t) u equal c" (two solutions) or "the angle about w that takes u to v" (one):
//   q1: the point p56 where axes 5 and 6 meet is moved by E1...E4 only, and E2 E3 E4 (parallel
//       axes) keep its component along w2: (E1^-1 g p56) . w2 = p56 . w2.
//   q5: R6 keeps w6 and R2 R3 R4 keep w2, so w2 . R5 w6 = w2 . R1^T Rg w6.
//   q6: R6 (Rg^T R1 w2) = R5^T w2.
//   q3: the point p45 where axes 4 and 5 meet is moved by E2 E3 only; its distance from axis 2,
//       across the axes, fixes q3 (the planar elbow), then q2 turns it into place and q4 is what
//       is left of the rotation E2 E3 E4.
// Up to 8 solutions; each is verified by forward kinematics (checked_arm_solutions), so a chain
// that only nearly has the layout loses nothing but speed: load_rig takes this method only when
// configurations spread over the joint ranges come back through it (parallel_axes_layout).
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "core/base/format.hpp"
#include "core/base/units.hpp"
#include "core/rig/rig_internal.hpp"

namespace pbnbv {

using namespace rig_internal;

namespace {

constexpr double kAxisTol = 1e-9;      // parallel / meeting axes: |sin| and distance, (m)
constexpr double kDegenerate = 1e-12;  // a subproblem whose coefficients vanish (a singularity)
constexpr int kRoundTripConfigurations = 24;  // parallel_axes_layout's self-check

// The chain's joint axes at q = 0 in the base frame, and where axes 4-5 and 5-6 meet.
struct Screws {
  std::array<Eigen::Vector3d, 6> w, r;  // unit direction, a point on the axis
  Pose m = Pose::Identity();            // the flange at q = 0
  Eigen::Vector3d p45, p56;
};

Screws home_screws(const RigModel& rig) {
  Screws s;
  Pose t = Pose::Identity();
  for (int i = 0; i < 6; ++i) {
    t = t * rig.chain[i].parent_T_body;
    s.w[i] = (t.linear() * rig.chain[i].axis).normalized();
    s.r[i] = t * rig.chain[i].anchor;
  }
  s.m = t * rig.last_T_flange;
  return s;
}

// Where lines (r_a, w_a) and (r_b, w_b) meet (the midpoint of their closest points); nullopt
// when they are parallel or pass each other further apart than kAxisTol.
std::optional<Eigen::Vector3d> meeting_point(const Eigen::Vector3d& ra, const Eigen::Vector3d& wa,
                                             const Eigen::Vector3d& rb, const Eigen::Vector3d& wb) {
  const double c = wa.dot(wb), den = 1.0 - c * c;
  if (den < kAxisTol) return std::nullopt;
  const Eigen::Vector3d d = rb - ra;
  const double sa = (d.dot(wa) - c * d.dot(wb)) / den, sb = (c * d.dot(wa) - d.dot(wb)) / den;
  const Eigen::Vector3d pa = ra + sa * wa, pb = rb + sb * wb;
  if ((pa - pb).norm() > kAxisTol) return std::nullopt;
  return 0.5 * (pa + pb);
}

bool parallel(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return a.cross(b).norm() < kAxisTol; }

// The rigid motion of turning by `angle` about the line (r, w).
Pose turn_about(const Eigen::Vector3d& w, const Eigen::Vector3d& r, double angle) {
  Pose p = Pose::Identity();
  p.linear() = Eigen::AngleAxisd(angle, w).toRotationMatrix();
  p.translation() = r - p.linear() * r;
  return p;
}

// The angles t with v . R(w, t) u = c (w unit): R u = (w.u) w + cos t (u - (w.u) w) + sin t w x u,
// so A cos t + B sin t = c - (w.u)(w.v). Empty when |c'| > hypot(A, B) (beyond reach); nullopt
// when A = B = 0 (every angle or none: a singularity, resolved by the caller).
std::optional<std::vector<double>> angles_for_projection(const Eigen::Vector3d& v, const Eigen::Vector3d& w,
                                                         const Eigen::Vector3d& u, double c) {
  const double wu = w.dot(u), wv = w.dot(v);
  const double a = v.dot(u) - wu * wv, b = v.dot(w.cross(u)), n = std::hypot(a, b);
  if (n < kDegenerate) return std::nullopt;
  double k = (c - wu * wv) / n;
  if (std::abs(k) > 1.0 + 1e-9) return std::vector<double>{};
  k = std::clamp(k, -1.0, 1.0);
  const double base = std::atan2(b, a), d = std::acos(k);
  if (d < 1e-12) return std::vector<double>{base};
  return std::vector<double>{base + d, base - d};
}

// The angle about w that takes u to v (their parts across w); nullopt when u lies along w.
std::optional<double> angle_taking(const Eigen::Vector3d& w, const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
  const Eigen::Vector3d up = u - w.dot(u) * w, vp = v - w.dot(v) * w;
  if (up.norm() < kDegenerate || vp.norm() < kDegenerate) return std::nullopt;
  return std::atan2(w.dot(up.cross(vp)), up.dot(vp));
}

// The layout's points, or false when the chain does not have it.
bool layout_points(Screws* s) {
  if (!parallel(s->w[1], s->w[2]) || !parallel(s->w[1], s->w[3])) return false;
  const auto p45 = meeting_point(s->r[3], s->w[3], s->r[4], s->w[4]);
  const auto p56 = meeting_point(s->r[4], s->w[4], s->r[5], s->w[5]);
  if (!p45 || !p56) return false;
  s->p45 = *p45;
  s->p56 = *p56;
  return true;
}

}  // namespace

namespace rig_internal {

namespace {

// The raw solutions (not yet verified); empty with the reason when the pose is out of reach.
std::vector<Vector6d> parallel_axes_raw(const RigModel& rig, const Pose& world_T_flange, const Vector6d& q_ref,
                                        std::string* why_none) {
  Screws s = home_screws(rig);
  if (!layout_points(&s)) {
    throw std::invalid_argument("rig model " + rig.model_path +
                                ": the parallel-axes IK needs joints 2-4 parallel and axes 4-5, 5-6 meeting; "
                                "use the general IK");
  }
  const auto& w = s.w;
  const auto& r = s.r;
  const Pose g = rig.world_T_base.inverse() * world_T_flange * s.m.inverse();
  const Eigen::Matrix3d& rg = g.linear();
  const auto across = [&](const Eigen::Vector3d& x) -> Eigen::Vector3d { return x - w[1].dot(x) * w[1]; };

  // q1: the wrist point's component along the parallel axes.
  const Eigen::Vector3d wrist = g * s.p56;
  std::vector<double> q1s;
  if (const auto a = angles_for_projection(wrist - r[0], w[0], w[1], w[1].dot(s.p56) - w[1].dot(r[0]))) q1s = *a;
  else q1s = {q_ref[0]};  // the wrist point on axis 1: any q1 (or none; verification decides)
  if (q1s.empty()) {
    if (why_none) {
      const Eigen::Vector3d off = wrist - r[0] - w[0].dot(wrist - r[0]) * w[0];
      *why_none = "out of reach: the wrist (axes 5-6) is " + fixed(off.norm(), 3) + " m from the " +
                  rig.joint_names[0] + " axis, less than the arm's offset along the " + rig.joint_names[1] + " axis";
    }
    return {};
  }

  std::vector<Vector6d> raw;
  double nearest_miss = std::numeric_limits<double>::infinity();  // beyond the elbow's reach, m
  for (const double q1 : q1s) {
    const Pose e1 = turn_about(w[0], r[0], q1);
    const Eigen::Matrix3d& r1 = e1.linear();
    std::vector<double> q5s;
    if (const auto a = angles_for_projection(w[1], w[4], w[5], w[1].dot(r1.transpose() * rg * w[5]))) q5s = *a;
    else q5s = {q_ref[4]};
    for (const double q5 : q5s) {
      const Pose e5 = turn_about(w[4], r[4], q5);
      const double q6 = angle_taking(w[5], rg.transpose() * r1 * w[1], e5.linear().transpose() * w[1]).value_or(q_ref[5]);
      const Pose e6 = turn_about(w[5], r[5], q6);
      const Pose g234 = e1.inverse() * g * e6.inverse() * e5.inverse();
      const Eigen::Vector3d target45 = g234 * s.p45;
      const Eigen::Vector3d u3 = across(s.p45 - r[2]), v3 = across(r[2] - r[1]);
      const double d2 = across(target45 - r[1]).squaredNorm();
      std::vector<double> q3s;
      if (const auto a = angles_for_projection(v3, w[2], u3, 0.5 * (d2 - u3.squaredNorm() - v3.squaredNorm()))) q3s = *a;
      else q3s = {q_ref[2]};
      if (q3s.empty()) {
        const double reach = u3.norm() + v3.norm(), inner = std::abs(u3.norm() - v3.norm()), d = std::sqrt(d2);
        nearest_miss = std::min(nearest_miss, d > reach ? d - reach : inner - d);
      }
      for (const double q3 : q3s) {
        const Pose e3 = turn_about(w[2], r[2], q3);
        const double q2 = angle_taking(w[1], e3 * s.p45 - r[1], target45 - r[1]).value_or(q_ref[1]);
        const Pose e2 = turn_about(w[1], r[1], q2);
        const Eigen::Matrix3d r4 = (e2.linear() * e3.linear()).transpose() * g234.linear();
        const Eigen::Vector3d a = w[3].unitOrthogonal();
        Vector6d q;
        q << q1, q2, q3, std::atan2(w[3].dot(a.cross(r4 * a)), a.dot(r4 * a)), q5, q6;
        raw.push_back(q);
      }
    }
  }
  if (raw.empty()) {
    if (why_none) {
      *why_none = "out of reach: the wrist (axes 4-5) is " + fixed(nearest_miss, 3) + " m beyond what the " +
                  rig.joint_names[1] + " and " + rig.joint_names[2] + " links reach";
    }
  }
  return raw;
}

}  // namespace

std::vector<Vector6d> parallel_axes_ik(const RigModel& rig, const Pose& world_T_flange, const Vector6d& q_ref,
                                       std::string* why_none) {
  const std::vector<Vector6d> raw = parallel_axes_raw(rig, world_T_flange, q_ref, why_none);
  if (raw.empty()) return {};
  return checked_arm_solutions(rig, world_T_flange, raw, why_none);
}

std::vector<Vector6d> parallel_axes_ik_nearest(const RigModel& rig, const Pose& world_T_flange, const Vector6d& q_ref,
                                               std::string* why_none) {
  const std::vector<Vector6d> raw = parallel_axes_raw(rig, world_T_flange, q_ref, why_none);
  std::vector<Vector6d> out;
  int bad_joint = -1, verified = 0;
  for (const Vector6d& r : raw) {
    const auto v = verified_arm_solution(rig, world_T_flange, r);
    if (!v) continue;
    ++verified;
    Vector6d q;
    for (int i = 0; i < 6; ++i) q[i] = nearest_in_limits(rig, i, (*v)[i], q_ref[i]);
    int bad = -1;
    if (!within_limits(rig, q, &bad)) {
      if (bad_joint < 0) bad_joint = bad;
      continue;
    }
    if (std::none_of(out.begin(), out.end(), [&](const Vector6d& o) { return same_modulo_turns(o, q); })) out.push_back(q);
  }
  if (out.empty() && !raw.empty() && why_none) {
    *why_none = verified == 0 ? "none of the " + std::to_string(raw.size()) + " closed-form solutions reaches the pose"
                              : "all " + std::to_string(verified) + " solutions violate joint limits (e.g. " +
                                    rig.joint_names[bad_joint] + ")";
  }
  return out;
}

bool parallel_axes_layout(const RigModel& rig) {
  Screws s = home_screws(rig);
  if (!layout_points(&s)) return false;
  // Self-check: configurations spread over the joint ranges, and the zero one (singular: wrist
  // axes 4 and 6 in line), come back through it. (Home is not known yet when load_rig asks.)
  std::vector<Vector6d> qs = spread_seeds(rig, kRoundTripConfigurations);
  qs.push_back(Vector6d::Zero());
  for (const Vector6d& q : qs) {
    const std::vector<Vector6d> sols = parallel_axes_ik(rig, flange_in_world(rig, q), q, nullptr);
    bool back = false;
    for (const Vector6d& x : sols) back = back || same_modulo_turns(x, q);
    if (!back) return false;
  }
  return true;
}

}  // namespace rig_internal

}  // namespace pbnbv
