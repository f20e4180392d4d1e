#include "core/surface/scan_mesh.hpp"

#include <chrono>
#include <stdexcept>

#include "core/base/enum_names.hpp"
#include "core/io/mesh_file.hpp"
#include "core/surface/mesh_topology.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv {

namespace {
// Fragments smaller than this are noise (a few stray points' surface), not the object.
constexpr std::size_t kMinComponentTriangles = 50;
}  // namespace

json mesh_scan(const fs::path& dir, const std::vector<SurfaceFrame>& frames, const SurfaceSettings& settings,
               bool with_stl) {
  const auto t0 = std::chrono::steady_clock::now();
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

}  // namespace pbnbv
