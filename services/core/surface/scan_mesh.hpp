#pragma once
// The surface mesh of a scan folder: its accepted frames (frames/view_NNN.ply, registered, object
// frame) with their cameras from scan.json, fused into mesh.ply (vertex normals), mesh.obj and
// (asked for) mesh.stl in the folder. What was written goes into scan.json's "mesh" object.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/surface/surface.hpp"

namespace pbnbv {

// The accepted frames of the scan in `dir` and the settings its scan.json implies (camera,
// point spacing) on top of `base` (method, voxel, truncation). Throws naming the file when
// scan.json or a frame is missing or unreadable, or no view was accepted.
std::vector<SurfaceFrame> read_scan_frames(const std::filesystem::path& dir, const nlohmann::json& scan,
                                           SurfaceSettings& settings);

// Meshes the scan in `dir` (scan.json as `scan`), writes mesh.ply, mesh.obj (and, `with_stl`,
// mesh.stl: binary, 50 bytes a triangle, 13 MB for a 10-view bunny) there
// and returns the "mesh" object: file, method, vertices, triangles, watertight, boundary_loops,
// hole_boundary_length_m (the holes left after those with a rim up to settings.fill_holes_m were
// closed: holes_filled), area_m2, volume_m3 (when watertight), seconds, settings.
nlohmann::json mesh_scan(const std::filesystem::path& dir, const nlohmann::json& scan, SurfaceSettings settings,
                         bool with_stl = false);

// mesh_scan on the folder's scan.json, then its "mesh" object written into scan.json.
nlohmann::json mesh_scan_folder(const std::filesystem::path& dir, const SurfaceSettings& settings, bool with_stl = false);

}  // namespace pbnbv
