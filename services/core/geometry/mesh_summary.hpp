#pragma once
// What a scan's surface mesh is and how it was made, as plain data: the registration service
// makes the mesh (core/surface/scan_mesh.hpp), MESH_RESULT carries this to the coordinator, and
// scan.json's "mesh" says it (core/scan/scan_record.hpp: to_json).
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace pbnbv {

struct MeshSummary {
  bool tsdf = true;                        // the method: TSDF fusion, else screened Poisson
  std::vector<std::string> files;          // in the scan's folder: "mesh.ply" (vertex normals),
                                           // "mesh.obj", and "mesh.stl" when asked for
  std::size_t frames = 0, points = 0;      // what was fused
  std::size_t vertices = 0, triangles = 0;
  bool watertight = false;
  std::size_t boundary_loops = 0, boundary_edges = 0, non_manifold_edges = 0;
  double hole_boundary_length_m = 0;       // the rims of the holes left
  double area_m2 = 0;
  std::optional<double> volume_m3;         // when watertight
  std::size_t small_fragments_removed_triangles = 0;
  std::size_t holes_filled = 0;            // holes with a rim up to fill_holes_m closed
  double fill_holes_m = 0;
  double seconds = 0;                      // wall time of meshing and writing
  // TSDF: the voxel, the truncation distance, camera pixels per depth-image pixel, voxels
  // allocated; Poisson: the octree depth.
  double voxel_m = 0, truncation_m = 0;
  int image_scale = 1;
  std::size_t voxels = 0;
  int poisson_depth = 0;
};

}  // namespace pbnbv
