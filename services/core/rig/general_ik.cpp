// General IK for any 6R chain: Levenberg-Marquardt (damped least squares with adaptive damping)
// on the chain's geometric Jacobian, from several seeds, joint limits respected. See rig.hpp.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/base/format.hpp"
#include "core/base/units.hpp"
#include "core/rig/rig_internal.hpp"

namespace pbnbv {

using namespace rig_internal;

namespace {

constexpr int kSeedIterations = 40;        // LM iterations per seed (typically 5-15 suffice)
constexpr double kConvergedError = 1e-24;  // squared pose error (m^2 + rad^2) counted converged
constexpr double kMaxStepRad = 0.5;        // largest joint step per iteration
constexpr int kStallWindow = 5;            // LM stall window, iterations (kStallRatioFast, kStallRatioFull)
constexpr int kFullSearchSpreadSeeds = 32;  // inverse_kinematics(): spread seeds after ref, home

// target - current as a twist: position (m), rotation vector (rad), both in the same frame.
Vector6d twist_error(const Pose& target, const Pose& cur) {
  Vector6d e;
  e.head<3>() = target.translation() - cur.translation();
  const Eigen::Matrix3d r = target.linear() * cur.linear().transpose();
  const Eigen::Vector3d v(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));
  const double s = 0.5 * v.norm(), c = 0.5 * (r.trace() - 1.0);
  if (c < -0.99) {  // near pi: the skew part loses the axis
    const Eigen::AngleAxisd aa(r);
    e.tail<3>() = aa.angle() * aa.axis();
  } else {
    e.tail<3>() = s < 1e-15 ? Eigen::Vector3d(0.5 * v) : Eigen::Vector3d(std::atan2(s, c) / (2 * s) * v);
  }
  return e;
}

// Joint i's value brought into its limits: a 2*pi turn (the same geometry) when that fits, else
// clamped.
double into_limits(const RigModel& rig, int i, double v) {
  const double lo = rig.q_lower[i], hi = rig.q_upper[i];
  if (v < lo) {
    const double w = v + 2.0 * kPi * std::ceil((lo - v) / (2.0 * kPi));
    return w <= hi ? w : lo;
  }
  if (v > hi) {
    const double w = v - 2.0 * kPi * std::ceil((v - hi) / (2.0 * kPi));
    return w >= lo ? w : hi;
  }
  return v;
}

// Levenberg-Marquardt from `seed` towards base_T_target (flange in the base frame); joints kept
// within their limits at every step. True when the pose error vanished.
bool lm_solve(const RigModel& rig, const Pose& base_T_target, const Vector6d& seed, int max_iter,
              double stall_ratio, Vector6d* q_out) {
  Vector6d q;
  for (int i = 0; i < 6; ++i) q[i] = into_limits(rig, i, seed[i]);
  Matrix6d jac, jac_next;
  Vector6d e = twist_error(base_T_target, chain_fk_jacobian(rig, q, &jac));
  double f = e.squaredNorm();
  double lambda = 1e-3;
  double f_before = f;  // error kStallWindow iterations ago
  for (int it = 0; it < max_iter && f > kConvergedError; ++it) {
    if (it > 0 && it % kStallWindow == 0) {
      if (f > stall_ratio * f_before) break;  // stalled: a local minimum or a joint limit in the way
      f_before = f;
    }
    Matrix6d a = jac.transpose() * jac;
    a.diagonal().array() += lambda;
    Vector6d dq = a.llt().solve(jac.transpose() * e);  // a is positive definite
    const double mx = dq.cwiseAbs().maxCoeff();
    if (!(mx < 1e9)) return false;  // NaN or runaway
    if (mx > kMaxStepRad) dq *= kMaxStepRad / mx;
    Vector6d qn = q + dq;
    for (int i = 0; i < 6; ++i) qn[i] = into_limits(rig, i, qn[i]);
    const Vector6d en = twist_error(base_T_target, chain_fk_jacobian(rig, qn, &jac_next));
    const double fn = en.squaredNorm();
    if (fn < f) {
      q = qn;
      e = en;
      f = fn;
      jac = jac_next;
      lambda = std::max(lambda * 0.1, 1e-12);
    } else {
      lambda *= 10.0;
      if (lambda > 1e4) break;  // stuck in a local minimum or against a limit
    }
  }
  if (f > kConvergedError) return false;
  *q_out = q;
  return true;
}

// Upper bound of the distance from joint 1's axis point to the flange origin: each joint turns
// the rest of the chain about its own axis point, so the distances between consecutive axis
// points (and from the last to the flange) never change.
double chain_reach_bound(const RigModel& rig, Eigen::Vector3d* first_anchor) {
  Pose t = Pose::Identity();
  double sum = 0;
  Eigen::Vector3d prev;
  for (int i = 0; i < 6; ++i) {
    t = t * rig.chain[i].parent_T_body;
    const Eigen::Vector3d p = t * rig.chain[i].anchor;
    if (i == 0) *first_anchor = p;
    else sum += (p - prev).norm();
    prev = p;
  }
  return sum + ((t * rig.last_T_flange).translation() - prev).norm();
}

}  // namespace

namespace rig_internal {

// Quasi-random configurations spread over the joint ranges (Halton sequence; ranges wider than
// one turn cut to +-pi, other turns being the same geometry).
std::vector<Vector6d> spread_seeds(const RigModel& rig, int n) {
  static constexpr int kBases[6] = {2, 3, 5, 7, 11, 13};
  std::vector<Vector6d> out;
  for (int k = 1; k <= n; ++k) {
    Vector6d q;
    for (int i = 0; i < 6; ++i) {
      double f = 1, r = 0;
      for (int x = k; x > 0; x /= kBases[i]) {
        f /= kBases[i];
        r += f * (x % kBases[i]);
      }
      const double lo = std::max(rig.q_lower[i], -kPi), hi = std::min(rig.q_upper[i], kPi);
      q[i] = lo + r * (hi - lo);
    }
    out.push_back(q);
  }
  return out;
}

// "out of reach" reason when the flange pose is provably beyond the chain's reach, else "".
std::string general_out_of_reach(const RigModel& rig, const Pose& base_T_target) {
  Eigen::Vector3d p1;
  const double bound = chain_reach_bound(rig, &p1);
  const double dist = (base_T_target.translation() - p1).norm();
  if (dist <= bound + 1e-9) return "";
  return "out of reach: the flange is " + fixed(dist, 3) + " m from the first joint, the arm reaches at most " +
         fixed(bound, 3) + " m";
}

bool general_ik_seed(const RigModel& rig, const Pose& world_T_flange, const Vector6d& seed,
                     double stall_ratio, Vector6d* q) {
  Vector6d sol;
  if (!lm_solve(rig, rig.world_T_base.inverse() * world_T_flange, seed, kSeedIterations, stall_ratio, &sol)) {
    return false;
  }
  const auto [ep, er] = pose_error(flange_in_world(rig, sol), world_T_flange);
  if (ep > kVerifyPosTol || er > kVerifyRotTol || !within_limits(rig, sol)) return false;
  *q = sol;
  return true;
}

// General IK: the distinct solutions reached from q_ref, home and the spread seeds, with their
// +-2*pi variants.
std::vector<Vector6d> general_ik(const RigModel& rig, const Pose& world_T_flange,
                                 const Vector6d& q_ref, std::string* why_none) {
  const std::string far = general_out_of_reach(rig, rig.world_T_base.inverse() * world_T_flange);
  if (!far.empty()) {
    if (why_none) *why_none = far;
    return {};
  }
  std::vector<Vector6d> seeds{q_ref, rig.q_home};
  const std::vector<Vector6d> spread = spread_seeds(rig, kFullSearchSpreadSeeds);
  seeds.insert(seeds.end(), spread.begin(), spread.end());
  std::vector<Vector6d> distinct;
  for (const Vector6d& seed : seeds) {
    Vector6d q;
    if (!general_ik_seed(rig, world_T_flange, seed, kStallRatioFull, &q)) continue;
    bool dup = false;
    for (const Vector6d& d : distinct) dup = dup || same_modulo_turns(d, q);
    if (!dup) distinct.push_back(q);
  }
  const std::array<bool, 6> revolute{true, true, true, true, true, true};
  std::vector<Vector6d> sols;
  std::string violation;
  for (const Vector6d& q : distinct) expand_variants(rig, q, revolute, &sols, &violation);
  if (sols.empty() && why_none) {
    *why_none = distinct.empty()
                    ? "no IK solution within the joint limits from " + std::to_string(seeds.size()) +
                          " seeds (out of reach or beyond the limits)"
                    : "all " + std::to_string(distinct.size()) + " solutions violate joint limits" +
                          (violation.empty() ? std::string() : " (e.g. " + violation + ")");
  }
  return sols;
}

}  // namespace rig_internal

bool general_ik_from_seed(const RigModel& rig, const Pose& world_T_flange, const Vector6d& seed,
                          Vector6d* q) {
  if (rig.kind != RigKind::kArm) throw std::invalid_argument("general_ik_from_seed: not an arm rig");
  return general_ik_seed(rig, world_T_flange, seed, kStallRatioFull, q);
}

}  // namespace pbnbv
