// The rig's MuJoCo model: loading (serialised) and static body poses. See rig_internal.hpp.
#include <fstream>
#include <mutex>
#include <stdexcept>

#include "core/rig/rig_internal.hpp"

namespace pbnbv::rig_internal {

Pose pose_from_mj(const mjtNum pos[3], const mjtNum quat[4]) {
  Pose p = Pose::Identity();
  Eigen::Quaterniond q(quat[0], quat[1], quat[2], quat[3]);
  p.linear() = q.normalized().toRotationMatrix();
  p.translation() = Eigen::Vector3d(pos[0], pos[1], pos[2]);
  return p;
}

Pose body_local_pose(const mjModel* m, int b) {
  return pose_from_mj(m->body_pos + 3 * b, m->body_quat + 4 * b);
}

Pose body_world_pose_static(const mjModel* m, int b) {
  Pose p = Pose::Identity();
  while (b > 0) {
    p = body_local_pose(m, b) * p;
    b = m->body_parentid[b];
  }
  return p;
}

ModelPtr load_mj_model(const std::string& path) {
  {
    std::ifstream f(path);
    if (!f.good()) throw std::runtime_error("rig model " + path + ": cannot open the file");
  }
  char err[1000] = {0};
  // The MJCF parser keeps global state; serialise loads (checkers are built per thread).
  static std::mutex load_mutex;
  mjModel* m = nullptr;
  {
    std::lock_guard<std::mutex> lock(load_mutex);
    m = mj_loadXML(path.c_str(), nullptr, err, sizeof(err));
  }
  if (!m) throw std::runtime_error("rig model " + path + ": MuJoCo cannot load it: " + err);
  return ModelPtr(m);
}

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw std::runtime_error("rig model " + path + ": " + what);
}

}  // namespace pbnbv::rig_internal
