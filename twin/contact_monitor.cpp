#include "twin/contact_monitor.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

namespace pbnbv::twin {

namespace {

// Collision filter of the monitor's model copy: (contype1 & conaffinity2) || (contype2 &
// conaffinity1) holds for a moving geom against an other geom (bit 2), and for the object turning
// on the turntable against a fixed part (bit 4), only.
constexpr int kMovingContype = 2, kMovingConaffinity = 0;
constexpr int kOtherContype = 0, kOtherConaffinity = 2;
constexpr int kTurningContype = 4, kTurningConaffinity = kOtherConaffinity;
constexpr int kFixedContype = 0, kFixedConaffinity = kOtherConaffinity | kTurningContype;

std::string body_name(const mjModel* m, int body) {
  const char* n = mj_id2name(m, mjOBJ_BODY, body);
  return n ? std::string(n) : "body " + std::to_string(body);
}

std::string geom_name(const mjModel* m, int geom) {
  const char* n = mj_id2name(m, mjOBJ_GEOM, geom);
  if (n) return n;
  const char* b = mj_id2name(m, mjOBJ_BODY, m->geom_bodyid[geom]);
  return b ? std::string(b) : "geom " + std::to_string(geom);
}

// A pair's moving side: a body of the arm (>= 0), or the turning object's geom (-1 - geom).
std::string side_name(const mjModel* m, int side) { return side >= 0 ? body_name(m, side) : geom_name(m, -1 - side); }

bool in_subtree(const mjModel* m, int body, int root) {
  for (int b = body; b > 0; b = m->body_parentid[b]) {
    if (b == root) return true;
  }
  return root == 0;
}

}  // namespace

std::string RigContact::text() const {
  return fmt::format("{} / {}, {:.2g} mm deep, at rig time {:.3f} s, {}", moving, other, depth_m * 1e3, rig_time_s,
                     command_seq < 0 ? std::string("before any command") : fmt::format("during command {}", command_seq));
}

ContactMonitor::ContactMonitor(const mjModel* model, const std::string& first_joint, const double* qpos) {
  const int joint = mj_name2id(model, mjOBJ_JOINT, first_joint.c_str());
  if (joint < 0) throw std::runtime_error("contact check: the rig model has no joint '" + first_joint + "'");
  m_ = mj_copyModel(nullptr, model);
  if (!m_) throw std::runtime_error("contact check: MuJoCo could not copy the rig model");
  d_ = mj_makeData(m_);
  if (!d_) {
    mj_deleteModel(m_);
    throw std::runtime_error("contact check: mj_makeData failed");
  }
  // Contacts on even where the physics has them off (the free rig), every parent-child pair
  // checked, and nothing else in the way of finding them.
  m_->opt.disableflags &= ~mjDSBL_CONTACT;
  m_->opt.disableflags |= mjDSBL_FILTERPARENT;
  m_->opt.collision = mjCOL_ALL;
  const int root = m_->jnt_bodyid[joint];
  is_moving_.assign(static_cast<std::size_t>(m_->ngeom), 0);
  is_other_.assign(static_cast<std::size_t>(m_->ngeom), 0);
  is_turning_.assign(static_cast<std::size_t>(m_->ngeom), 0);
  is_fixed_.assign(static_cast<std::size_t>(m_->ngeom), 0);
  for (int g = 0; g < m_->ngeom; ++g) {
    const bool moving = in_subtree(m_, m_->geom_bodyid[g], root);
    const char* name = mj_id2name(m_, mjOBJ_GEOM, g);
    const bool inserted = name && (std::string(name) == "object" || std::string(name) == "calibration_sphere");
    const bool solid = m_->geom_contype[g] != 0 || m_->geom_conaffinity[g] != 0;
    if (moving && solid) {
      is_moving_[static_cast<std::size_t>(g)] = 1;
      moving_.push_back(g);
      m_->geom_contype[g] = kMovingContype;
      m_->geom_conaffinity[g] = kMovingConaffinity;
    } else if (!moving && (solid || inserted)) {
      is_other_[static_cast<std::size_t>(g)] = 1;
      other_.push_back(g);
      m_->geom_contype[g] = kOtherContype;
      m_->geom_conaffinity[g] = kOtherConaffinity;
      if (inserted && m_->body_weldid[m_->geom_bodyid[g]] != 0) {  // carried by a joint: the turntable
        is_turning_[static_cast<std::size_t>(g)] = 1;
        m_->geom_contype[g] = kTurningContype;
        m_->geom_conaffinity[g] = kTurningConaffinity;
      } else if (!inserted && m_->body_weldid[m_->geom_bodyid[g]] == 0) {  // welded to the world
        is_fixed_[static_cast<std::size_t>(g)] = 1;
        m_->geom_contype[g] = kFixedContype;
        m_->geom_conaffinity[g] = kFixedConaffinity;
      }
    } else {
      m_->geom_contype[g] = 0;
      m_->geom_conaffinity[g] = 0;
    }
    m_->geom_margin[g] = kSeparatedM;
    m_->geom_gap[g] = 0;
  }
  // Explicit <contact><pair> elements of the rig file would collide whatever the flags: none here.
  m_->npair = 0;
  carried_.resize(static_cast<std::size_t>(m_->njnt));
  for (int j = 0; j < m_->njnt; ++j) {
    for (int g = 0; g < m_->ngeom; ++g) {
      if ((is_moving_[static_cast<std::size_t>(g)] || is_other_[static_cast<std::size_t>(g)]) &&
          in_subtree(m_, m_->geom_bodyid[g], m_->jnt_bodyid[j])) {
        carried_[static_cast<std::size_t>(j)].push_back(g);
      }
    }
  }
  last_qpos_.assign(qpos, qpos + m_->nq);
  initial_ = check_state(qpos, 0.0, -1);
}

ContactMonitor::~ContactMonitor() {
  if (d_) mj_deleteData(d_);
  if (m_) mj_deleteModel(m_);
}

double ContactMonitor::motion_bound_m(const double* qpos) const {
  double bound = 0;
  for (int j = 0; j < m_->njnt; ++j) {
    const auto& carried = carried_[static_cast<std::size_t>(j)];
    if (carried.empty()) continue;
    // The reach of what the joint carries, from its anchor (at the state last checked).
    double reach = 0;
    for (int g : carried) {
      double r2 = 0;
      for (int k = 0; k < 3; ++k) {
        const double dx = d_->geom_xpos[3 * g + k] - d_->xanchor[3 * j + k];
        r2 += dx * dx;
      }
      reach = std::max(reach, std::sqrt(r2) + m_->geom_rbound[g]);
    }
    const int a = m_->jnt_qposadr[j];
    auto delta = [&](int i) { return qpos[a + i] - last_qpos_[static_cast<std::size_t>(a + i)]; };
    switch (m_->jnt_type[j]) {
      case mjJNT_HINGE: bound += std::abs(delta(0)) * reach; break;
      case mjJNT_SLIDE: bound += std::abs(delta(0)); break;
      case mjJNT_BALL:
      case mjJNT_FREE: {
        const int q0 = m_->jnt_type[j] == mjJNT_FREE ? 3 : 0;  // a free joint: position, then quaternion
        double t2 = 0, r2 = 0;
        for (int i = 0; i < q0; ++i) t2 += delta(i) * delta(i);
        for (int i = 0; i < 4; ++i) r2 += delta(q0 + i) * delta(q0 + i);
        // A unit quaternion's change of length s turns the body by at most about 2 s rad.
        bound += std::sqrt(t2) + 2 * std::sqrt(r2) * reach;
        break;
      }
      default: break;
    }
  }
  return bound;
}

std::vector<RigContact> ContactMonitor::check(const double* qpos, bool sweep, double rig_time_s, int64_t command_seq) {
  const double bound = motion_bound_m(qpos);
  if (bound < 1e-6) return {};  // nothing moved: the contacts are those of the state last checked
  const auto t0 = std::chrono::steady_clock::now();
  const int n = sweep ? std::max(1, static_cast<int>(std::ceil(bound / kMaxSweepStepM))) : 1;
  std::vector<double> from = last_qpos_, q(static_cast<std::size_t>(m_->nq));
  std::vector<RigContact> found;
  for (int k = 1; k <= n; ++k) {
    const double s = static_cast<double>(k) / n;
    for (int i = 0; i < m_->nq; ++i) q[static_cast<std::size_t>(i)] = from[static_cast<std::size_t>(i)] + s * (qpos[i] - from[static_cast<std::size_t>(i)]);
    std::vector<RigContact> began = check_state(k == n ? qpos : q.data(), rig_time_s, command_seq);
    found.insert(found.end(), began.begin(), began.end());
  }
  last_qpos_.assign(qpos, qpos + m_->nq);
  ++cost_.calls;
  cost_.states += n;
  cost_.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return found;
}

std::vector<RigContact> ContactMonitor::check_state(const double* qpos, double rig_time_s, int64_t command_seq) {
  mju_copy(d_->qpos, qpos, m_->nq);
  mj_kinematics(m_, d_);
  mj_collision(m_, d_);
  // The deepest penetration of each pair within the margin, in the order first found.
  std::vector<std::pair<std::pair<int, int>, double>> pairs;
  for (int i = 0; i < d_->ncon; ++i) {
    const mjContact& c = d_->contact[i];
    const auto at = [](const std::vector<char>& v, int g) { return v[static_cast<std::size_t>(g)] != 0; };
    // The arm against the rest, or the object turning against a fixed part.
    const bool first_moving = at(is_moving_, c.geom1) || (!at(is_moving_, c.geom2) && at(is_turning_, c.geom1));
    const int gm = first_moving ? c.geom1 : c.geom2, go = first_moving ? c.geom2 : c.geom1;
    const bool arm = at(is_moving_, gm) && at(is_other_, go);
    const bool turning = at(is_turning_, gm) && at(is_fixed_, go);
    if (!arm && !turning) continue;
    // The arm's side by its body, the object's by its geom (-1 - geom).
    const std::pair<int, int> key{arm ? m_->geom_bodyid[gm] : -1 - gm, go};
    auto it = std::find_if(pairs.begin(), pairs.end(), [&](const auto& p) { return p.first == key; });
    if (it == pairs.end()) {
      pairs.push_back({key, c.dist});
    } else {
      it->second = std::min(it->second, static_cast<double>(c.dist));
    }
  }
  // Separated: no longer within the margin.
  for (auto it = touching_.begin(); it != touching_.end();) {
    const bool near = std::any_of(pairs.begin(), pairs.end(), [&](const auto& p) { return p.first == *it; });
    it = near ? std::next(it) : touching_.erase(it);
  }
  std::vector<RigContact> began;
  for (const auto& [key, dist] : pairs) {
    if (dist >= 0 || touching_.count(key)) continue;
    touching_.insert(key);
    ++events_;
    began.push_back({side_name(m_, key.first), geom_name(m_, key.second), -dist, rig_time_s, command_seq});
  }
  return began;
}

std::vector<std::string> ContactMonitor::touching() const {
  std::vector<std::string> out;
  for (const auto& [side, geom] : touching_) out.push_back(side_name(m_, side) + " / " + geom_name(m_, geom));
  return out;
}

}  // namespace pbnbv::twin
