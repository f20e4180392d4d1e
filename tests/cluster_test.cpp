// pbnbv bench --slurm on a one-node Slurm cluster of this machine (scripts/slurm-local: munged,
// slurmctld, slurmd, real sbatch / squeue / scancel): the same results as a local run (the
// evaluation too run as Slurm tasks), a failing
// task reported with Slurm's reason while the others complete, a cancelled task run again and a
// rerun that runs nothing twice. The cluster is started once for the cases, which run one after
// another (one ctest test: Slurm's ports are the machine's).
#include <gtest/gtest.h>
#include <stdlib.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "process/processes.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using nlohmann::json;
using namespace pbnbv::testing;

namespace {

fs::path slurm_dir() { return fs::temp_directory_path() / "pbnbv-test-slurm"; }

class Cluster : public ::testing::Environment {
 public:
  void SetUp() override {
    const CommandResult r = run_command(source_dir() + "/scripts/slurm-local start " + slurm_dir().string());
    ASSERT_EQ(r.exit_code, 0) << "the one-node cluster did not start (scripts/test installs slurm-wlm and munge):\n"
                              << r.output;
    ::setenv("SLURM_CONF", (slurm_dir() / "slurm.conf").c_str(), 1);  // for the bench and squeue here
  }
  void TearDown() override { run_command(source_dir() + "/scripts/slurm-local stop " + slurm_dir().string()); }
};
const auto* const kCluster = ::testing::AddGlobalTestEnvironment(new Cluster);

std::string bench(const std::string& options, const fs::path& out) {
  return bin_dir() + "/pbnbv bench --rig free " + options + " --out " + out.string();
}

json summary(const fs::path& out) { return json::parse(read_file(out / "summary.json")); }

// summary.json's coverage per view of every run: planner -> run -> curve.
std::map<std::string, std::map<std::string, json>> curves(const json& s) {
  std::map<std::string, std::map<std::string, json>> out;
  for (const json& planner : s.at("planners")) {
    const json& runs = s.at(planner.get<std::string>()).at("runs");
    for (auto r = runs.begin(); r != runs.end(); ++r) out[planner.get<std::string>()][r.key()] = r.value().at("coverage_by_view");
  }
  return out;
}

}  // namespace

// 2 objects x 2 planners, 3 views on the free rig: run here (--jobs 2) and through Slurm (two
// tasks at once on the node's 2 CPUs), the coverage curves of summary.json are the same, bit for
// bit (free-rig scans are reproducible); every scan ran once (one task record each, exit 0).
TEST(SlurmBench, GivesTheSameCoverageAsTheSameBenchRunHere) {
  const fs::path dir = fresh_dir("cluster-same");
  const std::string options = "--objects bunny,sphere --planners pbnbv,pbnbv-paper --views 3";
  auto t0 = std::chrono::steady_clock::now();
  const CommandResult local = run_command(bench(options + " --jobs 2", dir / "local"));
  const double local_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(local.exit_code, 0) << local.output;
  t0 = std::chrono::steady_clock::now();
  const CommandResult slurm = run_command(bench(options + " --slurm", dir / "slurm"));
  const double slurm_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(slurm.exit_code, 0) << slurm.output;
  std::printf("the same bench: here %.1f s, through Slurm %.1f s (%.2fx)\n", local_s, slurm_s, slurm_s / local_s);
  EXPECT_NE(slurm.output.find("4 scans submitted to Slurm, job array "), std::string::npos) << slurm.output;
  // The evaluation too: one task per object, on the node, not in the launcher.
  EXPECT_NE(slurm.output.find("2 evaluations submitted to Slurm, job array "), std::string::npos) << slurm.output;
  for (const char* object : {"bunny", "sphere"}) {
    const json task = json::parse(read_file(dir / "slurm" / "evaluation" / object / "bench_task.json"));
    EXPECT_EQ(task.at("exit_code"), 0) << object;
    EXPECT_TRUE(fs::exists(dir / "slurm" / "evaluation" / object / "evaluation.json")) << object;
  }
  EXPECT_TRUE(fs::exists(dir / "slurm" / "slurm" / "evaluate-1.sh"));
  const auto a = curves(summary(dir / "local")), b = curves(summary(dir / "slurm"));
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a, b);
  for (const auto& [planner, runs] : b) {
    ASSERT_EQ(runs.size(), 2u) << planner;
    for (const auto& [run, curve] : runs) {
      EXPECT_EQ(curve.size(), 3u) << planner << " " << run;
      const json task = json::parse(read_file(dir / "slurm" / planner / run / "bench_task.json"));
      EXPECT_EQ(task.at("exit_code"), 0);
      const json record = json::parse(read_file(dir / "slurm" / planner / run / "bench_run.json"));
      EXPECT_TRUE(std::regex_match(record.at("slurm_job").get<std::string>(), std::regex(R"(\d+_[0-3])"))) << record;
    }
  }
  EXPECT_TRUE(summary(dir / "slurm").at("machine").contains("slurm"));
}

// A mesh that cannot be read fails its task: reported with Slurm's state and reason and the
// scan's own reason, submitted once more, failed again; the other object's scan completes.
TEST(SlurmBench, ATaskThatFailsIsReportedWithItsReasonAndTheOthersComplete) {
  const fs::path dir = fresh_dir("cluster-broken");
  std::ofstream(dir / "broken.obj") << "v 0 0 0\nf 1 2 3\n";  // a face of vertices that do not exist
  const CommandResult r =
      run_command(bench("--objects sphere," + (dir / "broken.obj").string() + " --planners pbnbv --views 2 --slurm", dir / "out"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("broken - pbnbv: FAILED (exit 2): Slurm: FAILED (NonZeroExitCode)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("broken - pbnbv: submitted once more"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("1 scans submitted to Slurm"), std::string::npos) << "the resubmission: " << r.output;
  EXPECT_NE(r.output.find("pbnbv bench: 1 scans did not complete"), std::string::npos) << r.output;
  const json runs = summary(dir / "out").at("pbnbv").at("runs");
  EXPECT_TRUE(runs.at("sphere").at("complete").get<bool>());
  EXPECT_FALSE(runs.at("broken").at("complete").get<bool>());
}

// A running task cancelled (scancel JOB_TASK) is submitted once more and completes; a rerun of
// the same command finds every scan complete and submits nothing; no scan ran twice to the end
// (each folder one scan of 10 views).
TEST(SlurmBench, ACancelledTaskRunsAgainAndARerunRunsNothingTwice) {
  const fs::path dir = fresh_dir("cluster-cancel");
  const std::string command = bench("--objects sphere,bunny --planners pbnbv --views 10 --slurm", dir / "out");
  std::vector<pbnbv::process::Child> kids(1);
  pbnbv::process::Child& b = kids[0];
  b.name = "bench";
  b.argv = {"sh", "-c", command};
  b.log_path = (dir / "bench.log").string();
  pbnbv::process::start(b);
  // The first task running: its id from squeue.
  std::string task;
  for (int i = 0; i < 600 && task.empty(); ++i) {
    const CommandResult q = run_command("squeue -h -r -t RUNNING -n pbnbv-bench -o %i");
    std::smatch m;
    if (std::regex_search(q.output, m, std::regex(R"((\d+_\d+))"))) task = m[1];
    if (task.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_FALSE(task.empty()) << "no task ran in 60 s:\n" << read_file(dir / "bench.log");
  std::this_thread::sleep_for(std::chrono::seconds(1));  // into its scan (10 views: about 12 s)
  const CommandResult cancel = run_command("scancel " + task);
  ASSERT_EQ(cancel.exit_code, 0) << cancel.output;
  for (int i = 0; i < 3000 && b.running; ++i) {
    pbnbv::process::reap(kids);
    if (b.running) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  const std::string log = read_file(dir / "bench.log");
  ASSERT_FALSE(b.running) << "the bench did not end in 300 s:\n" << log;
  EXPECT_EQ(b.exit_code, 0) << log;
  EXPECT_NE(log.find("Slurm: CANCELLED"), std::string::npos) << log;
  EXPECT_NE(log.find("submitted once more"), std::string::npos) << log;
  const CommandResult again = run_command(command);
  EXPECT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("(2 already complete"), std::string::npos) << again.output;
  EXPECT_EQ(again.output.find("submitted to Slurm"), std::string::npos) << again.output;  // neither scans nor evaluations
  for (const char* object : {"sphere", "bunny"}) {
    const json scan = json::parse(read_file(dir / "out" / "pbnbv" / object / "scan.json"));
    EXPECT_EQ(scan.at("views").size(), 10u) << object;
  }
}
