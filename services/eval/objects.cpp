#include "eval/objects.hpp"
#include "core/base/install_paths.hpp"
#include "core/io/mesh_file.hpp"

#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;

namespace pbnbv::eval {

const std::vector<DefaultObject>& default_objects() {
  static const std::vector<DefaultObject> objects = {
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
  };
  return objects;
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
  for (const auto& d : default_objects()) {
    if (object != d.name) continue;
    o.up = d.up;
    o.source = resource_dir("PBNBV_DATA_DIR", "data", PBNBV_DATA_DIR) + "/meshes/" + d.file;
    if (!fs::exists(o.source)) {
      throw std::runtime_error("object '" + object + "' needs " + o.source + " (" + d.origin +
                               "), which ./scripts/setup fetches: run it first");
    }
    o.mesh = load_mesh(o.source);
    return o;
  }
  if (!fs::exists(object)) {
    std::string names;
    for (const auto& d : default_objects()) names += std::string(names.empty() ? "" : ", ") + d.name;
    throw std::runtime_error("object '" + object + "' is neither a mesh file nor a known object (" + names +
                             ", sphere, box)");
  }
  o.source = fs::absolute(object).string();
  o.mesh = load_mesh(o.source);
  return o;
}


}  // namespace pbnbv::eval
