#pragma once
// Mesh files: loading (OBJ, STL ascii/binary, OFF, PLY ascii/binary; CGAL's polygon-soup
// readers) and writing (binary STL, OBJ).
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/mesh.hpp"

namespace pbnbv {

// Loads a mesh by file extension (.obj .stl .off .ply, case-insensitive). Polygons with more
// than three corners are fanned into triangles; degenerate (zero-area) triangles are dropped.
// Throws std::runtime_error with the path and what is wrong: missing file, unknown extension,
// unreadable (for OBJ, OFF and text PLY, the line where the reader stopped, quoted; for STL and
// binary PLY, truncation), a PLY header CGAL cannot read, a face's vertex index out of range,
// a non-finite coordinate, no triangles, a zero-size bounding box.
TriangleMesh load_mesh(const std::string& path);

// The length unit of a written mesh: the pipeline's metres, or millimetres (what CAD and
// inspection tools assume of a unitless STL or OBJ).
enum class LengthUnit { kMetre, kMillimetre };
// "m" or "mm", and back (std::invalid_argument naming the text otherwise).
const char* unit_symbol(LengthUnit unit);
LengthUnit parse_length_unit(const std::string& text);

// Binary STL, coordinates in `unit`; its 80-byte header names the writer, its version and the
// unit. Throws std::runtime_error naming the path on an I/O error.
void write_stl_binary(const TriangleMesh& mesh, const std::string& path, LengthUnit unit = LengthUnit::kMetre);
// OBJ, coordinates in `unit`, with `normals` (one per vertex, as vn lines and v//vn faces) when
// given; its comments name the writer, its version and the unit. Throws std::invalid_argument
// when the normals are not one per vertex, std::runtime_error naming the path on an I/O error.
void write_obj(const TriangleMesh& mesh, const std::string& path, const std::vector<Eigen::Vector3d>& normals = {},
               LengthUnit unit = LengthUnit::kMetre);

}  // namespace pbnbv
