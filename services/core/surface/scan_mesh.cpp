#include "core/surface/scan_mesh.hpp"

#include <chrono>
#include <stdexcept>

#include "core/base/enum_names.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "core/io/mesh_file.hpp"
#include "core/surface/mesh_topology.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv {

namespace {
// Fragments smaller than this are noise (a few stray points' surface), not the object.
constexpr std::size_t kMinComponentTriangles = 50;
}  // namespace

std::vector<SurfaceFrame> read_scan_frames(const fs::path& dir, const json& scan, SurfaceSettings& settings) {
  const std::string where = (dir / "scan.json").string();
  try {
    const json& cam = scan.at("settings").at("camera");
    settings.camera.width = cam.at("width").get<int>();
    settings.camera.height = cam.at("height").get<int>();
    settings.camera.fx = cam.at("fx").get<double>();
    settings.camera.fy = cam.at("fy").get<double>();
    settings.camera.cx = cam.at("cx").get<double>();
    settings.camera.cy = cam.at("cy").get<double>();
    settings.point_spacing_m = scan.at("settings").value("voxel_m", 0.0);
  } catch (const json::exception& e) {
    throw std::invalid_argument(where + ": settings.camera or settings.voxel_m unreadable: " + e.what());
  }
  std::vector<SurfaceFrame> frames;
  for (const json& v : scan.value("views", json::array())) {
    if (!v.value("merged", false) || !v.contains("frame_file")) continue;
    const std::string what = where + " view " + std::to_string(v.value("view", -1));
    SurfaceFrame f;
    if (v.contains("registration") && v["registration"].contains("registered_object_T_camera")) {
      f.object_T_camera = pose_from_json(v["registration"]["registered_object_T_camera"], what + " registered pose");
    } else if (v.contains("capture")) {
      f.object_T_camera = pose_from_json(v["capture"].at("camera_object_T_camera"), what + " camera pose");
    } else {
      throw std::invalid_argument(what + ": a merged view without a camera pose");
    }
    f.points = read_ply((dir / v["frame_file"].get<std::string>()).string());
    frames.push_back(std::move(f));
  }
  if (frames.empty()) throw std::invalid_argument(where + ": no accepted view to mesh");
  return frames;
}

json mesh_scan(const fs::path& dir, const json& scan, SurfaceSettings settings, bool with_stl) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<SurfaceFrame> frames = read_scan_frames(dir, scan, settings);
  SurfaceStats stats;
  TriangleMesh mesh = build_surface(frames, settings, &stats);
  const std::size_t removed = remove_small_components(mesh, kMinComponentTriangles);
  const std::size_t filled = fill_small_holes(mesh, settings.fill_holes_m);
  if (mesh.triangles.empty()) throw std::runtime_error(dir.string() + ": the mesh has no triangles");
  const MeshTopology t = mesh_topology(mesh);
  write_mesh_ply(mesh, vertex_normals(mesh), (dir / "mesh.ply").string());
  write_obj(mesh, (dir / "mesh.obj").string());
  if (with_stl) write_stl_binary(mesh, (dir / "mesh.stl").string());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  json j = {{"file", "mesh.ply"},
            {"also", with_stl ? json{"mesh.obj", "mesh.stl"} : json{"mesh.obj"}},
            {"method", std::string(name_of(settings.method))},
            {"frames", stats.frames},
            {"points", stats.points},
            {"vertices", mesh.vertices.size()},
            {"triangles", mesh.triangles.size()},
            {"watertight", t.watertight},
            {"boundary_loops", t.boundary_loops},
            {"boundary_edges", t.boundary_edges},
            {"non_manifold_edges", t.non_manifold_edges},
            {"hole_boundary_length_m", t.boundary_length_m},
            {"area_m2", t.area_m2},
            {"volume_m3", t.watertight ? json(t.volume_m3) : json(nullptr)},
            {"small_fragments_removed_triangles", removed},
            {"holes_filled", filled},
            {"fill_holes_m", settings.fill_holes_m},
            {"seconds", seconds}};
  if (settings.method == MeshMethod::kTsdf) {
    j["settings"] = {{"voxel_m", settings.voxel_m},
                     {"truncation_m", settings.voxel_m * settings.truncation_voxels},
                     {"image_scale", stats.image_scale},
                     {"voxels", stats.voxels}};
  } else {
    j["settings"] = {{"poisson_depth", settings.poisson_depth}};
  }
  return j;
}

json mesh_scan_folder(const fs::path& dir, const SurfaceSettings& settings, bool with_stl) {
  const std::string path = (dir / "scan.json").string();
  json scan = read_json(path);
  const json m = mesh_scan(dir, scan, settings, with_stl);
  scan["mesh"] = m;
  write_json_atomic(scan, path);
  return m;
}

}  // namespace pbnbv
