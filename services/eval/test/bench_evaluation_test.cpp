// The bench's evaluation task: a run's record back exactly (17 digits, NaN as null), a record
// field missing or of the wrong type named, a request naming a folder outside its bench refused,
// a scan that is not there recorded with its reason, and a record kept only while the scans it
// was made from are unchanged; a scan is resumed only from its record.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/io/json.hpp"
#include "eval/bench_evaluation.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv::eval {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

ObjectRun full_run() {
  ObjectRun r;
  r.object = "bunny";
  r.first_view = 2;
  r.initial_view = Eigen::Vector3d(0.1 + 0.2, -1.0 / 3.0, 0.7071067811865476);
  r.planner = PlannerKind::kPbnbvPaper;
  r.complete = true;
  r.coverage_by_view = {31.234567890123456, 1.0 / 3.0, 99.99999999999999};
  r.observable_by_view = {32.5, 2.0 / 3.0, 100.0};
  r.planner_ms = {4.1e-3, 12.25};
  r.planner_critical_ms = {3.5e-3, 0.1 + 0.2};
  r.views_to_95 = 3;
  r.views_done = 3;
  r.stop_reason = "budget";
  r.wall_s = 12.345678901234567;
  r.rig_time_by_view = {1.5, kNaN, 4.75};  // view 2 not measured in full
  r.rig_time = RigTime{2.25, 0.5, 0.1 + 0.2, 1e-300};
  r.new_surface_by_view = {100.0, kNaN, 0.015625};  // view 2 not merged
  r.stop_view = 2;
  r.stop_rule_reason = "views 2-3 each added less than 0.5 %";
  r.seconds_stop_view = std::nullopt;
  r.seconds_stop_reason = "";
  SurfaceMetrics m;
  m.model = "cloud";
  m.threshold_m = 0.005;
  m.accuracy = {1000, 0.00031, 0.0002, 0.0004, 0.0009, 0.002};
  m.completeness = {20000, 0.0011, 0.0007, 0.0015, 0.004, 0.03};
  m.precision = 0.99;
  m.recall = 0.875;
  m.f_score = 2 * 0.99 * 0.875 / (0.99 + 0.875);
  m.skipped_points = 3;
  r.cloud_metrics = m;
  r.rig_contacts = 2;
  r.rig_contact_list = {"view 3 (request 17): camera / turntable"};
  return r;
}

// Equal, NaN to NaN, bit for bit.
void expect_same(const std::vector<double>& a, const std::vector<double>& b, const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(a[i])) {
      EXPECT_TRUE(std::isnan(b[i])) << what << "[" << i << "]";
    } else {
      EXPECT_EQ(a[i], b[i]) << what << "[" << i << "]";
    }
  }
}

TEST(BenchEvaluation, ARunsRecordGivesItBackExactly) {
  const ObjectRun r = full_run();
  // Through text, as the task writes it and the launcher reads it.
  const ObjectRun b = run_from_record(json::parse(run_record(r).dump()));
  EXPECT_EQ(b.object, r.object);
  EXPECT_EQ(b.first_view, 2);
  ASSERT_TRUE(b.initial_view.has_value());
  EXPECT_EQ(*b.initial_view, *r.initial_view);
  EXPECT_EQ(b.planner, PlannerKind::kPbnbvPaper);
  EXPECT_TRUE(b.complete);
  expect_same(b.coverage_by_view, r.coverage_by_view, "coverage");
  expect_same(b.observable_by_view, r.observable_by_view, "observable");
  expect_same(b.planner_ms, r.planner_ms, "planner_ms");
  expect_same(b.planner_critical_ms, r.planner_critical_ms, "planner_critical_ms");
  EXPECT_EQ(b.views_to_95, 3);
  EXPECT_EQ(b.stop_reason, "budget");
  EXPECT_EQ(b.wall_s, r.wall_s);
  expect_same(b.rig_time_by_view, r.rig_time_by_view, "rig time");
  ASSERT_TRUE(b.rig_time.has_value());
  EXPECT_EQ(b.rig_time->capture_s, 0.1 + 0.2);
  EXPECT_EQ(b.rig_time->compute_s, 1e-300);
  expect_same(b.new_surface_by_view, r.new_surface_by_view, "new surface");
  EXPECT_EQ(b.stop_view, 2);
  EXPECT_EQ(b.stop_rule_reason, r.stop_rule_reason);
  EXPECT_FALSE(b.seconds_stop_view.has_value());
  ASSERT_TRUE(b.cloud_metrics.has_value());
  EXPECT_FALSE(b.mesh_metrics.has_value());
  EXPECT_EQ(b.cloud_metrics->completeness.p95_m, 0.004);
  EXPECT_EQ(b.cloud_metrics->accuracy.count, 1000u);
  EXPECT_EQ(b.cloud_metrics->f_score, r.cloud_metrics->f_score);
  EXPECT_EQ(b.cloud_metrics->skipped_points, 3u);
  EXPECT_EQ(b.rig_contacts, 2);
  EXPECT_EQ(b.rig_contact_list, r.rig_contact_list);
  // So the summary made from the records is the one made from the runs.
  EXPECT_EQ(run_record(b), run_record(r));

  // A run that failed: no figures, its error.
  ObjectRun failed;
  failed.object = "box";
  failed.error = "scan failed after 1 of 3 views: camera timed out";
  const ObjectRun f = run_from_record(json::parse(run_record(failed).dump()));
  EXPECT_FALSE(f.complete);
  EXPECT_EQ(f.error, failed.error);
  EXPECT_FALSE(f.initial_view.has_value());
  EXPECT_FALSE(f.rig_time.has_value());
  EXPECT_FALSE(f.views_to_95.has_value());
}

TEST(BenchEvaluation, ARecordsBadFieldIsNamed) {
  json j = run_record(full_run());
  j.erase("planner_ms");
  try {
    run_from_record(j);
    FAIL() << "a record without planner_ms was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "run planner_ms is missing");
  }
  j = run_record(full_run());
  j["coverage_by_view"][1] = "a third";
  EXPECT_THROW(
      {
        try {
          run_from_record(j);
        } catch (const std::invalid_argument& e) {
          EXPECT_EQ(std::string(e.what()), "run coverage_by_view holds a value that is not a number");
          throw;
        }
      },
      std::invalid_argument);
  j = run_record(full_run());
  j["cloud_metrics"]["accuracy"].erase("p95_m");
  EXPECT_THROW(
      {
        try {
          run_from_record(j);
        } catch (const std::invalid_argument& e) {
          EXPECT_EQ(std::string(e.what()), "run cloud_metrics accuracy p95_m is missing");
          throw;
        }
      },
      std::invalid_argument);
  j = run_record(full_run());
  j["planner"] = "telepathy";
  EXPECT_THROW(run_from_record(j), std::invalid_argument);
}

// The bench resumes an interrupted scan only when there is a record to continue from: a task
// cancelled while its scan started (processes.json and settings.json written, no scan.json yet)
// is started anew, as `pbnbv scan --resume` would refuse it ("cannot resume: ... scan.json does
// not exist") on every resubmission.
TEST(BenchEvaluation, AScanIsResumedOnlyFromItsRecord) {
  const fs::path dir = fs::temp_directory_path() / ("pbnbv_resumable_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  EXPECT_FALSE(scan_resumable(dir));
  std::ofstream(dir / "processes.json") << "{}";
  std::ofstream(dir / "settings.json") << "{}";
  EXPECT_FALSE(scan_resumable(dir));  // cancelled before the coordinator's first record
  std::ofstream(dir / "scan.json") << "{}";
  EXPECT_TRUE(scan_resumable(dir));
  EXPECT_FALSE(scan_complete(dir));  // a record, but not of a scan that is done
  fs::remove(dir / "settings.json");
  EXPECT_FALSE(scan_resumable(dir));
  fs::remove_all(dir);
}

class EvaluationTask : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pbnbv_evaluation_task_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    spec_.out = dir_ / "bench";
    job_.object = job_.name = job_.run = "sphere";
    job_.planner = PlannerKind::kPbnbv;
    job_.dir = spec_.out / "pbnbv" / "sphere";
    job_.log = spec_.out / "logs" / "pbnbv-sphere.log";
    fs::create_directories(job_.dir);
    task_ = spec_.out / "evaluation" / "sphere";
    fs::create_directories(task_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  void request(const ScanJob& j) { write_json_atomic(evaluation_request(spec_, {j}), (task_ / "request.json").string()); }
  std::string refusal() {
    std::ostringstream log;
    try {
      run_evaluation_task(task_ / "request.json", log);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_, task_;
  BenchSpec spec_;
  ScanJob job_;
};

TEST_F(EvaluationTask, AScanFolderOrLogOutsideTheBenchIsRefused) {
  ScanJob j = job_;
  j.dir = "/etc";
  request(j);
  EXPECT_NE(refusal().find("scans 0 dir /etc is not inside the bench folder " + spec_.out.string()), std::string::npos)
      << refusal();
  j = job_;
  j.dir = spec_.out / ".." / "elsewhere";
  request(j);
  EXPECT_NE(refusal().find("scans 0 dir"), std::string::npos) << refusal();
  j = job_;
  j.log = "relative.log";
  request(j);
  EXPECT_NE(refusal().find("scans 0 log"), std::string::npos) << refusal();
  EXPECT_FALSE(fs::exists(task_ / "evaluation.json"));
  // A request with a field out of range.
  json q = evaluation_request(spec_, {job_});
  q["views"] = 0;
  write_json_atomic(q, (task_ / "request.json").string());
  EXPECT_NE(refusal().find("views"), std::string::npos) << refusal();
  EXPECT_NE(refusal().find("views = 0 is not a whole number in"), std::string::npos) << refusal();
  q = evaluation_request(spec_, {job_});
  q["scans"] = json::array();
  write_json_atomic(q, (task_ / "request.json").string());
  EXPECT_NE(refusal().find("scans is not a list of 1 to 1000 scans"), std::string::npos) << refusal();
}

TEST_F(EvaluationTask, AScanThatIsNotThereIsRecordedWithItsReasonAndTheRecordIsKeptWhileTheScanIsUnchanged) {
  request(job_);
  EXPECT_FALSE(evaluation_current(task_));  // no record yet
  EXPECT_EQ(refusal(), "");
  std::string error;
  const std::optional<ObjectEvaluation> e = read_evaluation(task_, &error);
  ASSERT_TRUE(e.has_value()) << error;
  EXPECT_EQ(e->object, "sphere");
  EXPECT_EQ(e->observable, "");  // no complete scan: no mask made
  ASSERT_EQ(e->runs.size(), 1u);
  EXPECT_FALSE(e->runs[0].complete);
  EXPECT_NE(e->runs[0].error.find("no scan.json and no log"), std::string::npos) << e->runs[0].error;
  EXPECT_TRUE(evaluation_current(task_));
  // The same request written again (a rerun): still current.
  request(job_);
  EXPECT_TRUE(evaluation_current(task_));
  // A file of the scan changes: the record is no longer the scan's.
  std::ofstream(job_.dir / "scan.json") << "{}";
  request(job_);
  EXPECT_FALSE(evaluation_current(task_));
  // Other settings: neither.
  EXPECT_EQ(refusal(), "");
  EXPECT_TRUE(evaluation_current(task_));
  spec_.stop_rule.window = 3;
  request(job_);
  EXPECT_FALSE(evaluation_current(task_));
  // A record that is not one.
  std::ofstream(task_ / "evaluation.json") << "{\"kind\": \"something else\"}";
  EXPECT_FALSE(read_evaluation(task_, &error).has_value());
  EXPECT_NE(error.find("not an evaluation record"), std::string::npos) << error;
}

}  // namespace
}  // namespace pbnbv::eval
