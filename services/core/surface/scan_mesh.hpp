#pragma once
// The surface mesh of a scan: its accepted frames (registered, object frame) with their cameras,
// fused into mesh.ply (vertex normals), mesh.obj and (asked for) mesh.stl in the scan's folder.
// The registration service meshes a scan's merged frames at its end; `pbnbv mesh` meshes a folder
// again (the frames named in scan.json: core/scan/scan_file.hpp, merged_frames).
#include <filesystem>
#include <vector>

#include "core/geometry/mesh_summary.hpp"
#include "core/io/mesh_file.hpp"
#include "core/surface/surface.hpp"

namespace pbnbv {

// Meshes `frames` (a scan's accepted frames, object frame) with `settings` (its camera and point
// spacing set), writes mesh.ply (metres, vertex normals), mesh.obj (vertex normals) and, `with_stl`,
// mesh.stl (binary, 50 bytes a triangle, 13 MB for a 10-view bunny) into `dir`, the OBJ and STL
// in `unit`, and returns what it made (scan.json's "mesh").
// Throws when the frames give no triangles or a file cannot be written.
MeshSummary mesh_scan(const std::filesystem::path& dir, const std::vector<SurfaceFrame>& frames,
                         const SurfaceSettings& settings, bool with_stl = false, LengthUnit unit = LengthUnit::kMetre);

}  // namespace pbnbv
