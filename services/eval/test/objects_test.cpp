// The objects a benchmark names: the tuning set (the default set's 12 first), its halves by the
// one fixed rule, the named sets and how an --objects list mixes them with names and paths.
#include "eval/objects.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "core/scan/scan_settings.hpp"

namespace fs = std::filesystem;

namespace pbnbv::eval {
namespace {

std::vector<std::string> names(const std::vector<KnownObject>& objects) {
  std::vector<std::string> out;
  for (const auto& o : objects) out.emplace_back(o.name);
  return out;
}

TEST(ObjectSets, TheDefaultSetIsTheFirst12OfTheTuningSet) {
  const std::vector<std::string> tuning = names(tuning_objects());
  ASSERT_EQ(tuning.size(), 30u);
  EXPECT_EQ(std::set<std::string>(tuning.begin(), tuning.end()).size(), 30u);  // no name twice
  const std::vector<std::string> defaults = {"bunny", "teapot", "armadillo", "bear", "bull", "cow",
                                             "dino", "dragon", "elephant", "elk", "fandisk", "homer"};
  EXPECT_EQ(names(default_objects()), defaults);
  EXPECT_EQ(object_set(ObjectSet::kDefault), defaults);
  EXPECT_EQ(object_set(ObjectSet::kTuning), tuning);
  EXPECT_TRUE(std::equal(defaults.begin(), defaults.end(), tuning.begin()));
  // The up axes the renders showed, x among them.
  const auto up = [](const std::string& n) {
    for (const auto& o : tuning_objects())
      if (n == o.name) return o.up;
    throw std::logic_error(n);
  };
  EXPECT_EQ(up("dragknob"), UpAxis::kX);
  EXPECT_EQ(up("turbine"), UpAxis::kX);
  EXPECT_EQ(up("bones"), UpAxis::kY);
  EXPECT_EQ(up("cheese"), UpAxis::kZ);
}

// Sorted alphabetically, positions 1, 3, 5, ... are the tune half, 2, 4, 6, ... the confirm half.
TEST(ObjectSets, TheHalvesRule) {
  const std::vector<std::string> tune = object_set(ObjectSet::kTune), confirm = object_set(ObjectSet::kConfirm);
  EXPECT_EQ(tune, (std::vector<std::string>{"armadillo", "bones", "bunny", "couplingdown", "dino", "dragon", "elephant",
                                            "fandisk", "head", "joint", "mushroom", "oblong", "pig", "retinal", "teapot"}));
  EXPECT_EQ(confirm, (std::vector<std::string>{"bear", "bull", "cheese", "cow", "dragknob", "eight", "elk", "handle",
                                               "homer", "man", "nefertiti", "part", "pipe", "rotor", "turbine"}));
  std::set<std::string> both(tune.begin(), tune.end());
  both.insert(confirm.begin(), confirm.end());
  EXPECT_EQ(both.size(), 30u);  // disjoint, and together the tuning set
  const std::vector<std::string> tuning = object_set(ObjectSet::kTuning);
  EXPECT_EQ(both, std::set<std::string>(tuning.begin(), tuning.end()));
  EXPECT_EQ(tuning_half("armadillo"), ObjectSet::kTune);
  EXPECT_EQ(tuning_half("bear"), ObjectSet::kConfirm);
  EXPECT_FALSE(tuning_half("sphere").has_value());
  EXPECT_FALSE(tuning_half("meshes/bunny.obj").has_value());  // a path is no member
}

TEST(ObjectSets, AListMixesSetsNamesAndPaths) {
  const fs::path mesh = fs::temp_directory_path() / ("pbnbv_objects_test_" + std::to_string(::getpid()) + ".obj");
  std::ofstream(mesh) << "v 0 0 0\n";  // only its existence is checked here
  std::vector<std::string> want = object_set(ObjectSet::kTune);
  want.push_back("sphere");
  EXPECT_EQ(expand_objects({"tune", "sphere"}), want);
  // A name listed twice (bunny is in the tune half) is kept once, where it first appears.
  want = {"bunny"};
  for (const auto& o : object_set(ObjectSet::kTune))
    if (o != "bunny") want.push_back(o);
  want.push_back(mesh.string());
  EXPECT_EQ(expand_objects({"bunny", "tune", mesh.string(), "bunny"}), want);
  EXPECT_EQ(expand_objects({"default"}), object_set(ObjectSet::kDefault));
  EXPECT_EQ(expand_objects({"tune", "confirm"}).size(), 30u);
  fs::remove(mesh);

  // An unknown entry is named with what it could have been.
  try {
    expand_objects({"tune", "tunning"});
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("--objects: 'tunning' is neither an object set (default, tuning, tune or confirm), a known object (bunny, "
                      "teapot, ",
                      0),
              0u)
        << m;
    EXPECT_NE(m.find("a built-in (sphere, box) nor a mesh file"), std::string::npos) << m;
  }
  EXPECT_THROW(expand_objects({mesh.string()}), std::invalid_argument);  // removed: no longer a file
}

// Every object of the tuning set is fetched (./scripts/setup), loads with the triangles its
// source has, and passes the checks a scan makes before anything starts.
TEST(ObjectSets, EveryTuningObjectLoadsAndPassesTheScansChecks) {
  const std::map<std::string, std::size_t> triangles = {
      {"bunny", 3674},    {"teapot", 992},   {"armadillo", 52000}, {"bear", 27648},  {"bull", 12396},
      {"cow", 5804},      {"dino", 7828},    {"dragon", 19994},    {"elephant", 5558}, {"elk", 3290},
      {"fandisk", 12946}, {"homer", 9856},   {"cheese", 17786},    {"couplingdown", 3714}, {"dragknob", 318},
      {"handle", 2326},   {"joint", 446},    {"man", 34986},       {"part", 346},    {"pipe", 320},
      {"rotor", 1200},    {"turbine", 18460}, {"bones", 4204},     {"eight", 634},   {"retinal", 7282},
      {"oblong", 840},    {"head", 2918},    {"mushroom", 4608},   {"pig", 891},     {"nefertiti", 562}};
  ASSERT_EQ(triangles.size(), tuning_objects().size());
  for (const auto& k : tuning_objects()) {
    SCOPED_TRACE(k.name);
    ObjectSpec o = resolve_object(k.name);
    EXPECT_EQ(o.name, k.name);
    EXPECT_EQ(o.up, k.up);
    const MeshNormalisation n = normalise_mesh(o.mesh, 0.3, o.up);
    EXPECT_EQ(n.num_triangles, triangles.at(k.name));
    EXPECT_NEAR(n.extent_m.minCoeff(), 0.3, 1e-9);
    EXPECT_NO_THROW(check_object_limits(o.mesh, n, k.name, true));
  }
}

TEST(ObjectSets, IsTheDefaultSetInAnyOrder) {
  std::vector<std::string> d = object_set(ObjectSet::kDefault);
  EXPECT_TRUE(is_default_set(d));
  std::reverse(d.begin(), d.end());
  EXPECT_TRUE(is_default_set(d));
  d.pop_back();
  EXPECT_FALSE(is_default_set(d));
  EXPECT_FALSE(is_default_set(object_set(ObjectSet::kTuning)));
  EXPECT_FALSE(is_default_set({"sphere"}));
}

}  // namespace
}  // namespace pbnbv::eval
