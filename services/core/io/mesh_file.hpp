#pragma once
// Mesh files: loading (OBJ, STL ascii/binary, OFF, PLY ascii/binary; CGAL's polygon-soup
// readers) and writing (binary STL, OBJ).
#include <string>

#include "core/geometry/mesh.hpp"

namespace pbnbv {

// Loads a mesh by file extension (.obj .stl .off .ply, case-insensitive). Polygons with more
// than three corners are fanned into triangles; degenerate (zero-area) triangles are dropped.
// Throws std::runtime_error with the path and what is wrong: missing file, unknown extension,
// unreadable (for OBJ, OFF and text PLY, the line where the reader stopped, quoted; for STL and
// binary PLY, truncation), a PLY header CGAL cannot read, a face's vertex index out of range,
// a non-finite coordinate, no triangles, a zero-size bounding box.
TriangleMesh load_mesh(const std::string& path);

void write_stl_binary(const TriangleMesh& mesh, const std::string& path);  // throws on I/O error
void write_obj(const TriangleMesh& mesh, const std::string& path);

}  // namespace pbnbv
