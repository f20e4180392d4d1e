#pragma once
// An arm described in URDF, turned into MJCF by MuJoCo's own URDF compiler: the first step of
// "Bring your own rig" (README). The MJCF written holds the arm's bodies, joints (with their
// limits) and geoms, ready to be placed under the "base" body of a rig file.
#include <string>
#include <vector>

namespace pbnbv {

struct ImportedArm {
  std::vector<std::string> hinge_joints;  // in the order of the kinematic tree
  std::vector<std::string> other_joints;  // slide, ball, free: a rig's arm has none
  std::vector<std::string> bodies;
};

// Reads `urdf_path` with MuJoCo and writes it as MJCF to `mjcf_path`. Throws std::runtime_error
// naming the file and MuJoCo's reason when it does not load or cannot be written.
ImportedArm import_urdf(const std::string& urdf_path, const std::string& mjcf_path);

}  // namespace pbnbv
