#include "core/surface/scan_mesh.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "core/base/enum_names.hpp"
#include "core/io/mesh_file.hpp"
#include "core/perception/neighbours.hpp"
#include "core/surface/mesh_topology.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv {

namespace {
// Fragments smaller than this are noise (a few stray points' surface), not the object.
constexpr std::size_t kMinComponentTriangles = 50;

// Each vertex's colour: that of the nearest coloured frame point within 3 point spacings (at
// least 3 mm), kNoColour beyond. Empty when no frame has colours.
std::vector<Rgb> vertex_colours(const TriangleMesh& mesh, const std::vector<SurfaceFrame>& frames, double spacing_m) {
  PointCloud points;
  std::vector<Rgb> colours;
  for (const SurfaceFrame& f : frames) {
    if (f.colours.size() != f.points.size()) continue;
    points.insert(points.end(), f.points.begin(), f.points.end());
    colours.insert(colours.end(), f.colours.begin(), f.colours.end());
  }
  if (points.empty()) return {};
  const NeighbourIndex index(points);
  const float reach = static_cast<float>(std::max(0.003, 3 * spacing_m));
  std::vector<Rgb> out(mesh.vertices.size(), kNoColour);
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    float d2 = 0;
    const int k = index.nearest(mesh.vertices[i].cast<float>(), reach * reach, d2);
    if (k >= 0) out[i] = colours[static_cast<std::size_t>(k)];
  }
  return out;
}

}  // namespace

MeshSummary mesh_scan(const fs::path& dir, const std::vector<SurfaceFrame>& frames, const SurfaceSettings& settings,
                      bool with_stl, LengthUnit unit) {
  const auto t0 = std::chrono::steady_clock::now();
  SurfaceStats stats;
  TriangleMesh mesh = build_surface(frames, settings, &stats);
  const std::size_t removed = remove_small_components(mesh, kMinComponentTriangles);
  const std::size_t filled = fill_small_holes(mesh, settings.fill_holes_m);
  if (mesh.triangles.empty()) throw std::runtime_error(dir.string() + ": the mesh has no triangles");
  const MeshTopology t = mesh_topology(mesh);
  const std::vector<Eigen::Vector3d> normals = vertex_normals(mesh);
  write_mesh_ply(mesh, normals, (dir / "mesh.ply").string(), vertex_colours(mesh, frames, settings.point_spacing_m));
  write_obj(mesh, (dir / "mesh.obj").string(), normals, unit);
  if (with_stl) write_stl_binary(mesh, (dir / "mesh.stl").string(), unit);
  MeshSummary m;
  m.tsdf = settings.method == MeshMethod::kTsdf;
  m.files = {"mesh.ply", "mesh.obj"};
  if (with_stl) m.files.push_back("mesh.stl");
  m.frames = stats.frames;
  m.points = stats.points;
  m.vertices = mesh.vertices.size();
  m.triangles = mesh.triangles.size();
  m.watertight = t.watertight;
  m.boundary_loops = t.boundary_loops;
  m.boundary_edges = t.boundary_edges;
  m.non_manifold_edges = t.non_manifold_edges;
  m.hole_boundary_length_m = t.boundary_length_m;
  m.area_m2 = t.area_m2;
  if (t.watertight) m.volume_m3 = t.volume_m3;
  m.small_fragments_removed_triangles = removed;
  m.holes_filled = filled;
  m.fill_holes_m = settings.fill_holes_m;
  if (m.tsdf) {
    m.voxel_m = settings.voxel_m;
    m.truncation_m = settings.voxel_m * settings.truncation_voxels;
    m.image_scale = stats.image_scale;
    m.voxels = stats.voxels;
  } else {
    m.poisson_depth = settings.poisson_depth;
  }
  m.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return m;
}

}  // namespace pbnbv
