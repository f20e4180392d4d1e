#include "twin/rig_sim.hpp"

#include "core/io/mesh_file.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace pbnbv::twin {

namespace {
constexpr const char* kAssetMarker = "<!-- PBNBV_OBJECT_ASSET -->";
constexpr const char* kGeomMarker = "<!-- PBNBV_OBJECT_GEOM -->";
constexpr double kPositionTolerance = 1e-4;  // rad (m), settled
constexpr double kVelocityTolerance = 2e-3;  // rad/s (m/s), settled
// At rest: every degree of freedom slower than this (rad/s, m/s) with no ramp running. A step
// then moves nothing by more than kRestSpeed x timestep (2 nrad at 2 ms): the state is held.
constexpr double kRestSpeed = 1e-6;

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read rig model " + path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void replace_marker(std::string& xml, const std::string& marker, const std::string& with,
                    const std::string& path) {
  const auto pos = xml.find(marker);
  if (pos == std::string::npos) {
    throw std::runtime_error("rig model " + path + " has no '" + marker +
                             "' marker where the object goes");
  }
  xml.replace(pos, marker.size(), with);
}
}  // namespace

std::vector<ObjectColourPart> split_by_colour(const TriangleMesh& mesh, const std::vector<Rgb>& vertex_colours,
                                              const std::string& dir, const std::string& stem, int levels) {
  if (vertex_colours.size() != mesh.vertices.size()) {
    throw std::invalid_argument("split_by_colour: " + std::to_string(vertex_colours.size()) + " colours for " +
                                std::to_string(mesh.vertices.size()) + " vertices");
  }
  if (levels < 1 || levels > 256) throw std::invalid_argument("split_by_colour: levels must be in [1, 256]");
  struct Group {
    TriangleMesh mesh;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  };
  std::map<int, Group> groups;  // by quantised colour
  for (const Eigen::Vector3i& t : mesh.triangles) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const Rgb& v = vertex_colours[static_cast<std::size_t>(t[k])];
      c += Eigen::Vector3d(v[0], v[1], v[2]) / 3.0;
    }
    int key = 0;
    for (int k = 0; k < 3; ++k) key = key * levels + std::min(levels - 1, static_cast<int>(c[k] * levels / 256.0));
    Group& g = groups[key];
    g.sum += c;
    const int base = static_cast<int>(g.mesh.vertices.size());
    for (int k = 0; k < 3; ++k) g.mesh.vertices.push_back(mesh.vertices[static_cast<std::size_t>(t[k])]);
    g.mesh.triangles.emplace_back(base, base + 1, base + 2);
  }
  std::vector<Group*> order;
  for (auto& [key, g] : groups) order.push_back(&g);
  std::stable_sort(order.begin(), order.end(),
                   [](const Group* a, const Group* b) { return a->mesh.triangles.size() > b->mesh.triangles.size(); });
  std::vector<ObjectColourPart> parts;
  for (const Group* g : order) {
    ObjectColourPart part;
    part.mesh_path = stem + "_colour_" + std::to_string(parts.size()) + ".stl";
    part.triangles = g->mesh.triangles.size();
    const Eigen::Vector3d mean = g->sum / (255.0 * static_cast<double>(part.triangles));
    part.rgb = {mean.x(), mean.y(), mean.z()};
    write_stl_binary(g->mesh, (std::filesystem::path(dir) / part.mesh_path).string());
    parts.push_back(part);
  }
  return parts;
}

std::string compose_model_xml(const std::string& rig_xml_path, const ObjectPlacement& object) {
  std::string xml = read_text(rig_xml_path);
  std::string asset, geom;
  if (!object.mesh_path.empty()) {
    asset = "<mesh name=\"pbnbv_object\" file=\"" + object.mesh_path + "\"/>";
    std::ostringstream g;
    g.precision(17);
    // Rendered (group 0) and collides with the arm like the real object would; with colour parts
    // it only collides (group 3) and the parts, which do not collide, are drawn in its place.
    const bool parts = !object.colour_parts.empty();
    g << "<geom name=\"object\" type=\"mesh\" mesh=\"pbnbv_object\" pos=\"0 0 " << object.object_z_m
      << "\" group=\"" << (parts ? 3 : 0) << "\" rgba=\"0.8 0.75 0.6 1\" mass=\"0.5\"/>";
    for (std::size_t i = 0; i < object.colour_parts.size(); ++i) {
      const ObjectColourPart& part = object.colour_parts[i];
      asset += "<mesh name=\"pbnbv_object_colour_" + std::to_string(i) + "\" file=\"" + part.mesh_path + "\"/>";
      g << "<geom name=\"object_colour_" << i << "\" type=\"mesh\" mesh=\"pbnbv_object_colour_" << i
        << "\" pos=\"0 0 " << object.object_z_m << "\" group=\"0\" contype=\"0\" conaffinity=\"0\" mass=\"1e-6\" rgba=\""
        << part.rgb[0] << " " << part.rgb[1] << " " << part.rgb[2] << " 1\"/>";
    }
    geom = g.str();
  }
  if (object.calibration_sphere_radius_m > 0) {
    std::ostringstream g;
    g.precision(17);
    const double r = object.calibration_sphere_radius_m;
    // On the object mount (the platter top at the turntable's zero), turning with the platter.
    g << "<geom name=\"calibration_sphere\" type=\"sphere\" size=\"" << r << "\" pos=\""
      << object.calibration_sphere_offset_m << " 0 " << r << "\" group=\"0\" rgba=\"0.9 0.9 0.9 1\" mass=\"0.2\"/>";
    geom += g.str();
  }
  replace_marker(xml, kAssetMarker, asset, rig_xml_path);
  replace_marker(xml, kGeomMarker, geom, rig_xml_path);
  return xml;
}

bool PoseErrorModel::enabled() const {
  return !hand_eye_error.isApprox(Pose::Identity()) || turntable_offset_rad != 0 || joint_sigma_rad != 0 ||
         turntable_backlash_rad != 0;
}

PoseErrorModel make_pose_error(double hand_eye_m, double hand_eye_rad, double turntable_rad,
                               double joint_sigma_rad, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  auto random_unit = [&] {
    Eigen::Vector3d v(n(rng), n(rng), n(rng));
    return v.normalized();
  };
  PoseErrorModel e;
  e.hand_eye_error.translation() = hand_eye_m * random_unit();
  e.hand_eye_error.linear() = Eigen::AngleAxisd(hand_eye_rad, random_unit()).toRotationMatrix();
  e.turntable_offset_rad = turntable_rad;
  e.joint_sigma_rad = joint_sigma_rad;
  e.seed = seed;
  return e;
}

RigSim::RigSim(const RigModel& rig, const ObjectPlacement& object,
               const std::string& model_out_path, const PoseErrorModel& errors)
    : errors_(errors), rng_(errors.seed) {
  // The model names the object's mesh by a path relative to its own folder (MuJoCo resolves it
  // from there), so a scan folder copied or moved elsewhere still loads: a mesh in that folder
  // (the launcher's object.stl) is named as it is, one elsewhere is copied beside the model first.
  ObjectPlacement placed = object;
  if (!object.mesh_path.empty()) {
    namespace fs = std::filesystem;
    const fs::path dir = fs::absolute(model_out_path).parent_path();
    fs::path rel = fs::absolute(object.mesh_path).lexically_normal().lexically_relative(dir);
    if (rel.empty() || *rel.begin() == "..") {
      rel = fs::path(fs::path(model_out_path).stem().string() + "_object" + fs::path(object.mesh_path).extension().string());
      fs::copy_file(object.mesh_path, dir / rel, fs::copy_options::overwrite_existing);
    }
    placed.mesh_path = rel.string();
  }
  const std::string xml = compose_model_xml(rig.model_path, placed);
  {
    std::ofstream out(model_out_path);
    if (!out) throw std::runtime_error("cannot write the composed twin model " + model_out_path);
    out << xml;
  }
  // The rig file uses no asset files besides the object's mesh, named relative to the model.
  char error[1000] = "";
  m_ = mj_loadXML(model_out_path.c_str(), nullptr, error, sizeof(error));
  if (!m_) {
    throw std::runtime_error("MuJoCo could not load the twin model " + model_out_path + ": " + error);
  }
  d_ = mj_makeData(m_);
  if (!errors_.hand_eye_error.isApprox(Pose::Identity())) {
    // The real camera sits slightly elsewhere on its bracket than the model says.
    const int cam = mj_name2id(m_, mjOBJ_BODY, "camera_optical");
    if (cam < 0) throw std::runtime_error("twin model has no body 'camera_optical'");
    const Pose truth = rig.flange_T_camera * errors_.hand_eye_error;
    // body_pos/quat are relative to the parent body, the flange (load_rig checks this), whose
    // frame the model's flange_T_camera is expressed in.
    const Eigen::Quaterniond q(truth.linear());
    for (int k = 0; k < 3; ++k) m_->body_pos[3 * cam + k] = truth.translation()[k];
    m_->body_quat[4 * cam + 0] = q.w();
    m_->body_quat[4 * cam + 1] = q.x();
    m_->body_quat[4 * cam + 2] = q.y();
    m_->body_quat[4 * cam + 3] = q.z();
  }
  // The free rig is the paper's idealised comparison setup: a virtual gantry whose camera goes
  // straight to any pose, through the object if the line crosses it (nothing stalls a move and
  // no view is lost to the rig). Only the arm rig has contacts.
  if (rig.kind == RigKind::kFree) m_->opt.disableflags |= mjDSBL_CONTACT;
  teleport_ = rig.kind == RigKind::kFree;
  arm_ = make_group(rig.joint_names, {rig.qd_max.data(), rig.qd_max.data() + 6}, {rig.qdd_max.data(), rig.qdd_max.data() + 6});
  if (rig.has_turntable) turntable_ = make_group({"turntable"}, {rig.turntable_qd_max}, {rig.turntable_qdd_max});
  // Start at home, holding.
  for (int i = 0; i < 6; ++i) {
    d_->qpos[arm_.qpos_adr[i]] = rig.q_home[i];
    arm_.start[i] = arm_.target[i] = arm_.setpoint[i] = rig.q_home[i];
  }
  mj_forward(m_, d_);
  contacts_ = std::make_unique<ContactMonitor>(m_, rig.joint_names[0], d_->qpos);
  untaken_contacts_ = contacts_->initial_contacts();
  if (!untaken_contacts_.empty()) last_contact_ = untaken_contacts_.back();
}

std::vector<RigContact> RigSim::take_contacts() {
  std::vector<RigContact> out;
  out.swap(untaken_contacts_);
  return out;
}

void RigSim::protective_stop() {
  hold_arm(arm_.command_seq);
  if (turntable_) {
    const std::vector<double> here{d_->qpos[turntable_->qpos_adr[0]]};
    turntable_->setpoint = here;
    start_ramp(*turntable_, here, 1.0, turntable_->command_seq);
  }
}

RigSim::~RigSim() {
  if (d_) mj_deleteData(d_);
  if (m_) mj_deleteModel(m_);
}

JointGroup RigSim::make_group(const std::vector<std::string>& joints, const std::vector<double>& speeds,
                              const std::vector<double>& accelerations) {
  JointGroup g;
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const int j = mj_name2id(m_, mjOBJ_JOINT, joints[i].c_str());
    if (j < 0) throw std::runtime_error("twin model has no joint '" + joints[i] + "'");
    int act = -1;
    for (int a = 0; a < m_->nu; ++a) {
      if (m_->actuator_trntype[a] == mjTRN_JOINT && m_->actuator_trnid[2 * a] == j) act = a;
    }
    if (act < 0) throw std::runtime_error("twin model has no actuator driving joint '" + joints[i] + "'");
    g.names.push_back(joints[i]);
    g.qpos_adr.push_back(m_->jnt_qposadr[j]);
    g.dof_adr.push_back(m_->jnt_dofadr[j]);
    g.actuator.push_back(act);
    g.speed_limit.push_back(speeds.at(i));
    g.accel_limit.push_back(accelerations.at(i));
    const bool limited = m_->jnt_limited[j];
    g.lower.push_back(limited ? m_->jnt_range[2 * j] : -1e9);
    g.upper.push_back(limited ? m_->jnt_range[2 * j + 1] : 1e9);
    const double q = d_->qpos[m_->jnt_qposadr[j]];
    g.start.push_back(q);
    g.target.push_back(q);
    g.setpoint.push_back(q);
    g.setpoint_velocity.push_back(0.0);
    g.setpoint_acceleration.push_back(0.0);
  }
  return g;
}

void RigSim::start_ramp(JointGroup& g, const std::vector<double>& target, double speed_scale,
                        long seq) {
  if (ignore_limits_) speed_scale = std::clamp(speed_scale, 0.01, 1.0);
  if (!(speed_scale > 0 && speed_scale <= 1)) {
    throw std::invalid_argument("speed_scale " + std::to_string(speed_scale) + " is outside (0, 1]");
  }
  for (std::size_t i = 0; i < target.size(); ++i) {
    if (!std::isfinite(target[i])) {
      std::ostringstream os;
      os << "joint " << g.names[i] << " target " << target[i] << " is not finite";
      throw std::invalid_argument(os.str());
    }
    if (!ignore_limits_ && (target[i] < g.lower[i] - 1e-9 || target[i] > g.upper[i] + 1e-9)) {
      std::ostringstream os;
      os << "joint " << g.names[i] << " target " << target[i] << " is outside its limits ["
         << g.lower[i] << ", " << g.upper[i] << "]";
      throw OutOfLimits(os.str());
    }
  }
  // Synchronised smoothstep ramp: the slowest joint sets the duration (none when teleporting);
  // the services' rig-time model (core/rig: arm_move_s) is this.
  double duration = 0;
  for (std::size_t i = 0; i < target.size() && !teleport_; ++i) {
    duration = std::max(duration, ramp_duration_s(std::abs(target[i] - g.setpoint[i]), g.speed_limit[i] * speed_scale,
                                                  g.accel_limit[i] * speed_scale));
  }
  g.start = g.setpoint;
  g.target = target;
  g.t0 = d_->time;
  g.t1 = d_->time + duration;
  g.command_seq = seq;
  g.ramping = true;
}

void RigSim::command_arm(const Vector6d& target, double speed_scale, long seq) {
  // Commands are in reported (encoder) angles; a new command brings new encoder offsets.
  Vector6d offset = Vector6d::Zero();
  if (errors_.joint_sigma_rad > 0) {
    std::normal_distribution<double> n(0.0, errors_.joint_sigma_rad);
    for (int i = 0; i < 6; ++i) offset[i] = n(rng_);
  }
  const Vector6d truth = target - offset;
  start_ramp(arm_, std::vector<double>(truth.data(), truth.data() + 6), speed_scale, seq);
  joint_offset_ = offset;
}

void RigSim::command_turntable(double target_rad, double speed_scale, long seq) {
  if (!turntable_) throw std::invalid_argument("this rig has no turntable");
  // The turntable turns without end stops, but one command turns it at most one full turn from
  // where it is now (its setpoint): 1e6 rad would be eleven days of turning.
  if (std::isfinite(target_rad) && std::abs(target_rad - errors_.turntable_offset_rad - turntable_->setpoint[0]) > kMaxTurntableTurnRad) {
    std::ostringstream os;
    os << "turntable target " << target_rad << " rad is " << std::abs(target_rad - turntable_->setpoint[0])
       << " rad from its setpoint " << turntable_->setpoint[0] << " rad: one command turns it at most one full turn (2 pi)";
    throw OutOfLimits(os.str());
  }
  // Backlash: the motor reaches the target, the platter stops half the backlash short of it, on
  // the side it came from.
  const double motor = target_rad - errors_.turntable_offset_rad;
  const double motor_now = turntable_->setpoint[0] + turntable_lag_rad_;
  if (motor != motor_now) turntable_lag_rad_ = (motor > motor_now ? 0.5 : -0.5) * errors_.turntable_backlash_rad;
  start_ramp(*turntable_, {motor - turntable_lag_rad_}, speed_scale, seq);
}

Pose RigSim::true_camera_in_object(double object_z_m) const {
  auto body_pose = [&](const char* name) {
    const int b = mj_name2id(m_, mjOBJ_BODY, name);
    if (b < 0) throw std::runtime_error(std::string("twin model has no body '") + name + "'");
    Pose p = Pose::Identity();
    Eigen::Matrix3d r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r(i, j) = d_->xmat[9 * b + 3 * i + j];
    p.linear() = r;
    p.translation() = Eigen::Vector3d(d_->xpos[3 * b], d_->xpos[3 * b + 1], d_->xpos[3 * b + 2]);
    return p;
  };
  Pose world_T_object = body_pose("object_mount");
  world_T_object.translate(Eigen::Vector3d(0, 0, object_z_m));
  return world_T_object.inverse() * body_pose("camera_optical");
}

void RigSim::hold_arm(long seq) {
  std::vector<double> here;
  for (int a : arm_.qpos_adr) here.push_back(d_->qpos[a]);
  arm_.setpoint = here;
  start_ramp(arm_, here, 1.0, seq);
}

void RigSim::advance_ramp(JointGroup& g) {
  std::fill(g.setpoint_velocity.begin(), g.setpoint_velocity.end(), 0.0);
  std::fill(g.setpoint_acceleration.begin(), g.setpoint_acceleration.end(), 0.0);
  if (g.ramping) {
    const double span = g.t1 - g.t0;
    const double tau = span <= 0 ? 1.0 : std::clamp((d_->time - g.t0) / span, 0.0, 1.0);
    // s = 3 tau^2 - 2 tau^3, ds/dt = 6 tau (1 - tau) / span, d2s/dt2 = (6 - 12 tau) / span^2
    const double s = tau * tau * (3.0 - 2.0 * tau);
    const double ds = span <= 0 ? 0.0 : 6.0 * tau * (1.0 - tau) / span;
    const double dds = span <= 0 || tau >= 1.0 ? 0.0 : (6.0 - 12.0 * tau) / (span * span);
    for (std::size_t i = 0; i < g.target.size(); ++i) {
      const double delta = g.target[i] - g.start[i];
      g.setpoint[i] = g.start[i] + s * delta;
      g.setpoint_velocity[i] = ds * delta;
      g.setpoint_acceleration[i] = dds * delta;
    }
    if (tau >= 1.0) g.ramping = false;
  }
  for (std::size_t i = 0; i < g.target.size(); ++i) d_->ctrl[g.actuator[i]] = g.setpoint[i];
}

bool RigSim::at_rest() const {
  if (arm_.ramping || (turntable_ && turntable_->ramping)) return false;
  for (int i = 0; i < m_->nv; ++i) {
    if (!(std::abs(d_->qvel[i]) < kRestSpeed)) return false;
  }
  return true;
}

void RigSim::step() {
  // A rig at rest stays where it is: the clock advances without a physics step (as physics
  // engines let resting bodies sleep), and the first command wakes it. Nothing moved, so no
  // contact can begin either.
  if (at_rest()) {
    d_->time += m_->opt.timestep;
    ++rest_steps_;
    return;
  }
  advance_ramp(arm_);
  if (turntable_) advance_ramp(*turntable_);
  // The rig's own controller: gravity and Coriolis compensation, plus feed-forward of the
  // ramp's acceleration (through the mass matrix) and velocity (through the joint damping).
  std::vector<mjtNum> qdd(m_->nv, 0.0), inertial(m_->nv, 0.0);
  mju_copy(d_->qfrc_applied, d_->qfrc_bias, m_->nv);
  auto feed_forward = [&](const JointGroup& g) {
    for (std::size_t i = 0; i < g.dof_adr.size(); ++i) {
      qdd[g.dof_adr[i]] = g.setpoint_acceleration[i];
      d_->qfrc_applied[g.dof_adr[i]] += m_->dof_damping[g.dof_adr[i]] * g.setpoint_velocity[i];
    }
  };
  feed_forward(arm_);
  if (turntable_) feed_forward(*turntable_);
  mj_mulM(m_, d_, inertial.data(), qdd.data());
  for (int i = 0; i < m_->nv; ++i) d_->qfrc_applied[i] += inertial[i];
  const double t = d_->time;
  mj_step(m_, d_);
  if (teleport_) {
    for (std::size_t i = 0; i < arm_.qpos_adr.size(); ++i) {
      d_->qpos[arm_.qpos_adr[i]] = arm_.setpoint[i];
      d_->qvel[arm_.dof_adr[i]] = 0.0;
    }
  }
  // MuJoCo resets the state (and the clock) when the physics diverges: never carry on silently.
  if (d_->warning[mjWARN_BADQACC].number > 0) {
    throw std::runtime_error("the physics diverged at rig time " + std::to_string(t) +
                             " s (MuJoCo reset the simulation); the rig model's gains or the command are unsafe");
  }
  const std::vector<RigContact> found = contacts_->check(d_->qpos, !teleport_, d_->time, arm_.command_seq);
  if (!found.empty()) {
    protective_stop();
    last_contact_ = found.back();
    untaken_contacts_.insert(untaken_contacts_.end(), found.begin(), found.end());
  }
}

double RigSim::time_s() const { return d_->time; }

Vector6d RigSim::arm_position() const {
  Vector6d q;
  for (int i = 0; i < 6; ++i) q[i] = d_->qpos[arm_.qpos_adr[i]];
  return q;
}

Vector6d RigSim::arm_velocity() const {
  Vector6d v;
  for (int i = 0; i < 6; ++i) v[i] = d_->qvel[arm_.dof_adr[i]];
  return v;
}

double RigSim::turntable_angle() const { return turntable_ ? d_->qpos[turntable_->qpos_adr[0]] : 0.0; }
double RigSim::turntable_velocity() const { return turntable_ ? d_->qvel[turntable_->dof_adr[0]] : 0.0; }

bool RigSim::settled(const JointGroup& g) const {
  if (g.ramping) return false;
  for (std::size_t i = 0; i < g.target.size(); ++i) {
    if (std::abs(d_->qpos[g.qpos_adr[i]] - g.target[i]) > kPositionTolerance) return false;
    if (std::abs(d_->qvel[g.dof_adr[i]]) > kVelocityTolerance) return false;
  }
  return true;
}

}  // namespace pbnbv::twin
