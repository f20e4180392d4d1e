#pragma once
// Mesh files: loading (OBJ, STL ascii/binary, OFF, PLY ascii/binary) and writing (binary STL, OBJ).
#include <string>

#include "core/geometry/mesh.hpp"

namespace pbnbv {

// Loads a mesh by file extension (.obj .stl .off .ply, case-insensitive). Polygons with more
// than three corners are fanned into triangles. Throws std::runtime_error with the path and what
// is wrong (missing file, unknown extension, parse error with line number, index out of range,
// non-finite coordinate, no triangles, zero-size bounding box).
TriangleMesh load_mesh(const std::string& path);

void write_stl_binary(const TriangleMesh& mesh, const std::string& path);  // throws on I/O error
void write_obj(const TriangleMesh& mesh, const std::string& path);

}  // namespace pbnbv
