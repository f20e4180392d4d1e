#include "eval/objects.hpp"
#include "core/base/install_paths.hpp"
#include "core/io/mesh_file.hpp"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;

namespace pbnbv::eval {

namespace {

constexpr std::size_t kDefaultSetSize = 12;  // the first 12 of the tuning set

const char* const kBuiltIns[] = {"sphere", "box"};

const KnownObject* find_known(const std::string& name) {
  for (const auto& d : tuning_objects()) {
    if (name == d.name) return &d;
  }
  return nullptr;
}

std::string known_names() {
  std::string names;
  for (const auto& d : tuning_objects()) names += std::string(names.empty() ? "" : ", ") + d.name;
  return names;
}

}  // namespace

const std::vector<KnownObject>& tuning_objects() {
  static const std::vector<KnownObject> objects = {
      // The default set.
      {"bunny", "bunny.obj", UpAxis::kY, "npm package bunny (Stanford bunny)"},
      {"teapot", "teapot.obj", UpAxis::kY, "npm package teapot (Utah teapot)"},
      {"armadillo", "armadillo.off", UpAxis::kY, "libcgal-demo data/meshes/armadillo.off"},
      {"bear", "bear.off", UpAxis::kY, "libcgal-demo data/meshes/bear.off"},
      {"bull", "bull.off", UpAxis::kY, "libcgal-demo data/meshes/bull.off"},
      {"cow", "cow.off", UpAxis::kY, "libcgal-demo data/meshes/cow.off"},
      {"dino", "dino.off", UpAxis::kZ, "libcgal-demo data/meshes/dino.off"},
      {"dragon", "ChineseDragon-10kv.off", UpAxis::kY, "libcgal-demo data/meshes/ChineseDragon-10kv.off"},
      {"elephant", "elephant.off", UpAxis::kY, "libcgal-demo data/meshes/elephant.off"},
      {"elk", "elk.off", UpAxis::kY, "libcgal-demo data/meshes/elk.off"},
      {"fandisk", "fandisk.off", UpAxis::kY, "libcgal-demo data/meshes/fandisk.off"},
      {"homer", "homer.off", UpAxis::kY, "libcgal-demo data/meshes/homer.off"},
      // The 18 more of the tuning set.
      {"cheese", "cheese.off", UpAxis::kZ, "libcgal-demo data/meshes/cheese.off"},
      {"couplingdown", "couplingdown.off", UpAxis::kZ, "libcgal-demo data/meshes/couplingdown.off"},
      {"dragknob", "dragknob.off", UpAxis::kX, "libcgal-demo data/meshes/dragknob.off"},
      {"handle", "handle.off", UpAxis::kZ, "libcgal-demo data/meshes/handle.off"},
      {"joint", "joint.off", UpAxis::kZ, "libcgal-demo data/meshes/joint.off"},
      {"man", "man.off", UpAxis::kZ, "libcgal-demo data/meshes/man.off"},
      {"part", "part.off", UpAxis::kZ, "libcgal-demo data/meshes/part.off"},
      {"pipe", "pipe.off", UpAxis::kZ, "libcgal-demo data/meshes/pipe.off"},
      {"rotor", "rotor.off", UpAxis::kZ, "libcgal-demo data/meshes/rotor.off"},
      {"turbine", "turbine.off", UpAxis::kX, "libcgal-demo data/meshes/turbine.off"},
      {"bones", "bones.off", UpAxis::kY, "libcgal-demo data/meshes/bones.off"},
      {"eight", "eight.off", UpAxis::kY, "libcgal-demo data/meshes/eight.off"},
      {"retinal", "retinal.off", UpAxis::kZ, "libcgal-demo data/meshes/retinal.off"},
      {"oblong", "oblong.off", UpAxis::kZ, "libcgal-demo data/meshes/oblong.off"},
      {"head", "head.off", UpAxis::kY, "libcgal-demo data/meshes/head.off (open: 58 boundary edges)"},
      {"mushroom", "mushroom.off", UpAxis::kZ, "libcgal-demo data/meshes/mushroom.off (open: 64 boundary edges)"},
      {"pig", "pig.off", UpAxis::kY, "libcgal-demo data/meshes/pig.off (open: 55 boundary edges)"},
      {"nefertiti", "nefertiti.off", UpAxis::kY, "libcgal-demo data/meshes/nefertiti.off (open: 34 boundary edges)"},
  };
  return objects;
}

const std::vector<KnownObject>& default_objects() {
  static const std::vector<KnownObject> objects(tuning_objects().begin(), tuning_objects().begin() + kDefaultSetSize);
  return objects;
}

std::optional<ObjectSet> tuning_half(const std::string& name) {
  std::vector<std::string> sorted;
  for (const auto& d : tuning_objects()) sorted.emplace_back(d.name);
  std::sort(sorted.begin(), sorted.end());
  const auto it = std::find(sorted.begin(), sorted.end(), name);
  if (it == sorted.end()) return std::nullopt;
  // Index 0 is position 1: even indices are the odd positions, the tune half.
  return (it - sorted.begin()) % 2 == 0 ? ObjectSet::kTune : ObjectSet::kConfirm;
}

std::vector<std::string> object_set(ObjectSet set) {
  std::vector<std::string> names;
  if (set == ObjectSet::kDefault || set == ObjectSet::kTuning) {
    for (const auto& d : set == ObjectSet::kDefault ? default_objects() : tuning_objects()) names.emplace_back(d.name);
    return names;
  }
  for (const auto& d : tuning_objects()) {
    if (tuning_half(d.name) == set) names.emplace_back(d.name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::vector<std::string> expand_objects(const std::vector<std::string>& given) {
  std::vector<std::string> out;
  const auto add = [&out](const std::string& o) {
    if (std::find(out.begin(), out.end(), o) == out.end()) out.push_back(o);
  };
  for (const std::string& g : given) {
    if (const std::optional<ObjectSet> set = find_name<ObjectSet>(g)) {
      for (const std::string& o : object_set(*set)) add(o);
    } else if (find_known(g) || std::find(std::begin(kBuiltIns), std::end(kBuiltIns), g) != std::end(kBuiltIns) ||
               fs::is_regular_file(g)) {
      add(g);
    } else {
      throw std::invalid_argument("--objects: '" + g + "' is neither an object set (" + choices_of<ObjectSet>() +
                                  "), a known object (" + known_names() + "), a built-in (sphere, box) nor a mesh file");
    }
  }
  return out;
}

bool is_default_set(const std::vector<std::string>& objects) {
  std::vector<std::string> a = objects, b = object_set(ObjectSet::kDefault);
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  return a == b;
}

ObjectSpec resolve_object(const std::string& object) {
  ObjectSpec o;
  o.name = fs::path(object).stem().string();
  if (object == "sphere") {
    o.source = "built-in icosphere";
    o.mesh = make_icosphere(0.5, 5);
    return o;
  }
  if (object == "box") {
    o.source = "built-in box 1.2 x 1.0 x 0.8";
    o.mesh = make_box(Eigen::Vector3d(1.2, 1.0, 0.8));
    return o;
  }
  if (const KnownObject* d = find_known(object)) {
    o.up = d->up;
    o.source = resource_dir("PBNBV_DATA_DIR", "data", PBNBV_DATA_DIR) + "/meshes/" + d->file;
    if (!fs::exists(o.source)) {
      throw std::runtime_error("object '" + object + "' needs " + o.source + " (" + d->origin +
                               "), which ./scripts/setup fetches: run it first");
    }
    o.mesh = load_mesh(o.source);
    return o;
  }
  if (!fs::exists(object)) {
    throw std::runtime_error("object '" + object + "' is neither a mesh file nor a known object (" + known_names() +
                             ", sphere, box)");
  }
  o.source = fs::absolute(object).string();
  o.mesh = load_mesh(o.source);
  return o;
}

}  // namespace pbnbv::eval
