// libFuzzer target: a mesh file as --object and the evaluation read it (load_mesh: CGAL's
// readers on a stream we hold, then our checks). The first byte picks the extension (.off,
// .obj, .stl, .ply), the rest is the file. A file load_mesh accepts must be a mesh the pipeline
// can use: triangles whose corners are vertices, finite coordinates, a box of positive size.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "core/io/mesh_file.hpp"
#include "fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* const kExtensions[] = {".off", ".obj", ".stl", ".ply"};
  const std::string path = pbnbv::fuzz::write_input(pbnbv::fuzz::as_text(data + 1, size - 1),
                                                    std::string("mesh") + kExtensions[data[0] % 4]);
  pbnbv::TriangleMesh mesh;
  try {
    mesh = pbnbv::load_mesh(path);
  } catch (const std::exception&) {  // refused, naming the file: what a user sees
    return 0;
  }
  if (mesh.triangles.empty()) {
    std::fprintf(stderr, "load_mesh accepted a file without triangles\n");
    std::abort();
  }
  for (const auto& v : mesh.vertices) {
    if (!v.allFinite()) {
      std::fprintf(stderr, "load_mesh accepted a non-finite vertex\n");
      std::abort();
    }
  }
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || static_cast<size_t>(t[k]) >= mesh.vertices.size()) {
        std::fprintf(stderr, "load_mesh accepted a corner index out of range\n");
        std::abort();
      }
    }
  }
  return 0;
}
