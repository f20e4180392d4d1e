// The benchmark command end to end: `pbnbv bench` runs three planners (PB-NBV and the two
// baselines served by the same view scorer) on two objects for three views, every scan a full
// pipeline of processes on a real LCM bus in its own private network namespace; summary.json
// must be well formed and agree with the scans, the report and plots must be written, a rerun
// must resume (skip every complete scan), and first views may be added to the folder (drawn
// ones beside the default's). Also the summary's rules on hand-made curves.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <opencv2/imgcodecs.hpp>

#include "eval/bench.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;
using nlohmann::json;

namespace {

json read_json_file(const fs::path& p) {
  std::ifstream in(p);
  return json::parse(in);
}

TEST(BenchRules, ViewsToReach) {
  EXPECT_EQ(eval::views_to_reach({30, 60, 94.9, 95.0, 99}, 95.0), 4);
  EXPECT_EQ(eval::views_to_reach({96}, 95.0), 1);
  EXPECT_FALSE(eval::views_to_reach({30, 60, 94.99}, 95.0).has_value());
  EXPECT_FALSE(eval::views_to_reach({}, 95.0).has_value());
}

TEST(BenchRules, PadViewsKeepsTheLastFigureAfterAnEarlyStop) {
  EXPECT_EQ(eval::pad_views({40, 80, 97}, 5), (std::vector<double>{40, 80, 97, 97, 97}));
  EXPECT_EQ(eval::pad_views({40, 80, 97}, 2), (std::vector<double>{40, 80}));
  EXPECT_TRUE(eval::pad_views({}, 3).empty());
}

TEST(BenchRules, SummaryMeansMediansAndFailures) {
  eval::ObjectRun a, b, c;
  a.object = "a";
  a.complete = true;
  a.coverage_by_view = {40, 90, 96};
  a.planner_ms = {10, 30};
  a.views_to_95 = 3;
  b.object = "b";
  b.complete = true;
  b.coverage_by_view = {60, 96};  // stopped after view 2: its 96 holds for view 3
  b.planner_ms = {20};
  b.views_to_95 = 2;
  c.object = "c";
  c.error = "the scan did not complete";
  b.rig_contacts = 2;  // the rig's contacts count in every run, complete or not
  c.rig_contacts = 1;
  const eval::PlannerSummary s = eval::summarise(PlannerKind::kPbnbv, {a, b, c}, 3);
  EXPECT_EQ(s.rig_contacts, 3);
  EXPECT_EQ(s.runs_with_rig_contacts, (std::vector<std::string>{"b", "c"}));
  EXPECT_EQ(s.complete, 2);
  EXPECT_EQ(s.failed, 1);
  ASSERT_EQ(s.coverage_by_view.size(), 3u);
  EXPECT_DOUBLE_EQ(s.coverage_by_view[0], 50.0);
  EXPECT_DOUBLE_EQ(s.coverage_by_view[1], 93.0);
  EXPECT_DOUBLE_EQ(s.coverage_by_view[2], 96.0);
  EXPECT_DOUBLE_EQ(s.planner_ms_median, 20.0);  // of 10, 20, 30
  EXPECT_DOUBLE_EQ(s.planner_ms_mean, 20.0);
  ASSERT_TRUE(s.views_to_95.has_value());
  EXPECT_DOUBLE_EQ(*s.views_to_95, 2.5);
  EXPECT_EQ(s.reached_95, 2);
  EXPECT_EQ(s.views_to_95_of_mean, 3);  // the mean curve reaches 95 % at view 3
}

// Gap to the oracle: per view, the oracle's coverage minus the planner's, mean over the objects
// both completed (an object only one of them completed does not count).
TEST(BenchRules, GapToTheOracleMeansOverObjectsBothCompleted) {
  auto run = [](const std::string& name, std::vector<double> c) {
    eval::ObjectRun r;
    r.object = name;
    r.complete = !c.empty();
    r.coverage_by_view = std::move(c);
    return r;
  };
  std::vector<eval::PlannerSummary> planners = {
      eval::summarise(PlannerKind::kPbnbv, {run("a", {40, 70, 90}), run("b", {50, 80}), run("c", {10, 20, 30})}, 3),
      eval::summarise(PlannerKind::kOracle, {run("a", {50, 80, 95}), run("b", {60, 90, 99}), run("c", {})}, 3)};
  eval::add_gaps_to_oracle(planners, 3);
  EXPECT_EQ(planners[0].gap_objects, 2);  // c: the oracle did not complete it
  // a: 10, 10, 5; b (80 holds for view 3): 10, 10, 19.
  EXPECT_EQ(planners[0].gap_to_oracle_by_view, (std::vector<double>{10, 10, 12}));
  EXPECT_EQ(planners[1].gap_to_oracle_by_view, (std::vector<double>{0, 0, 0}));
  std::vector<eval::PlannerSummary> without = {planners[0]};
  without[0].gap_to_oracle_by_view.clear();
  eval::add_gaps_to_oracle(without, 3);
  EXPECT_TRUE(without[0].gap_to_oracle_by_view.empty());
}

// Where the stop rule would have stopped: per object the stop view (the budget when never), the
// coverage there against the budget's; mean views saved, worst shortfall.
TEST(BenchRules, StopRuleSummaryViewsSavedAndWorstShortfall) {
  auto run = [](const std::string& name, std::vector<double> c, std::optional<int> stop) {
    eval::ObjectRun r;
    r.object = name;
    r.complete = true;
    r.coverage_by_view = std::move(c);
    r.stop_view = stop;
    return r;
  };
  const std::vector<eval::ObjectRun> runs = {
      run("a", {40, 80, 95, 95.2, 95.3}, 3),    // stops after 3: 95 against 95.3, 2 views saved
      run("b", {50, 90, 99, 99.9, 99.9}, 4),    // after 4: no shortfall, 1 saved
      run("c", {30, 60, 70, 80, 90}, std::nullopt)};  // never: the budget, nothing saved
  EXPECT_EQ(eval::stop_view_or_budget(runs[2], 5), 5);
  EXPECT_DOUBLE_EQ(eval::coverage_at_view(runs[0], 3), 95.0);
  const eval::StopRuleSummary s = eval::summarise_stop_rule(runs, 5);
  EXPECT_EQ(s.objects, 3);
  EXPECT_EQ(s.stopped, 2);
  EXPECT_DOUBLE_EQ(s.mean_stop_view, 4.0);                       // (3 + 4 + 5) / 3
  EXPECT_DOUBLE_EQ(s.mean_views_saved_percent, 100.0 * 3 / 15);  // (2 + 1 + 0) of 3 x 5 views
  EXPECT_NEAR(s.worst_shortfall, 0.3, 1e-9);
  EXPECT_EQ(s.worst_object, "a");
  EXPECT_EQ(s.within_half_point, 3);
}

TEST(Bench, ThreePlannersTwoObjectsThreeViewsInPrivateNamespaces) {
  const fs::path out = fresh_dir("bench");
  const std::string cmd = netns_run() + " " + bin_dir() +
                          "/pbnbv bench --objects sphere,box --planners pbnbv,raycast,random --rig free --area full "
                          "--views 3 --jobs 2 --out " + out.string();
  const CommandResult r = run_command(cmd);
  ASSERT_EQ(r.exit_code, 0) << cmd << "\n" << r.output;
  EXPECT_NE(r.output.find("[1/6] sphere - pbnbv"), std::string::npos) << r.output;  // progress

  const json s = read_json_file(out / "summary.json");
  EXPECT_EQ(s["planners"], json({"pbnbv", "raycast", "random"}));
  EXPECT_EQ(s["settings"]["views"], 3);
  EXPECT_EQ(s["settings"]["rig"], "free");
  EXPECT_EQ(s["settings"]["candidates"], 800);
  EXPECT_GE(s["machine"]["cores"].get<int>(), 1);
  std::map<std::string, double> first_view;  // object -> coverage after view 1
  for (const std::string planner : {"pbnbv", "raycast", "random"}) {
    SCOPED_TRACE(planner);
    const json& p = s.at(planner);
    ASSERT_EQ(p["coverage_by_view"].size(), 3u);
    EXPECT_EQ(p["objects_complete"], 2);
    EXPECT_GT(p["planner_ms_median"].get<double>(), 0.0);
    EXPECT_GT(p["planner_ms_mean"].get<double>(), 0.0);
    ASSERT_TRUE(p["views_to_95"].is_null() || p["views_to_95"].is_number());
    // No move of any scan touched anything (the twin's contact check).
    EXPECT_EQ(p["rig_contacts"]["events"], 0) << p["rig_contacts"].dump();
    EXPECT_EQ(p["rig_contacts"]["runs_with_any"], json::array());
    std::vector<double> mean(3, 0.0);
    double mean_f = 0;  // F-score at 5 mm, mean over the objects
    for (const std::string object : {"sphere", "box"}) {
      SCOPED_TRACE(object);
      const json& o = p["runs"].at(object);  // one first view: the run is named after the object
      EXPECT_EQ(o["object"], object);
      EXPECT_EQ(o["first_view"], 1);
      EXPECT_EQ(o["rig_contacts"], 0);
      EXPECT_EQ(p["objects"].at(object)["coverage_by_view"], o["coverage_by_view"]);  // its mean over one run
      ASSERT_EQ(o["coverage_by_view"].size(), 3u);
      EXPECT_EQ(o["planner_ms"].size(), 2u);  // views 2 and 3 were planned
      for (int i = 0; i < 3; ++i) {
        const double c = o["coverage_by_view"][i].get<double>();
        EXPECT_GT(c, 0.0);
        EXPECT_LE(c, 100.0);
        if (i > 0) {
          EXPECT_GE(c, o["coverage_by_view"][i - 1].get<double>());
        }
        mean[i] += c / 2;
      }
      // Every planner starts from the same first view: the same coverage, to within what the
      // rig's settling tolerance moves the camera (the twin's physics stops within a fraction
      // of a millimetre of the target, never at the same point twice).
      const double c1 = o["coverage_by_view"][0].get<double>();
      if (first_view.count(object)) {
        EXPECT_NEAR(c1, first_view[object], 0.5);
      }
      first_view[object] = c1;
      // A sphere seen from one side: about the visible cap, well under half.
      if (object == "sphere") {
        EXPECT_LT(c1, 50.0);
      }
      // And the scan's own outputs are there; its coverage.json without the surface metrics,
      // which the bench's evaluation computes (once, below).
      EXPECT_TRUE(fs::exists(out / planner / object / "cloud.ply"));
      const json own = read_json_file(out / planner / object / "coverage.json");
      EXPECT_EQ(own["coverage_by_view"].size(), 3u);
      EXPECT_EQ(own["surface_metrics"], json::object());
      // The scans ran the whole budget (the stop rule off); the summary says where the rule
      // would have stopped each, from the per-view figures the scan recorded.
      const json scan = read_json_file(out / planner / object / "scan.json");
      EXPECT_EQ(scan["settings"]["stop_rule"]["rule"], "off");
      EXPECT_EQ(scan["views"][0]["new_surface"]["percent_of_model"], 100.0);
      ASSERT_EQ(o["stop_rule"]["new_surface_by_view"].size(), 3u);
      EXPECT_EQ(o["stop_rule"]["coverage_at_budget"], o["coverage_by_view"][2]);
      // The final cloud against the true mesh: the free rig's poses are exact and its depth
      // noiseless, so the points lie on the surface but for the 2 mm voxel's centroids; recall
      // at 5 mm is the coverage's fraction (other samples, cloud.ply instead of the frames).
      const json& m = o.at("surface_metrics").at("cloud");
      EXPECT_LT(m["accuracy"]["mean_mm"].get<double>(), 1.0);
      EXPECT_GT(m["precision"].get<double>(), 0.99);
      EXPECT_NEAR(m["recall"].get<double>() * 100, o["coverage_by_view"][2].get<double>(), 2.0);
      mean_f += m["f_score"].get<double>() / 2;
    }
    // Rig time: both runs measured at every view, the rig time at the end of each view growing.
    EXPECT_EQ(p["rig_time_runs"], 2);
    ASSERT_EQ(p["rig_time_s_by_view"].size(), 3u);
    EXPECT_GT(p["rig_time_s_by_view"][0].get<double>(), 0.0);
    for (int i = 1; i < 3; ++i) EXPECT_GT(p["rig_time_s_by_view"][i].get<double>(), p["rig_time_s_by_view"][i - 1].get<double>());
    EXPECT_TRUE(p["rig_time_s_to_95"].is_null() || p["rig_time_s_to_95"].is_number());
    EXPECT_NEAR(p["rig_time_s"]["total"].get<double>(),
                p["rig_time_s"]["motion"].get<double>() + p["rig_time_s"]["settle"].get<double>() +
                    p["rig_time_s"]["capture"].get<double>() + p["rig_time_s"]["compute"].get<double>(),
                1e-9);
    EXPECT_NEAR(p["surface_metrics"]["cloud"]["f_score"].get<double>(), mean_f, 1e-9);
    EXPECT_EQ(p["surface_metrics"]["cloud"]["runs"], 2);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(p["coverage_by_view"][i].get<double>(), mean[i], 1e-9);
  }
  // Two planned views of a sphere add surface for a planner that looks for it.
  EXPECT_GT(s["pbnbv"]["runs"]["sphere"]["coverage_by_view"][2].get<double>(),
            s["pbnbv"]["runs"]["sphere"]["coverage_by_view"][0].get<double>() + 20.0);

  // The report in the paper's form, and the plots.
  std::ifstream md(out / "report.md");
  const std::string report((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
  EXPECT_NE(report.find("| pbnbv |"), std::string::npos);
  EXPECT_NE(report.find("| raycast |"), std::string::npos);
  EXPECT_NE(report.find("resolution 0.03 m"), std::string::npos);
  EXPECT_NE(report.find("## Stop rule"), std::string::npos);
  EXPECT_NE(report.find("Rig contacts: none"), std::string::npos);
  EXPECT_NE(report.find("## Surface metrics after the last view"), std::string::npos);
  EXPECT_NE(report.find("| pbnbv | cloud | 2 |"), std::string::npos);
  EXPECT_NE(report.find("## Rig time"), std::string::npos);
  for (const char* png : {"coverage.png", "time.png", "observable_time.png"}) {
    const cv::Mat img = cv::imread((out / png).string());
    EXPECT_EQ(img.cols, 960) << png;
    EXPECT_EQ(img.rows, 600) << png;
  }

  // A rerun skips every complete scan and gives the same figures.
  const CommandResult again = run_command(cmd);
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("(6 already complete"), std::string::npos) << again.output;
  // Nor evaluated again: each object's record was made from the same scans.
  EXPECT_NE(again.output.find("one task per object: 0 to run (2 recorded from the same scans)"), std::string::npos)
      << again.output;
  EXPECT_EQ(again.output.find("started"), std::string::npos) << again.output;
  const json s2 = read_json_file(out / "summary.json");
  for (const std::string planner : {"pbnbv", "raycast", "random"}) {
    EXPECT_EQ(s2[planner]["coverage_by_view"], s[planner]["coverage_by_view"]);
  }
  // First views added to the folder's benchmark: the box from a second first view, drawn, for two
  // of its planners. The default first view's scans are reused (<object>/, as with one); the drawn
  // one lies at the same distance from the centre, the same for both planners, in <object>-fv2/;
  // the means are over the runs, the interval over the objects (one: zero width).
  const CommandResult fv = run_command(netns_run() + " " + bin_dir() +
                                       "/pbnbv bench --objects box --planners pbnbv,random --rig free --area full "
                                       "--views 3 --first-views 2 --jobs 2 --out " + out.string());
  ASSERT_EQ(fv.exit_code, 0) << fv.output;
  EXPECT_NE(fv.output.find("1 objects x 2 first views x 2 planners = 4 scans (2 already complete"), std::string::npos)
      << fv.output;
  const json f = read_json_file(out / "summary.json");
  EXPECT_EQ(f["first_views"], 2);
  ASSERT_EQ(f["first_view_directions"].size(), 1u);
  auto point = [](const json& v) { return Eigen::Vector3d(v[0].get<double>(), v[1].get<double>(), v[2].get<double>()); };
  const Eigen::Vector3d direction = point(f["first_view_directions"][0]);
  EXPECT_NEAR(direction.norm(), 1.0, 1e-9);
  std::optional<Eigen::Vector3d> drawn;  // where the first planner's drawn run started
  for (const std::string planner : {"pbnbv", "random"}) {
    SCOPED_TRACE(planner);
    const json& p = f.at(planner);
    EXPECT_EQ(p["runs_complete"], 2);
    EXPECT_EQ(p["objects_complete"], 1);
    const json& a = p["runs"].at("box");
    const json& b = p["runs"].at("box-fv2");
    EXPECT_EQ(a["coverage_by_view"], s[planner]["runs"]["box"]["coverage_by_view"]);  // the same scan, kept
    EXPECT_EQ(b["first_view"], 2);
    EXPECT_TRUE(fs::exists(out / planner / "box-fv2" / "cloud.ply"));
    // The drawn first view as the scan recorded it: the default's distance, the drawn direction.
    const Eigen::Vector3d pa = point(a["initial_view"]), pb = point(b["initial_view"]);
    EXPECT_NEAR(pb.norm(), pa.norm(), 1e-9);
    EXPECT_LT((pb - pa.norm() * direction).norm(), 1e-9) << pb.transpose();
    if (drawn) {
      EXPECT_LT((pb - *drawn).norm(), 1e-12);
    }
    drawn = pb;
    for (int i = 0; i < 3; ++i) {
      const double ca = a["coverage_by_view"][i].get<double>(), cb = b["coverage_by_view"][i].get<double>();
      EXPECT_NEAR(p["coverage_by_view"][i].get<double>(), (ca + cb) / 2, 1e-9);
      EXPECT_NEAR(p["objects"]["box"]["coverage_by_view"][i].get<double>(), (ca + cb) / 2, 1e-9);
      EXPECT_NEAR(p["coverage_ci95_by_view"][i][0].get<double>(), (ca + cb) / 2, 1e-9);
      EXPECT_NEAR(p["coverage_ci95_by_view"][i][1].get<double>(), (ca + cb) / 2, 1e-9);
      EXPECT_EQ(p["coverage_min_by_view"][i].get<double>(), std::min(ca, cb));
    }
  }
  EXPECT_NEAR(f["pbnbv"]["runs"]["box-fv2"]["coverage_by_view"][0].get<double>(),
              f["random"]["runs"]["box-fv2"]["coverage_by_view"][0].get<double>(), 0.5);  // the same first view
  std::ifstream fmd(out / "report.md");
  const std::string freport((std::istreambuf_iterator<char>(fmd)), std::istreambuf_iterator<char>());
  EXPECT_NE(freport.find("1 object x 2 first views (2 runs)"), std::string::npos) << freport;

  // Other settings in the same folder are refused, naming the setting.
  const CommandResult other = run_command(netns_run() + " " + bin_dir() + "/pbnbv bench --objects sphere --planners pbnbv "
                                          "--views 4 --out " + out.string());
  EXPECT_NE(other.exit_code, 0);
  EXPECT_NE(other.output.find("views"), std::string::npos) << other.output;
}

// A sweep (--camera ideal,d435 --resolution 0.03,0.05): four benchmarks, each in its folder with
// its own settings and summary, their four scans run together, one table across them; a rerun
// runs and evaluates nothing; a bench of its own is refused in the sweep's folder.
TEST(Bench, ASweepRunsEveryCombinationInAFolderOfItsOwn) {
  const fs::path out = fresh_dir("bench-sweep");
  const std::string cmd = netns_run() + " " + bin_dir() +
                          "/pbnbv bench --objects box --planners pbnbv --rig free --area full --views 2 "
                          "--camera ideal,d435 --resolution 0.03,0.05 --jobs 2 --out " + out.string();
  const CommandResult r = run_command(cmd);
  ASSERT_EQ(r.exit_code, 0) << cmd << "\n" << r.output;
  EXPECT_NE(r.output.find("4 scans to run of 4 in 4 benchmarks, 2 at a time"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("[3/4] camera=d435,resolution=0.03 box - pbnbv: started"), std::string::npos) << r.output;
  const json sweep = read_json_file(out / "sweep.json");
  EXPECT_EQ(sweep["parameters"], json({"camera", "resolution"}));
  ASSERT_EQ(sweep["benches"].size(), 4u);
  std::map<std::string, double> first;  // camera -> coverage of box after view 1
  for (const json& b : sweep["benches"]) {
    const std::string folder = b["folder"];
    SCOPED_TRACE(folder);
    const json s = read_json_file(out / folder / "summary.json");
    EXPECT_EQ(s["settings"]["resolution_m"].get<double>(), std::stod(b["values"]["resolution"].get<std::string>()));
    EXPECT_EQ(s["settings"]["camera"], b["values"]["camera"]);
    EXPECT_EQ(s["pbnbv"]["runs"].size(), 1u);
    EXPECT_EQ(s["pbnbv"]["runs_complete"], 1);
    EXPECT_EQ(b["planners"]["pbnbv"]["coverage_by_view"], s["pbnbv"]["coverage_by_view"]);  // the table is the summaries'
    EXPECT_TRUE(fs::exists(out / folder / "report.md"));
    EXPECT_TRUE(fs::exists(out / folder / "logs" / "evaluate-box.log"));
    const double c = s["pbnbv"]["runs"]["box"]["coverage_by_view"][0].get<double>();
    // The resolution is the map's: with one camera, both resolutions' first views see the same.
    const std::string camera = b["values"]["camera"];
    if (first.count(camera)) {
      EXPECT_NEAR(c, first[camera], 0.5) << camera;
    }
    first[camera] = c;
  }
  EXPECT_EQ(first.size(), 2u);
  const std::string md = read_file(out / "sweep.md");
  EXPECT_NE(md.find("| d435 | 0.05 | pbnbv | 1 |"), std::string::npos) << md;
  EXPECT_NE(md.find("--resolution 0.03,0.05"), std::string::npos) << md;
  EXPECT_NE(md.find("--camera ideal,d435"), std::string::npos) << md;

  const CommandResult again = run_command(cmd);
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("0 scans to run of 4"), std::string::npos) << again.output;
  EXPECT_NE(again.output.find("0 to run (4 recorded from the same scans)"), std::string::npos) << again.output;
  EXPECT_EQ(again.output.find("started"), std::string::npos) << again.output;
  EXPECT_EQ(read_json_file(out / "sweep.json"), sweep);

  const CommandResult alone = run_command(netns_run() + " " + bin_dir() +
                                          "/pbnbv bench --objects box --planners pbnbv --views 2 --out " + out.string());
  EXPECT_EQ(alone.exit_code, 2) << alone.output;
  EXPECT_NE(alone.output.find("holds a sweep (sweep.json), not one benchmark"), std::string::npos) << alone.output;
}

// The oracle (pbnbv-scorer --truth-mesh, passed by pbnbv scan --planner oracle) on a box: from
// the same first view, its second view adds at least as much surface as a random one, and the
// summary, report and plot carry the random planner's gap to it.
TEST(Bench, OracleIsTheYardstick) {
  const fs::path out = fresh_dir("bench-oracle");
  const std::string cmd = netns_run() + " " + bin_dir() +
                          "/pbnbv bench --objects box --planners random,oracle --rig free --area full --views 2 --jobs 2 "
                          "--out " + out.string();
  const CommandResult r = run_command(cmd);
  ASSERT_EQ(r.exit_code, 0) << cmd << "\n" << r.output;
  const json s = read_json_file(out / "summary.json");
  const json& oracle = s.at("oracle")["runs"].at("box")["coverage_by_view"];
  const json& random = s.at("random")["runs"].at("box")["coverage_by_view"];
  ASSERT_EQ(oracle.size(), 2u);
  ASSERT_EQ(random.size(), 2u);
  EXPECT_NEAR(oracle[0].get<double>(), random[0].get<double>(), 0.5);  // the same first view
  EXPECT_GE(oracle[1].get<double>(), random[1].get<double>() - 0.5);
  EXPECT_GT(oracle[1].get<double>(), oracle[0].get<double>() + 10.0);  // a box: at least one new face
  const json& gap = s.at("random")["gap_to_oracle_by_view"];
  ASSERT_EQ(gap.size(), 2u);
  EXPECT_NEAR(gap[1].get<double>(), oracle[1].get<double>() - random[1].get<double>(), 1e-9);
  EXPECT_EQ(s.at("random")["gap_to_oracle_runs"], 1);
  // The scorer chose by the true surface.
  std::ifstream log(out / "oracle" / "box" / "logs" / "scorer.log");
  const std::string scorer((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_NE(scorer.find("new true surface samples"), std::string::npos) << scorer;
  std::ifstream md(out / "report.md");
  const std::string report((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
  EXPECT_NE(report.find("## Gap to the oracle"), std::string::npos);
  const cv::Mat img = cv::imread((out / "gap.png").string());
  EXPECT_EQ(img.cols, 960);
}

}  // namespace
