// ReachabilityChecker: IK solutions per candidate turntable angle, checked for collisions and a
// free line of sight in the rig's MuJoCo model. See rig.hpp (and rig_model.cpp's header comment).
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>

#include "core/base/format.hpp"
#include "core/base/units.hpp"
#include "core/rig/rig_internal.hpp"

namespace pbnbv {

using namespace rig_internal;

namespace {

// The turntable angles' grid of azimuth offsets (candidate_turntable_angles), and how often
// refine_least_turn halves a step of it (15 / 2^3: within 1.9 deg of the least clear turn).
constexpr int kTurnGridDeg = 15;
constexpr double kTurnGridRad = kTurnGridDeg * kPi / 180.0;
constexpr int kLeastTurnRefineSteps = 3;

// A keep-out box that encloses a volume (not empty, not flat): only such a box is checked.
bool has_volume(const Eigen::AlignedBox3d& box) { return !box.isEmpty() && box.sizes().minCoeff() > 0; }

}  // namespace

struct ReachabilityChecker::Impl {
  RigModel rig;
  ModelPtr model;
  DataPtr data;
  std::array<int, 6> qadr{};
  int turntable_qadr = -1;
  int keepout = -1;
  int keepout_contype = 0, keepout_conaffinity = 0;
  std::vector<char> arm_side;  // per geom: on the moving arm (or gantry) side
  std::vector<std::string> side_name;  // per geom: name used in reasons
  std::vector<char> in_object;  // per geom: part of the object mount (never an occluder)
  std::vector<char> follows_flange;  // per geom: on the last joint's body or below (its pose is
                                     // fixed by the flange pose alone)
  bool have_neighbour = false;  // solve_batch: the previous candidate's solution seeds the next
  Vector6d neighbour = Vector6d::Zero();
  // Per arm joint: the farthest any geom it carries (up to the next joint, then through it)
  // reaches from a point on its axis, m: a point's path over a straight joint-space move is at
  // most sum |dq_i| * lever[i] long.
  std::array<double, 6> lever{};
  TurntableChoice choice = TurntableChoice::kPreferred;

  // The keep-out geom as the cylinder about the turntable axis of radius r and half height `half`,
  // its centre z_centre above the object mount (its flags left to the caller).
  void keepout_cylinder(double r, double half, double z_centre) {
    mjModel* m = model.get();
    m->geom_type[keepout] = mjGEOM_CYLINDER;
    m->geom_size[3 * keepout] = r;
    m->geom_size[3 * keepout + 1] = half;
    m->geom_pos[3 * keepout] = m->geom_pos[3 * keepout + 1] = 0;  // on the axis
    m->geom_pos[3 * keepout + 2] = z_centre;
    m->geom_quat[4 * keepout] = 1;
    m->geom_quat[4 * keepout + 1] = m->geom_quat[4 * keepout + 2] = m->geom_quat[4 * keepout + 3] = 0;
    m->geom_rbound[keepout] = std::hypot(r, half);
  }

  // The keep-out box, placed in the object frame (on the platter: it turns with the turntable).
  // `turning`: the box as the turntable sweeps it through any angle, i.e. the cylinder about the
  // turntable axis through its farthest corner (same height).
  void set_keepout(const Eigen::AlignedBox3d& box, double object_z_m, bool turning = false) {
    mjModel* m = model.get();
    if (!has_volume(box)) {
      m->geom_contype[keepout] = 0;
      m->geom_conaffinity[keepout] = 0;
      return;
    }
    const Eigen::Vector3d half = 0.5 * box.sizes();
    Eigen::Vector3d c = box.center();
    if (rig.kind == RigKind::kArm) c.z() += object_z_m;
    m->geom_contype[keepout] = keepout_contype;
    m->geom_conaffinity[keepout] = keepout_conaffinity;
    if (turning && rig.has_turntable) {
      double r = 0;
      for (int k = 0; k < 4; ++k) {
        r = std::max(r, std::hypot((k & 1) ? box.max().x() : box.min().x(), (k & 2) ? box.max().y() : box.min().y()));
      }
      keepout_cylinder(r, half.z(), c.z());
      return;
    }
    m->geom_quat[4 * keepout] = 1;
    m->geom_quat[4 * keepout + 1] = m->geom_quat[4 * keepout + 2] = m->geom_quat[4 * keepout + 3] = 0;
    m->geom_type[keepout] = mjGEOM_BOX;
    for (int i = 0; i < 3; ++i) {
      m->geom_size[3 * keepout + i] = half[i];
      m->geom_pos[3 * keepout + i] = c[i];
    }
    m->geom_rbound[keepout] = half.norm();
  }

  // Line of sight: rays from the optical centre to the object frame origin and to the keep-out
  // box corners pulled 20% towards its centre must not hit a rendered geom (groups 0..2) of the
  // rig, e.g. the arm's own links or the pedestal. Call after place() (uses its kinematics).
  // Returns the name of the blocking geom's body/geom, or "" when the view is clear.
  std::string occluder(const Pose& world_T_camera, const Eigen::AlignedBox3d& box, double turntable_rad,
                       double object_z_m, bool* view_fixed = nullptr) {
    const mjModel* m = model.get();
    mjData* d = data.get();
    const Pose w_o = object_in_world(rig, turntable_rad, object_z_m);
    std::vector<Eigen::Vector3d> targets{w_o.translation()};
    if (has_volume(box)) {
      const Eigen::Vector3d half = 0.5 * box.sizes();
      const Eigen::Vector3d c = box.center();
      targets[0] = w_o * c;
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3d s((k & 1) ? 1 : -1, (k & 2) ? 1 : -1, (k & 4) ? 1 : -1);
        targets.push_back(w_o * (c + 0.8 * s.cwiseProduct(half)));
      }
    }
    const Eigen::Vector3d eye = world_T_camera.translation();
    const mjtByte groups[6] = {1, 1, 1, 0, 0, 0};
    for (const Eigen::Vector3d& t : targets) {
      const Eigen::Vector3d vec = t - eye;
      int gid = -1;
      const mjtNum x = mj_ray(m, d, eye.data(), vec.data(), groups, 1, -1, &gid);
      if (gid >= 0 && x >= 0 && x < 1.0 && !in_object[gid]) {
        if (view_fixed) *view_fixed = !arm_side[gid] || follows_flange[gid];
        return side_name[gid];
      }
    }
    return "";
  }

  // Colliding arm/environment geom pairs at this state (keep-out box already set).
  // `view_fixed` (optional): every colliding pair involves a geom that follows the flange (its
  // pose is fixed by the view, whatever the configuration).
  std::vector<std::string> colliding(const Vector6d& q, double turntable_rad, bool* view_fixed = nullptr) {
    place(q, turntable_rad);
    return colliding_placed(view_fixed);
  }

  // Kinematics of the model at this state (for occluder() and colliding_placed()).
  void place(const Vector6d& q, double turntable_rad) {
    mjData* d = data.get();
    for (int i = 0; i < 6; ++i) d->qpos[qadr[i]] = q[i];
    if (turntable_qadr >= 0) d->qpos[turntable_qadr] = turntable_rad - rig.turntable_zero_rad;
    mj_kinematics(model.get(), d);
  }

  // The lever of each arm joint (see `lever`), from the kinematics at home: distances between
  // points fixed in one body do not depend on the configuration.
  void compute_levers() {
    const mjModel* m = model.get();
    mjData* d = data.get();
    place(rig.q_home, 0);
    std::array<int, 6> jid{}, body{};
    for (int i = 0; i < 6; ++i) {
      jid[i] = mj_name2id(m, mjOBJ_JOINT, rig.joint_names[i].c_str());
      body[i] = m->jnt_bodyid[jid[i]];
    }
    const auto anchor = [&](int i) { return Eigen::Vector3d(d->xanchor[3 * jid[i]], d->xanchor[3 * jid[i] + 1], d->xanchor[3 * jid[i] + 2]); };
    std::array<double, 6> own{};  // per joint: the geoms whose nearest joint above is this one
    for (int g = 0; g < m->ngeom; ++g) {
      if (!arm_side[g]) continue;
      int carrier = -1;
      for (int b = m->geom_bodyid[g]; b > 0 && carrier < 0; b = m->body_parentid[b]) {
        for (int i = 0; i < 6; ++i) {
          if (body[i] == b) carrier = std::max(carrier, i);
        }
      }
      if (carrier < 0) continue;
      const Eigen::Vector3d c(d->geom_xpos[3 * g], d->geom_xpos[3 * g + 1], d->geom_xpos[3 * g + 2]);
      own[carrier] = std::max(own[carrier], (c - anchor(carrier)).norm() + m->geom_rbound[g]);
    }
    for (int i = 5; i >= 0; --i) {
      lever[i] = own[i];
      if (i < 5) lever[i] = std::max(lever[i], (anchor(i + 1) - anchor(i)).norm() + lever[i + 1]);
    }
  }

  // The first colliding pair on the straight move a -> b ("" when clear), keep-out box set by the
  // caller; `at` receives the fraction of the move where it is.
  std::string first_contact_on(const RigState& a, const RigState& b, double* at) {
    double length = 0;  // a bound on the path length of any point of the arm
    for (int i = 0; i < 6; ++i) length += std::abs(b.q[i] - a.q[i]) * lever[i];
    const int n = std::max(1, static_cast<int>(std::ceil(length / kPathStepM)));
    for (int k = 1; k <= n; ++k) {
      const double s = static_cast<double>(k) / n;
      const std::vector<std::string> c = colliding(a.q + s * (b.q - a.q), a.turntable_rad + s * (b.turntable_rad - a.turntable_rad));
      if (!c.empty()) {
        *at = s;
        return c.front();
      }
    }
    return "";
  }

  // colliding() at the state last placed.
  std::vector<std::string> colliding_placed(bool* view_fixed = nullptr) {
    mjModel* m = model.get();
    mjData* d = data.get();
    mj_collision(m, d);
    if (view_fixed) *view_fixed = true;
    std::vector<std::string> out;
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& c = d->contact[i];
      const bool a1 = arm_side[c.geom1], a2 = arm_side[c.geom2];
      if (a1 == a2) continue;
      if (c.dist >= kContactMargin) continue;
      const int ga = a1 ? c.geom1 : c.geom2, ge = a1 ? c.geom2 : c.geom1;
      if (view_fixed) *view_fixed = *view_fixed && follows_flange[ga];
      const std::string s = side_name[ga] + " / " + side_name[ge];
      if (std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
    }
    return out;
  }
};

ReachabilityChecker::ReachabilityChecker(const RigModel& rig, TurntableChoice choice) : impl_(std::make_unique<Impl>()) {
  Impl& im = *impl_;
  im.rig = rig;
  im.choice = choice;
  im.model = load_mj_model(rig.model_path);
  mjModel* m = im.model.get();
  im.data = DataPtr(mj_makeData(m));
  if (!im.data) throw std::runtime_error("rig model " + rig.model_path + ": mj_makeData failed");
  for (int i = 0; i < 6; ++i) {
    const int j = mj_name2id(m, mjOBJ_JOINT, rig.joint_names[i].c_str());
    if (j < 0) fail(rig.model_path, "missing joint \"" + rig.joint_names[i] + "\"");
    im.qadr[i] = m->jnt_qposadr[j];
  }
  const int tt = mj_name2id(m, mjOBJ_JOINT, "turntable");
  im.turntable_qadr = tt >= 0 ? m->jnt_qposadr[tt] : -1;
  im.keepout = mj_name2id(m, mjOBJ_GEOM, "keepout");
  if (im.keepout < 0) fail(rig.model_path, "missing geom \"keepout\"");

  // Arm side: geoms of bodies in the subtree of the first joint's body.
  const int first = m->jnt_bodyid[mj_name2id(m, mjOBJ_JOINT, rig.joint_names[0].c_str())];
  const int mount = mj_name2id(m, mjOBJ_BODY, "object_mount");
  im.arm_side.assign(m->ngeom, 0);
  im.in_object.assign(m->ngeom, 0);
  im.follows_flange.assign(m->ngeom, 0);
  const int last = m->jnt_bodyid[mj_name2id(m, mjOBJ_JOINT, rig.joint_names[5].c_str())];
  im.side_name.assign(m->ngeom, "");
  int arm_contype = 0, arm_conaffinity = 0;
  for (int g = 0; g < m->ngeom; ++g) {
    int b = m->geom_bodyid[g];
    const int body = b;
    bool arm = false;
    while (b > 0) {
      if (b == first) arm = true;
      b = m->body_parentid[b];
    }
    im.arm_side[g] = arm;
    for (int bb = body; bb > 0; bb = m->body_parentid[bb]) {
      if (bb == mount) im.in_object[g] = 1;
      if (bb == last) im.follows_flange[g] = 1;
    }
    const char* bn = mj_id2name(m, mjOBJ_BODY, body);
    const char* gn = mj_id2name(m, mjOBJ_GEOM, g);
    if (arm) {
      im.side_name[g] = bn ? bn : ("body " + std::to_string(body));
      arm_contype |= m->geom_contype[g];
      arm_conaffinity |= m->geom_conaffinity[g];
    } else {
      im.side_name[g] = gn ? gn : (bn ? bn : ("geom " + std::to_string(g)));
    }
    m->geom_margin[g] = kContactMargin;
  }
  // The keep-out box collides with the arm side only.
  im.keepout_contype = arm_conaffinity;
  im.keepout_conaffinity = arm_contype;
  m->geom_contype[im.keepout] = 0;
  m->geom_conaffinity[im.keepout] = 0;
  // The box is moved around: make mj_kinematics place it from geom_pos/geom_quat rather than
  // copying the body (or inertial) frame.
  m->geom_sameframe[im.keepout] = 0;
  if (rig.kind == RigKind::kArm) im.compute_levers();
}

ReachabilityChecker::~ReachabilityChecker() = default;

void ReachabilityChecker::set_turntable_choice(TurntableChoice choice) { impl_->choice = choice; }
TurntableChoice ReachabilityChecker::turntable_choice() const { return impl_->choice; }

std::string ReachabilityChecker::path_collision(const RigState& from, const RigState& to,
                                                const Eigen::AlignedBox3d& keepout, double object_z_m) {
  Impl& im = *impl_;
  if (im.rig.kind != RigKind::kArm) return "";  // the gantry flies through (rig_free.xml)
  im.set_keepout(keepout, object_z_m, std::abs(to.turntable_rad - from.turntable_rad) > 1e-9);
  double at = 0;
  const std::string hit = im.first_contact_on(from, to, &at);
  if (hit.empty()) return "";
  return hit + " at " + fixed(100 * at, 0) + " % of the move";
}

namespace {

// The arm configuration with the camera `back_m` behind where it is at `q` along its view axis
// (turntable unchanged): the IK solution quickest to reach from `q`; none when out of reach.
std::optional<Vector6d> backed_off(const RigModel& rig, const Vector6d& q, double back_m) {
  Pose w_c = camera_in_world(rig, q);
  w_c.translation() -= back_m * w_c.linear().col(2);
  const std::vector<Vector6d> sols = inverse_kinematics(rig, w_c * rig.flange_T_camera.inverse(), nullptr, q);
  std::optional<Vector6d> best;
  for (const Vector6d& s : sols) {
    if (!best || arm_move_s(rig, q, s) < arm_move_s(rig, q, *best)) best = s;
  }
  return best;
}

}  // namespace

RigPath ReachabilityChecker::plan_path(const RigState& from, const RigState& to, const Eigen::AlignedBox3d& keepout,
                                       double object_z_m) {
  const RigModel& rig = impl_->rig;
  RigPath out;
  out.route = "direct";
  out.stops = {to};
  out.time_s = move_s(rig, from, to);
  const std::string direct = path_collision(from, to, keepout, object_z_m);
  if (direct.empty()) {
    out.clear = true;
    return out;
  }
  std::vector<std::pair<std::string, std::vector<RigState>>> routes;
  // One joint group at a time: the turntable first, or the arm first (a turning keep-out box
  // is checked as its sweep; one that stands still as it is).
  routes.push_back({"turntable first", {{from.q, to.turntable_rad}, to}});
  routes.push_back({"arm first", {{to.q, from.turntable_rad}, to}});
  const std::optional<Vector6d> ra = backed_off(rig, from.q, kPathRetreatM), rb = backed_off(rig, to.q, kPathRetreatM);
  const std::optional<Vector6d> ra2 = backed_off(rig, from.q, 2 * kPathRetreatM),
                                rb2 = backed_off(rig, to.q, 2 * kPathRetreatM);
  const auto retreat = [&](double back, const std::optional<Vector6d>& a, const std::optional<Vector6d>& b) {
    if (a && b) {
      routes.push_back({"retreat " + fixed(back, 2) + " m, turn, approach", {{*a, from.turntable_rad}, {*b, to.turntable_rad}, to}});
    }
  };
  retreat(kPathRetreatM, ra, rb);
  retreat(2 * kPathRetreatM, ra2, rb2);
  routes.push_back({"via home", {{rig.q_home, to.turntable_rad}, to}});
  if (ra && rb) {
    routes.push_back({"retreat, home, approach",
                      {{*ra, from.turntable_rad}, {rig.q_home, to.turntable_rad}, {*rb, to.turntable_rad}, to}});
  }
  std::string reasons = "direct: " + direct;
  for (const auto& [name, stops] : routes) {
    double t = 0;
    std::string hit;
    RigState at = from;
    for (const RigState& next : stops) {
      t += move_s(rig, at, next);
      if (out.clear && t >= out.time_s) break;  // no quicker than the clear route found
      hit = path_collision(at, next, keepout, object_z_m);
      if (!hit.empty()) break;
      at = next;
    }
    if (!hit.empty()) {
      reasons += "; " + name + ": " + hit;
      continue;
    }
    if (out.clear && t >= out.time_s) continue;
    out.clear = true;
    out.stops = stops;
    out.time_s = t;
    out.route = name;
  }
  if (!out.clear) {
    out.stops.clear();
    out.route.clear();
    out.reason = "no collision-free path from where the rig stands (" + reasons + ")";
  }
  return out;
}

std::vector<std::string> ReachabilityChecker::collisions(const Vector6d& q, double turntable_rad,
                                                         const Eigen::AlignedBox3d& keepout,
                                                         double object_z_m) {
  impl_->set_keepout(keepout, object_z_m);
  return impl_->colliding(q, turntable_rad);
}

std::vector<std::string> ReachabilityChecker::turning_collisions(double radius_m, double bottom_z_m, double top_z_m,
                                                                double object_z_m) {
  Impl& im = *impl_;
  const double bottom = bottom_z_m + kTurningLiftM;
  if (im.rig.kind != RigKind::kArm || !im.rig.has_turntable || !(radius_m > 0) || !(top_z_m > bottom)) return {};
  mjModel* m = im.model.get();
  const int k = im.keepout;
  // The keep-out geom stands in for the cylinder, colliding with everything; off again after (every
  // check sets it anew).
  const double half = 0.5 * (top_z_m - bottom);
  im.keepout_cylinder(radius_m, half, object_z_m + bottom + half);
  m->geom_contype[k] = m->geom_conaffinity[k] = 0x7fffffff;
  im.place(im.rig.q_home, 0);
  mjData* d = im.data.get();
  mj_collision(m, d);
  std::vector<std::string> out;
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    if ((c.geom1 != k && c.geom2 != k) || c.dist >= kContactMargin) continue;
    const int g = c.geom1 == k ? c.geom2 : c.geom1;
    const bool fixed = m->body_weldid[m->geom_bodyid[g]] == 0 && (m->geom_contype[g] != 0 || m->geom_conaffinity[g] != 0);
    if (fixed && std::find(out.begin(), out.end(), im.side_name[g]) == out.end()) out.push_back(im.side_name[g]);
  }
  m->geom_contype[k] = m->geom_conaffinity[k] = 0;
  return out;
}

namespace {

// Joint-space distance weighted by the joint speed limits (~ motion time), with a small sum
// term to break ties.
double motion_cost(const RigModel& rig, const Vector6d& a, const Vector6d& b) {
  double mx = 0, sum = 0;
  for (int i = 0; i < 6; ++i) {
    const double t = std::abs(a[i] - b[i]) / rig.qd_max[i];
    mx = std::max(mx, t);
    sum += t;
  }
  return mx + 0.1 * sum;
}

std::string join_unique(const std::vector<std::string>& v, size_t max_items = 3) {
  std::string s;
  for (size_t i = 0; i < v.size() && i < max_items; ++i) s += (i ? ", " : "") + v[i];
  if (v.size() > max_items) s += ", ...";
  return s;
}

// The turntable angles to try a view at (TurntableChoice): the one bringing it to the preferred
// azimuth, then nearby azimuths (+-15 ... +-90 deg); kLeastTurn adds the current angle when the
// view lies within +-90 deg of the preferred azimuth there, and orders them by the turn. 0 alone
// without a turntable.
std::vector<double> candidate_turntable_angles(const RigModel& rig, const Pose& object_T_camera, double turntable_current,
                                               TurntableChoice choice, double* preferred) {
  *preferred = 0;
  if (rig.kind != RigKind::kArm || !rig.has_turntable) return {0.0};
  std::vector<double> offsets_deg{0};
  for (int k = kTurnGridDeg; k <= 90; k += kTurnGridDeg) {
    offsets_deg.push_back(k);
    offsets_deg.push_back(-k);
  }
  const Eigen::Vector3d c = object_T_camera.translation();
  const bool above = std::hypot(c.x(), c.y()) < 1e-6;
  const double psi = std::atan2(c.y(), c.x());
  std::vector<double> angles;
  for (double off : offsets_deg) {
    const double t = above ? turntable_current + off * kPi / 180.0
                           : rig.preferred_azimuth_rad + off * kPi / 180.0 - psi + rig.turntable_zero_rad;
    angles.push_back(nearest_equivalent_angle_rad(t, turntable_current));
  }
  *preferred = angles.front();
  if (choice != TurntableChoice::kPreferred) {
    // Where the view is with the turntable where it stands, as an offset from the preferred azimuth.
    const double off = above ? 0.0 : nearest_equivalent_angle_rad(turntable_current - angles.front(), 0.0);
    if (std::abs(off) <= 0.5 * kPi + 1e-9) angles.push_back(turntable_current);
    std::stable_sort(angles.begin(), angles.end(), [&](double a, double b) {
      return std::abs(a - turntable_current) < std::abs(b - turntable_current);
    });
  }
  return angles;
}

// kLeastTurn: the azimuth offsets are kTurnGridRad apart, so the first clear angle can stand up to
// that far past the least turn that brings the view within the arm's reach. Bisects between it and
// the next angle nearer to where the turntable stands (tried and unclear, or not on the list) or
// that angle itself, kLeastTurnRefineSteps times, keeping the nearest clear solution (`sol` on
// entry: the clear one; the bisection does not assume the clear angles are contiguous, it only
// ever takes a clear one). For one view (the motion executor's move): the view scorer's batch
// ranks by the grid's angles.
template <typename TryAngle>
void refine_least_turn(const TryAngle& try_angle, double turntable_current, ViewSolution& sol) {
  const double turn = sol.turntable_rad - turntable_current;
  if (std::abs(turn) < 1e-9) return;
  const double dir = turn > 0 ? 1.0 : -1.0;
  double clear = sol.turntable_rad;
  double unclear = std::abs(turn) > kTurnGridRad ? clear - dir * kTurnGridRad : turntable_current;
  for (int k = 0; k < kLeastTurnRefineSteps; ++k) {
    const double mid = 0.5 * (clear + unclear);
    ViewSolution trial;
    std::string reason;
    if (try_angle(mid, trial, reason)) {
      clear = mid;
      sol = trial;
    } else {
      unclear = mid;
    }
  }
}

}  // namespace

// The search for a clear solution at one turntable angle: candidate solutions in order of motion
// cost; the first collision-free one with the object in sight wins. Configurations equal up to
// whole joint turns share their geometry: one that failed is not checked again.
struct ReachabilityChecker::AngleSearch {
  Impl& im;
  const Vector6d& q_current;
  const Eigen::AlignedBox3d& keepout;
  double object_z_m;
  double t;  // the turntable angle
  // TurntableChoice::kQuickest: a solution whose move (from q_current, and the turn to t taking
  // turn_s) takes `bound` s or longer is passed over unchecked: a quicker one is known.
  double turn_s = 0;
  double bound = std::numeric_limits<double>::infinity();
  std::vector<std::string> hits, blocks;
  std::vector<Vector6d> failed;
  int checked = 0;
  // Set when what failed does not depend on the configuration (the view itself is blocked, or
  // the camera collides), so that no other solution at this turntable angle can be clear.
  bool hopeless = false;

  // True, with `out` set, when one of `sols` is clear.
  bool first_clear(std::vector<Vector6d> sols, ViewSolution& out) {
    const RigModel& rig = im.rig;
    std::sort(sols.begin(), sols.end(), [&](const Vector6d& x, const Vector6d& y) {
      return motion_cost(rig, x, q_current) < motion_cost(rig, y, q_current);
    });
    for (const Vector6d& q : sols) {
      if (bound < std::numeric_limits<double>::infinity() && std::max(arm_move_s(rig, q_current, q), turn_s) >= bound) {
        continue;
      }
      ++checked;
      if (std::any_of(failed.begin(), failed.end(), [&](const Vector6d& f) { return same_modulo_turns(f, q); })) {
        continue;
      }
      // Line of sight first (rays are cheaper than the collision check, and a view blocked by
      // the environment is blocked for every solution).
      im.place(q, t);
      const Pose w_c = camera_in_world(rig, q);
      const std::string occ = im.occluder(w_c, keepout, t, object_z_m, &hopeless);
      if (!occ.empty()) {
        if (std::find(blocks.begin(), blocks.end(), occ) == blocks.end()) blocks.push_back(occ);
        if (hopeless) return false;
        failed.push_back(q);
        continue;
      }
      const std::vector<std::string> col = im.colliding_placed(&hopeless);
      if (!col.empty()) {
        for (const std::string& c : col) {
          if (std::find(hits.begin(), hits.end(), c) == hits.end()) hits.push_back(c);
        }
        if (hopeless) return false;
        failed.push_back(q);
        continue;
      }
      out.reachable = true;
      out.q = q;
      out.turntable_rad = t;
      out.world_T_camera = w_c;
      return true;
    }
    return false;
  }

  // General IK, seeds in stages, each stage's solutions checked before the next is tried: in a
  // batch the previous candidate's solution (a neighbouring view: a few iterations, and the branch
  // continues the current configuration's), then the current configuration and home, then spread
  // seeds (in a batch only when a near seed converged). Each solution is taken in its whole-turn
  // variant nearest the current configuration. True when one is clear; else `reason` says why
  // none was found ("" when some were found and failed).
  bool general(const Pose& world_T_flange, ViewSolution& out, std::string& reason) {
    const RigModel& rig = im.rig;
    reason = general_out_of_reach(rig, rig.world_T_base.inverse() * world_T_flange);
    if (!reason.empty()) return false;
    std::vector<std::vector<Vector6d>> stages;
    if (im.have_neighbour) stages.push_back({im.neighbour});
    stages.push_back({q_current, rig.q_home});
    stages.push_back(spread_seeds(rig, kReachSpreadSeeds));
    int n_seeds = 0;
    for (const auto& st : stages) n_seeds += static_cast<int>(st.size());
    std::vector<Vector6d> found;
    for (const std::vector<Vector6d>& seeds : stages) {
      std::vector<Vector6d> fresh;
      for (const Vector6d& seed : seeds) {
        Vector6d q;
        if (!general_ik_seed(rig, world_T_flange, seed, kStallRatioFast, &q)) continue;
        if (std::any_of(found.begin(), found.end(), [&](const Vector6d& f) { return same_modulo_turns(f, q); })) continue;
        for (int i = 0; i < 6; ++i) q[i] = nearest_in_limits(rig, i, q[i], q_current[i]);
        found.push_back(q);
        fresh.push_back(q);
      }
      if (first_clear(fresh, out)) return true;
      if (hopeless) break;
      // In a batch, when not even the near seeds converge, spread seeds rarely find a
      // solution (measured: none of the 800 hemisphere views needed them) but cost most of
      // the time: skipped.
      if (im.have_neighbour && found.empty() && &seeds == &stages[stages.size() - 2]) break;
    }
    if (found.empty()) {
      reason = "no IK solution within the joint limits from " + std::to_string(n_seeds) +
               " seeds (out of reach or beyond the limits)";
    }
    return false;
  }

  // Why every solution checked failed.
  std::string collided() const {
    if (blocks.empty()) return "all " + std::to_string(checked) + " IK solutions collide (" + join_unique(hits) + ")";
    return "all " + std::to_string(checked) + " IK solutions collide or have the view blocked (" + join_unique(hits) +
           (hits.empty() ? "" : "; ") + "view blocked by " + join_unique(blocks) + ")";
  }
};

ViewSolution ReachabilityChecker::solve(const Pose& object_T_camera, const Vector6d& q_current,
                                        double turntable_current, const Eigen::AlignedBox3d& keepout,
                                        double object_z_m) {
  return solve_view(object_T_camera, q_current, turntable_current, keepout, object_z_m, true);
}

ViewSolution ReachabilityChecker::solve_view(const Pose& object_T_camera, const Vector6d& q_current,
                                             double turntable_current, const Eigen::AlignedBox3d& keepout,
                                             double object_z_m, bool narrow_turn) {
  Impl& im = *impl_;
  const RigModel& rig = im.rig;
  im.set_keepout(keepout, object_z_m);
  // One turntable angle: true, with `sol` set, when a clear solution stands there whose move
  // takes less than `bound` s (kQuickest); else `reason`.
  const auto try_angle = [&](double t, ViewSolution& sol, std::string& reason,
                             double bound = std::numeric_limits<double>::infinity()) {
    const Pose world_T_camera = object_in_world(rig, t, object_z_m) * object_T_camera;
    const Pose world_T_flange = world_T_camera * rig.flange_T_camera.inverse();
    AngleSearch search{im, q_current, keepout, object_z_m, t, turntable_move_s(rig, turntable_current, t), bound, {}, {}, {}};
    if (rig.kind == RigKind::kArm && rig.ik == IkMethod::kGeneral) {
      if (search.general(world_T_flange, sol, reason)) return true;
    } else if (rig.kind == RigKind::kArm && rig.ik == IkMethod::kParallelAxes) {
      // Each solution once, in its whole-turn variant nearest the current configuration (the
      // UR's +-2 pi joints would give up to 32 variants of each, with the same geometry).
      const std::vector<Vector6d> sols = parallel_axes_ik_nearest(rig, world_T_flange, q_current, &reason);
      if (!sols.empty() && search.first_clear(sols, sol)) return true;
    } else {
      std::string why;
      const std::vector<Vector6d> sols = ik_with_ref(rig, world_T_flange, q_current, &why);
      if (sols.empty()) reason = why;
      else if (search.first_clear(sols, sol)) return true;
    }
    if (reason.empty()) reason = search.collided();
    return false;
  };
  ViewSolution out;
  double preferred = 0;
  const std::vector<double> angles = candidate_turntable_angles(rig, object_T_camera, turntable_current, im.choice, &preferred);
  std::string first_reason;
  if (im.choice == TurntableChoice::kQuickest) {
    // The angles in order of turn: the first clear one is the least turn (narrowed for a single
    // view when that is no slower); a later one wins only with a quicker move, and none can once
    // the turn alone takes as long as the best move found.
    ViewSolution best;
    double best_s = std::numeric_limits<double>::infinity();
    const auto move_of = [&](const ViewSolution& v) {
      return move_s(rig, RigState{q_current, turntable_current}, RigState{v.q, v.turntable_rad});
    };
    for (const double t : angles) {
      if (best.reachable && turntable_move_s(rig, turntable_current, t) >= best_s) break;
      std::string reason;
      ViewSolution s;
      if (!try_angle(t, s, reason, best_s)) {
        if (t == preferred && !best.reachable) first_reason = reason;
        continue;
      }
      double s_s = move_of(s);
      if (!best.reachable && narrow_turn) {
        ViewSolution narrowed = s;
        refine_least_turn(try_angle, turntable_current, narrowed);
        if (const double n_s = move_of(narrowed); n_s <= s_s) {
          s = narrowed;
          s_s = n_s;
        }
      }
      best = s;
      best_s = s_s;
    }
    if (best.reachable) return best;
  } else {
    for (std::size_t a = 0; a < angles.size(); ++a) {
      const double t = angles[a];
      std::string reason;
      if (try_angle(t, out, reason)) {
        if (im.choice == TurntableChoice::kLeastTurn && narrow_turn) refine_least_turn(try_angle, turntable_current, out);
        return out;
      }
      if (t == preferred) first_reason = reason;
    }
  }
  out.reachable = false;
  out.reason = angles.size() == 1 ? first_reason
                                  : "at the preferred azimuth: " + first_reason +
                                        "; also unreachable at azimuth offsets up to +-90 deg";
  return out;
}

std::vector<ViewSolution> ReachabilityChecker::solve_batch(
    const std::vector<Pose>& object_T_cameras, const Vector6d& q_current,
    double turntable_current, const Eigen::AlignedBox3d& keepout, double object_z_m) {
  std::vector<ViewSolution> out;
  out.reserve(object_T_cameras.size());
  // Neighbouring candidates have nearby solutions: each seeds the next one's general IK.
  impl_->have_neighbour = false;
  for (const Pose& p : object_T_cameras) {
    out.push_back(solve_view(p, q_current, turntable_current, keepout, object_z_m, false));
    if (out.back().reachable) {
      impl_->neighbour = out.back().q;
      impl_->have_neighbour = true;
    }
  }
  impl_->have_neighbour = false;
  return out;
}

}  // namespace pbnbv
