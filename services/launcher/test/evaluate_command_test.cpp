// `pbnbv evaluate` on files whose answers are known by hand: a 10 cm square (the top of a 2 cm
// slab: the mesh reader refuses flat meshes) and a grid of points 2 mm above it, as PLY, PCD,
// OBJ and STL, a thin model mesh above it, a scan folder; and the inputs it must refuse, named.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/base/version.hpp"
#include "core/scan/scan_file.hpp"
#include "core/scan/scan_record.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "core/io/mesh_file.hpp"
#include "eval/evaluate.hpp"
#include "error_message.hpp"
#include "file_test_util.hpp"
#include "launcher/command_line.hpp"
#include "launcher/commands.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv::launcher {
namespace {

// The reference: a 10 x 10 x 2 cm slab centred at the origin, scaled (1000: in mm); its top, the
// 10 cm square, lies at z = 1 cm.
TriangleMesh slab(double scale = 1) {
  TriangleMesh m = make_box(Eigen::Vector3d(0.1, 0.1, 0.02));
  for (auto& v : m.vertices) v *= scale;
  return m;
}

// 101 x 101 points every 1 mm over the top square, 2 mm above it.
PointCloud grid_2mm_above() {
  PointCloud c;
  for (int i = 0; i <= 100; ++i) {
    for (int j = 0; j <= 100; ++j) c.emplace_back(-0.05 + i * 0.001, -0.05 + j * 0.001, 0.012);
  }
  return c;
}

// Recall at 5 mm of that grid: the top (100 cm^2) and a band of the sides 3 mm deep (the sides'
// points with (depth + 2 mm)^2 + (at most 0.5 mm sideways)^2 <= 25 mm^2; 4 x 3 cm^2) of the
// slab's 280 cm^2: 112 / 280. 28,000 samples: binomial spread 0.003.
constexpr double kRecall5mm = 112.0 / 280.0;

class EvaluateCommand : public testing::TempDirTest {
 protected:
  // Parses `pbnbv evaluate <words> --json F`, runs it, returns the JSON it wrote.
  json run(std::vector<std::string> words) {
    const std::string out_json = path("out.json");
    words.insert(words.begin(), {"pbnbv", "evaluate"});
    words.insert(words.end(), {"--json", out_json});
    std::vector<const char*> argv;
    for (const auto& w : words) argv.push_back(w.c_str());
    CommandLine line;
    std::ostringstream out, err;
    const auto code = line.parse(static_cast<int>(argv.size()), argv.data(), out, err);
    EXPECT_FALSE(code.has_value()) << err.str();
    EXPECT_EQ(line.command(), Command::kEvaluate);
    std::ostringstream table;
    EXPECT_EQ(run_evaluate(line.evaluate(), table), 0);
    table_ = table.str();
    return read_json(out_json);
  }
  // run_evaluate's error message for `o`.
  static std::string error_of(const EvaluateOptions& o) {
    std::ostringstream out;
    try {
      run_evaluate(o, out);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "(no error)";
  }
  std::string table_;

  // A finished twin scan in miniature in dir_/name: the true mesh, one merged frame, the cloud,
  // and scan.json recording that view (written through its types), with `patch` merged into it.
  fs::path mini_scan(const std::string& name, const json& patch) {
    const fs::path scan = dir_ / name;
    fs::create_directories(scan / "frames");
    write_stl_binary(slab(), (scan / "object.stl").string());
    write_ply(grid_2mm_above(), (scan / "frames" / "view_001.ply").string());
    write_ply(grid_2mm_above(), (scan / "cloud.ply").string());
    RecordedScan r;
    r.pbnbv_version = std::string(pbnbv_version());
    r.settings.scan_id = "mini-0123456789abcdef";
    ViewRecord v;
    v.capture = CaptureResult{};
    v.capture->ok = true;
    v.registration = RegisteredCloud{};
    v.registration->accepted = true;
    v.registration->frame_file = "frames/view_001.ply";
    v.map = VoxelMapSummary{};
    r.views = {v};
    json record = to_json(r);
    record.merge_patch(patch);
    write_json_atomic(record, (scan / "scan.json").string());
    return scan;
  }
};

// Accuracy `lo`..`hi` mm in every statistic, precision 1 and the slab's recall at 5 mm.
void expect_above_the_top(const json& m, double lo = 2.0, double hi = 2.0) {
  for (const char* k : {"mean_mm", "median_mm", "rmse_mm", "p95_mm", "max_mm"}) {
    EXPECT_GE(m.at("accuracy").at(k).get<double>(), lo - 1e-4) << k;
    EXPECT_LE(m.at("accuracy").at(k).get<double>(), hi + 1e-4) << k;
  }
  EXPECT_DOUBLE_EQ(m.at("precision").get<double>(), 1.0);
  const double r = m.at("recall").get<double>();
  EXPECT_NEAR(r, kRecall5mm, 0.012);
  EXPECT_NEAR(m.at("f_score").get<double>(), 2 * r / (1 + r), 1e-12);
}

TEST_F(EvaluateCommand, CloudTwoMillimetresAboveTheReference) {
  write_obj(slab(), path("square.obj"));
  write_ply(grid_2mm_above(), path("cloud.ply"));
  const json j = run({path("cloud.ply"), "--reference", path("square.obj")});
  ASSERT_EQ(j.at("models").size(), 1u);
  const json& m = j["models"][0];
  EXPECT_EQ(m.at("model"), "cloud");
  EXPECT_EQ(m.at("accuracy").at("count"), 101 * 101);
  EXPECT_EQ(m.at("completeness").at("count"), 28000);  // 280 cm^2, 100 per cm^2
  expect_above_the_top(m);
  EXPECT_DOUBLE_EQ(j.at("settings").at("threshold_mm").get<double>(), 5.0);
  EXPECT_NE(table_.find("precision 1.0000   recall 0.4"), std::string::npos) << table_;
  EXPECT_NE(table_.find("(within 5.00 mm)"), std::string::npos) << table_;
  EXPECT_NE(table_.find("accuracy         2.000    2.000    2.000    2.000    2.000"), std::string::npos) << table_;

  // Within 1 mm nothing counts: every point is 2 mm from the square, every sample 2 mm or more
  // from the points (the top's 2 to 2.12 mm, the sides' more).
  const json tight = run({path("cloud.ply"), "--reference", path("square.obj"), "--threshold", "0.001"});
  EXPECT_DOUBLE_EQ(tight["models"][0]["precision"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(tight["models"][0]["recall"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(tight["models"][0]["f_score"].get<double>(), 0.0);
}

TEST_F(EvaluateCommand, PcdCloudAndAReferenceInMillimetres) {
  write_stl_binary(slab(1000), path("square_mm.stl"));
  std::string pcd = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 10201\nHEIGHT 1\n"
                    "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 10201\nDATA ascii\n";
  for (const auto& p : grid_2mm_above()) pcd += fmt::format("{} {} {}\n", p.x(), p.y(), p.z());
  write("cloud.pcd", pcd);
  const json j = run({path("cloud.pcd"), "--reference", path("square_mm.stl"), "--reference-scale", "0.001"});
  expect_above_the_top(j["models"][0]);
  EXPECT_DOUBLE_EQ(j.at("reference_scale").get<double>(), 0.001);
}

TEST_F(EvaluateCommand, MeshTwoMillimetresAboveAndAScanFolder) {
  write_obj(slab(), path("square.obj"));
  // The model mesh as an ASCII PLY with faces (what mesh.ply is): a 10 x 10 cm box 0.1 mm thick,
  // from 2 to 2.1 mm above the top square: every point of it 2 to 2.1 mm from the slab.
  TriangleMesh sheet = make_box(Eigen::Vector3d(0.1, 0.1, 0.0001));
  std::string ply = fmt::format(
      "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n"
      "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
      sheet.vertices.size(), sheet.triangles.size());
  for (const auto& v : sheet.vertices) ply += fmt::format("{} {} {}\n", v.x(), v.y(), v.z() + 0.01205);
  for (const auto& t : sheet.triangles) ply += fmt::format("3 {} {} {}\n", t[0], t[1], t[2]);
  const fs::path scan = dir_ / "scan";
  fs::create_directories(scan);
  write("scan/mesh.ply", ply);
  write_ply(grid_2mm_above(), (scan / "cloud.ply").string());

  const json mesh = run({(scan / "mesh.ply").string(), "--reference", path("square.obj")});
  EXPECT_EQ(mesh["models"][0]["model"], "mesh");
  expect_above_the_top(mesh["models"][0], 2.0, 2.1);

  const json folder = run({scan.string(), "--reference", path("square.obj")});
  ASSERT_EQ(folder["models"].size(), 2u);
  EXPECT_EQ(folder["models"][0]["model"], "cloud");
  EXPECT_EQ(folder["models"][1]["model"], "mesh");
  expect_above_the_top(folder["models"][0]);
  expect_above_the_top(folder["models"][1], 2.0, 2.1);
}

TEST_F(EvaluateCommand, TwinScanFolderAgainstItsObjectStl) {
  const fs::path scan = mini_scan(
      "scan", {{"format_version", kScanFormatVersion}, {"status", {{"state", "done"}, {"views_done", 1}, {"message", "done"}}}});
  const json j = run({scan.string()});
  ASSERT_EQ(j.at("models").size(), 1u);
  expect_above_the_top(j["models"][0]);
  // Coverage as `pbnbv scan` measures it (10,000 samples, a point within 5 mm): the recall's
  // 112 of 280 cm^2, in percent.
  EXPECT_NEAR(j.at("scan").at("coverage_by_view").at(0).get<double>(), 100 * kRecall5mm, 2.0);
  expect_above_the_top(j["scan"]["surface_metrics"]["cloud"]);
  // The coverage alone (what tests that read only the coverage use): the same figures, no metrics.
  const eval::ScanEvaluation full = eval::evaluate_scan(scan);
  const eval::ScanEvaluation coverage = eval::evaluate_coverage(scan);
  ASSERT_TRUE(full.cloud_metrics.has_value());
  EXPECT_FALSE(coverage.cloud_metrics.has_value());
  EXPECT_FALSE(coverage.mesh_metrics.has_value());
  ASSERT_EQ(coverage.coverage_by_view.size(), 1u);
  EXPECT_EQ(coverage.coverage_by_view, full.coverage_by_view);
  EXPECT_EQ(coverage.points_by_view, full.points_by_view);
  EXPECT_EQ(coverage.state, full.state);
  EXPECT_EQ(coverage.views_done, full.views_done);

  // A mesh.ply without faces: said, with why, and exit code 1; the cloud and coverage stand.
  write("scan/mesh.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                         "property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"
                         "0 0 0\n1 0 0\n0 1 0\n");
  EvaluateOptions o;
  o.target = scan.string();
  o.json = path("broken.json");
  std::ostringstream table;
  EXPECT_EQ(run_evaluate(o, table), 1);
  EXPECT_NE(table.str().find("mesh.ply: not evaluated:"), std::string::npos) << table.str();
  const json b = read_json(o.json);
  ASSERT_EQ(b["models"].size(), 2u);
  expect_above_the_top(b["models"][0]);
  EXPECT_NE(b["models"][1]["error"].get<std::string>().find("mesh.ply"), std::string::npos) << b;
  EXPECT_NE(b["scan"]["surface_metrics"]["mesh"]["error"].get<std::string>().find("no triangles"), std::string::npos) << b;
}

TEST_F(EvaluateCommand, BadInputIsNamed) {
  write_obj(slab(), path("square.obj"));
  write_ply(grid_2mm_above(), path("cloud.ply"));
  write_ply(PointCloud{}, path("empty.ply"));
  write("vertices.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  write("broken.stl", "solid x\nfacet normal 0 0 1\n");
  fs::create_directories(dir_ / "empty_dir");

  EvaluateOptions o;
  o.reference = path("square.obj");
  auto expect = [&](const std::string& target, const std::string& reference, const std::vector<std::string>& needles) {
    o.target = target;
    o.reference = reference;
    const std::string e = error_of(o);
    for (const auto& n : needles) EXPECT_NE(e.find(n), std::string::npos) << "'" << e << "' lacks '" << n << "'";
  };
  expect(path("nothing.ply"), path("square.obj"), {"nothing.ply", "no such file"});
  expect(path("empty.ply"), path("square.obj"), {"empty.ply", "no points"});
  expect(path("vertices.obj"), path("square.obj"), {"vertices.obj", "no triangles"});
  expect(path("cloud.ply"), path("vertices.obj"), {"vertices.obj", "no triangles"});
  expect(path("cloud.ply"), path("broken.stl"), {"broken.stl"});
  expect(path("cloud.ply"), path("missing.obj"), {"missing.obj"});
  expect(path("cloud.ply"), "", {"--reference MESH is required", "cloud.ply"});
  expect((dir_ / "empty_dir").string(), "", {"empty_dir", "no object.stl", "--reference"});
  expect((dir_ / "empty_dir").string(), path("square.obj"), {"empty_dir", "neither cloud.ply nor mesh.ply"});
  write("notes.txt", "x");
  expect(path("notes.txt"), path("square.obj"), {"notes.txt", "not a cloud"});

  // The command line: no target; a threshold out of range.
  for (const auto& [words, needle] :
       std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"pbnbv", "evaluate"}, "name what to evaluate"},
           {{"pbnbv", "evaluate", "x.ply", "--threshold", "0"}, "--threshold"}}) {
    std::vector<const char*> argv;
    for (const auto& w : words) argv.push_back(w.c_str());
    CommandLine line;
    std::ostringstream out, err;
    EXPECT_EQ(line.parse(static_cast<int>(argv.size()), argv.data(), out, err), 2);
    EXPECT_NE(err.str().find(needle), std::string::npos) << err.str();
  }
}

// A scan folder whose scan.json is of another format (here format 3, as a later pbnbv might write)
// is refused by `pbnbv evaluate` and `pbnbv mesh` naming the file, both formats and the writer;
// nothing is written into the folder.
TEST_F(EvaluateCommand, AFolderOfAnotherScanFormatIsRefusedNamingBothFormats) {
  const fs::path scan =
      mini_scan("later", {{"format_version", 3}, {"pbnbv_version", "0.13.0"}, {"status", {{"state", "done"}}}});
  const std::string expected = (scan / "scan.json").string() + ": format 3 (written by pbnbv 0.13.0); this pbnbv (" +
                               std::string(pbnbv_version()) + ") reads format 2 only";
  using pbnbv::testing::error_message;
  EvaluateOptions e;
  e.target = scan.string();
  std::ostringstream table;
  EXPECT_EQ(error_message([&] { run_evaluate(e, table); }), expected);
  MeshOptions m;
  m.dir = scan.string();
  EXPECT_EQ(error_message([&] { run_mesh(m); }), expected);
  EXPECT_FALSE(fs::exists(scan / "mesh.ply"));
  EXPECT_EQ(error_message([&] { eval::evaluate_coverage(scan); }), expected);
}

}  // namespace
}  // namespace pbnbv::launcher
