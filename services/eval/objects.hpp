#pragma once
// The objects a scan or a benchmark can name: a mesh file, a mesh fetched by ./scripts/setup
// (the benchmark's default set), or a generated primitive.
#include <string>
#include <vector>

#include "core/geometry/mesh.hpp"

namespace pbnbv::eval {

struct ObjectSpec {
  std::string name;    // file stem or built-in name; names the benchmark's folders
  std::string source;  // the mesh file, or what generated the mesh
  UpAxis up = UpAxis::kZ;  // which axis of the file points up in its natural resting pose
  TriangleMesh mesh;   // as loaded (not yet normalised)
};

// The benchmark's default object set: real meshes from the package registries, fetched into
// build/data/meshes by ./scripts/setup (scripts/fetch-meshes), each with its natural up axis.
struct DefaultObject {
  const char* name;
  const char* file;    // in PBNBV_DATA_DIR/meshes
  UpAxis up;
  const char* origin;  // where it comes from
};
const std::vector<DefaultObject>& default_objects();

// A name (bunny, teapot, any default object, sphere, box) or a mesh path. Throws
// std::runtime_error naming the object when a fetched mesh is missing (run ./scripts/setup) or
// the file cannot be loaded.
ObjectSpec resolve_object(const std::string& name_or_path);


}  // namespace pbnbv::eval
