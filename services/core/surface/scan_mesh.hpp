#pragma once
// The surface mesh of a scan: its accepted frames (registered, object frame) with their cameras,
// fused into mesh.ply (vertex normals), mesh.obj and (asked for) mesh.stl in the scan's folder.
// Reading the frames from a scan folder is core/scan's (scan_file.hpp: read_scan_frames).
#include <filesystem>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/surface/surface.hpp"

namespace pbnbv {

// Meshes `frames` (a scan's accepted frames, object frame) with `settings` (its camera and point
// spacing set), writes mesh.ply, mesh.obj (and, `with_stl`, mesh.stl: binary, 50 bytes a
// triangle, 13 MB for a 10-view bunny) into `dir` and returns scan.json's "mesh" object: file,
// method, vertices, triangles, watertight, boundary_loops, hole_boundary_length_m (the holes left
// after those with a rim up to settings.fill_holes_m were closed: holes_filled), area_m2,
// volume_m3 (when watertight), seconds, settings.
nlohmann::json mesh_scan(const std::filesystem::path& dir, const std::vector<SurfaceFrame>& frames,
                         const SurfaceSettings& settings, bool with_stl = false);

}  // namespace pbnbv
