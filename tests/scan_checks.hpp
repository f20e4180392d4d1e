#pragma once
// What the scan tests check against: the merged cloud's distance to the true surface, scan.json
// read while the scan runs, a scan process's end.
#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/geometry/mesh.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/mesh_file.hpp"

namespace pbnbv::testing {

namespace fs = std::filesystem;

// A copy of models/<model> in `dir` whose stated camera (<custom> pbnbv_camera) is `camera`
// ("width height fx fy cx cy depth_min depth_max"): the tests' twin renders small frames, and a
// rig file holds a driver to its own camera.
inline fs::path rig_with_camera(const fs::path& models, const std::string& model, const fs::path& dir,
                                const std::string& camera) {
  std::ifstream in(models / model);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string key = "<numeric name=\"pbnbv_camera\" data=\"";
  const std::size_t at = text.find(key);
  if (at == std::string::npos) throw std::runtime_error(model + " states no camera (pbnbv_camera)");
  const std::size_t end = text.find('"', at + key.size());
  text.replace(at + key.size(), end - at - key.size(), camera);
  const fs::path out = dir / (fs::path(model).stem().string() + "-camera.xml");
  std::ofstream(out) << text;
  return out;
}

// Distances of a cloud's points to a mesh's surface, m.
struct Distances {
  double median = 0, p95 = 0;
  std::size_t n = 0;
};

inline Distances cloud_to_mesh(const fs::path& cloud_path, const fs::path& mesh_path) {
  const PointCloud cloud = read_ply(cloud_path.string());
  const TriangleMesh mesh = load_mesh(mesh_path.string());
  std::vector<Eigen::Vector3d> pts;
  for (const auto& p : cloud) pts.push_back(p.cast<double>());
  std::vector<double> d = distances_to_surface(mesh, pts);
  Distances r;
  r.n = d.size();
  if (d.empty()) return r;
  std::sort(d.begin(), d.end());
  r.median = d[d.size() / 2];
  r.p95 = d[d.size() * 95 / 100];
  return r;
}

inline nlohmann::json read_json_file(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

// Polls scan.json until at least `views` views are recorded or the timeout passes.
inline bool wait_for_views(const fs::path& out, std::size_t views, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < end) {
    try {
      if (fs::exists(out / "scan.json") && read_json_file(out / "scan.json")["views"].size() >= views) return true;
    } catch (const std::exception&) {  // being replaced: read again
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

// Waits for the child `pid` to exit (its exit code, or 128 + signal); kills it and returns -1 after
// the timeout.
inline int wait_exit(pid_t pid, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < end) {
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::kill(pid, SIGKILL);
  return -1;
}

}  // namespace pbnbv::testing
