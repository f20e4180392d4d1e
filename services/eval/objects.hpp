#pragma once
// The objects a scan or a benchmark can name: a mesh file, a mesh fetched by ./scripts/setup
// (the benchmark's tuning set of 30, whose first 12 are its default set), or a generated
// primitive; and the named object sets a benchmark takes (default, tuning and its two halves,
// tune and confirm).
#include <optional>
#include <string>
#include <vector>

#include "core/base/enum_names.hpp"
#include "core/geometry/mesh.hpp"

namespace pbnbv::eval {

struct ObjectSpec {
  std::string name;    // file stem or built-in name; names the benchmark's folders
  std::string source;  // the mesh file, or what generated the mesh
  UpAxis up = UpAxis::kZ;  // which axis of the file points up in its natural resting pose
  TriangleMesh mesh;   // as loaded (not yet normalised)
};

// A real mesh from the package registries, fetched into build/data/meshes by ./scripts/setup
// (scripts/fetch-meshes, which checks each file's SHA-256), with its natural up axis.
struct KnownObject {
  const char* name;
  const char* file;    // in PBNBV_DATA_DIR/meshes
  UpAxis up;
  const char* origin;  // where it comes from
};
// The tuning set: the default set's 12 first (in the README's order), then 18 more meshes of the
// same Debian package (libcgal-demo's data/meshes).
const std::vector<KnownObject>& tuning_objects();
// The benchmark's default set: the first 12 of the tuning set (the README's tables use it).
const std::vector<KnownObject>& default_objects();

// The named object sets `--objects` takes beside object names and paths.
enum class ObjectSet { kDefault, kTuning, kTune, kConfirm };

// The halves of the tuning set, one fixed rule: sort the 30 names alphabetically; positions 1, 3,
// 5, ... (1-based) form the tune half, positions 2, 4, 6, ... the confirm half. kTune or kConfirm
// for a member of the tuning set, none for any other name.
std::optional<ObjectSet> tuning_half(const std::string& name);

// A set's members: default and tuning in the tables' order, the halves alphabetically.
std::vector<std::string> object_set(ObjectSet set);

// An object list as given (`--objects tune,sphere,my/mesh.ply`): each set name replaced by its
// members, a name or path listed twice kept once (the first), in order. Throws
// std::invalid_argument naming an entry that is none of a set, a known object, a built-in
// (sphere, box) or an existing file.
std::vector<std::string> expand_objects(const std::vector<std::string>& given);

// True when `objects` are exactly the default set (in any order).
bool is_default_set(const std::vector<std::string>& objects);

// A name (any object of the tuning set, sphere, box) or a mesh path. Throws
// std::runtime_error naming the object when a fetched mesh is missing (run ./scripts/setup) or
// the file cannot be loaded.
ObjectSpec resolve_object(const std::string& name_or_path);

}  // namespace pbnbv::eval

namespace pbnbv {
template <>
struct EnumNames<eval::ObjectSet> {
  static constexpr std::string_view what = "object set";
  static constexpr std::array<NamedValue<eval::ObjectSet>, 4> names{{{eval::ObjectSet::kDefault, "default"},
                                                                     {eval::ObjectSet::kTuning, "tuning"},
                                                                     {eval::ObjectSet::kTune, "tune"},
                                                                     {eval::ObjectSet::kConfirm, "confirm"}}};
};
}  // namespace pbnbv
