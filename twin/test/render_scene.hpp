#pragma once
// The twin tests' scenes: one EGL context per process, an MJCF model written out and loaded, and
// the camera at the world origin looking along +z (its optical frame is the world frame: x right,
// y down, z forward; the MuJoCo camera inside has quat="0 1 0 0").
#include <mujoco/mujoco.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "twin/depth_renderer.hpp"

namespace pbnbv::twin {

namespace fs = std::filesystem;

inline EglContext& egl() {
  static EglContext context;  // one per process, current on the test thread
  return context;
}

// A loaded MJCF model and its data after mj_forward.
struct Scene {
  mjModel* model = nullptr;
  mjData* data = nullptr;
  explicit Scene(const std::string& xml) {
    static std::atomic<int> counter{0};
    const fs::path path = fs::temp_directory_path() /
                          ("pbnbv_depth_test_" + std::to_string(::getpid()) + "_" +
                           std::to_string(counter++) + ".xml");
    {
      std::ofstream out(path);
      out << xml;
    }
    char error[1000] = "";
    model = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
    fs::remove(path);
    if (!model) throw std::runtime_error(std::string("mj_loadXML: ") + error);
    data = mj_makeData(model);
    mj_forward(model, data);
  }
  ~Scene() {
    if (data) mj_deleteData(data);
    if (model) mj_deleteModel(model);
  }
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;
};

inline std::string mjcf(const std::string& world, const std::string& extra = "") {
  return "<mujoco>\n" + extra +
         "  <worldbody>\n"
         "    <body name=\"camera_body\" pos=\"0 0 0\">\n"
         "      <camera name=\"depth\" quat=\"0 1 0 0\"/>\n"
         "    </body>\n" +
         world + "  </worldbody>\n</mujoco>\n";
}

inline std::string fmt(double x) {
  std::ostringstream s;
  s.precision(12);
  s << x;
  return s.str();
}

// A box whose face z = -h (local) is the plane through p0 with normal R * e_z, facing the camera.
inline std::string plane_box(const Eigen::Vector3d& p0, const Eigen::Quaterniond& q,
                      const std::string& attrs = "") {
  const double h = 0.01;
  const Eigen::Vector3d n = q * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d c = p0 + h * n;
  return "    <geom type=\"box\" size=\"10 10 " + fmt(h) + "\" pos=\"" + fmt(c.x()) + " " +
         fmt(c.y()) + " " + fmt(c.z()) + "\" quat=\"" + fmt(q.w()) + " " + fmt(q.x()) + " " +
         fmt(q.y()) + " " + fmt(q.z()) + "\" " + attrs + "/>\n";
}

}  // namespace pbnbv::twin
