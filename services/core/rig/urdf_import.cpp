#include "core/rig/urdf_import.hpp"

#include <mujoco/mujoco.h>

#include <fstream>
#include <mutex>
#include <stdexcept>

namespace pbnbv {

ImportedArm import_urdf(const std::string& urdf_path, const std::string& mjcf_path) {
  if (!std::ifstream(urdf_path).good()) throw std::runtime_error("URDF " + urdf_path + ": cannot open the file");
  // MuJoCo's parser keeps the last model's XML in global state (mj_saveLastXML): one at a time.
  static std::mutex parser;
  std::lock_guard<std::mutex> lock(parser);
  char err[1000] = {0};
  mjModel* m = mj_loadXML(urdf_path.c_str(), nullptr, err, sizeof(err));
  if (!m) throw std::runtime_error("URDF " + urdf_path + ": MuJoCo cannot load it: " + err);
  ImportedArm arm;
  for (int j = 0; j < m->njnt; ++j) {
    const std::string name = mj_id2name(m, mjOBJ_JOINT, j) ? mj_id2name(m, mjOBJ_JOINT, j) : "(unnamed)";
    (m->jnt_type[j] == mjJNT_HINGE ? arm.hinge_joints : arm.other_joints).push_back(name);
  }
  for (int b = 1; b < m->nbody; ++b) arm.bodies.push_back(mj_id2name(m, mjOBJ_BODY, b) ? mj_id2name(m, mjOBJ_BODY, b) : "(unnamed)");
  const int saved = mj_saveLastXML(mjcf_path.c_str(), m, err, sizeof(err));
  mj_deleteModel(m);
  if (!saved) throw std::runtime_error("cannot write " + mjcf_path + ": " + err);
  return arm;
}

}  // namespace pbnbv
