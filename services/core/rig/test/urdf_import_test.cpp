// An arm's URDF turned into MJCF by MuJoCo's URDF compiler (the first step of "Bring your own rig"):
// the six revolute joints come out as hinges with their limits, and the MJCF loads again with the
// same body offsets (the URDF's joint origins, each relative to its parent).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/rig/urdf_import.hpp"

using namespace pbnbv;
namespace fs = std::filesystem;

namespace {
std::string urdf() { return std::string(PBNBV_MODELS_DIR) + "/../services/core/rig/test/six_joint_arm.urdf"; }
}  // namespace

TEST(UrdfImport, SixRevoluteJointsBecomeHingesWithTheirLimits) {
  const fs::path out = fs::temp_directory_path() / ("arm-" + std::to_string(::getpid()) + ".xml");
  const ImportedArm arm = import_urdf(urdf(), out.string());
  EXPECT_EQ(arm.hinge_joints, (std::vector<std::string>{"j1", "j2", "j3", "j4", "j5", "j6"}));
  EXPECT_TRUE(arm.other_joints.empty());
  EXPECT_EQ(arm.bodies.back(), "flange");
  std::ifstream in(out);
  const std::string mjcf((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(mjcf.find("<body name=\"link_1\" pos=\"0 0 0.1\""), std::string::npos) << mjcf;
  EXPECT_NE(mjcf.find("<body name=\"link_3\" pos=\"0.4 0 0\""), std::string::npos) << mjcf;
  EXPECT_NE(mjcf.find("name=\"j3\""), std::string::npos);
  EXPECT_NE(mjcf.find("range=\"-2.5 2.5\""), std::string::npos) << mjcf;
  // It loads again as MJCF with the same joints.
  const ImportedArm again = import_urdf(out.string(), (out.string() + ".2.xml"));
  EXPECT_EQ(again.hinge_joints, arm.hinge_joints);
  fs::remove(out);
  fs::remove(out.string() + ".2.xml");
}

TEST(UrdfImport, AFileMuJoCoCannotReadIsNamed) {
  try {
    import_urdf("/no/such/arm.urdf", "/tmp/x.xml");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "URDF /no/such/arm.urdf: cannot open the file");
  }
  const fs::path bad = fs::temp_directory_path() / ("bad-" + std::to_string(::getpid()) + ".urdf");
  std::ofstream(bad) << "<robot name=\"x\"><joint name=\"j\" type=\"revolute\"><parent link=\"a\"/></joint></robot>";
  try {
    import_urdf(bad.string(), "/tmp/x.xml");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("URDF " + bad.string() + ": MuJoCo cannot load it"), std::string::npos) << e.what();
  }
  fs::remove(bad);
}
