// Faults a scan must survive or report (ctest label `faults`): other scans and foreign traffic on
// the same bus, a launcher killed without warning (and its folder resumed: with a command planted
// in processes.json, and as a copy), a folder that already holds a scan, objects
// no rig can scan, and the main job's log. Every scan runs the real processes on a real LCM bus;
// the checks are figures (distances to the true surface, coverage, counts), not only exit codes.
// Coverage comes from eval::evaluate_coverage: the figures of evaluate_scan without its surface
// metrics, which no case here reads (they were most of each evaluation's time).
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "bus/log_audit.hpp"
#include "bus/scan_log_views.hpp"
#include "bus/rig_log.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "eval/evaluate.hpp"
#include "scan_checks.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;

namespace {

// `pbnbv scan OPTIONS --out OUT`, its output to OUT.stdout, as a shell command. The stop rule is
// off: these tests count views against the budget.
std::string scan_command(const fs::path& out, const std::string& options) {
  return bin_dir() + "/pbnbv scan " + options + " --stop-rule off --out " + out.string() + " > " + out.string() + ".stdout 2>&1";
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Lines of the scan's service logs that say a message of another scan was ignored.
int ignored_lines(const fs::path& out) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(out / "logs")) {
    const std::string log = read_text(e.path());
    for (std::size_t at = log.find("ignored a message"); at != std::string::npos; at = log.find("ignored a message", at + 1)) ++n;
  }
  return n;
}

// True while `pid` is a live process (a zombie is not: it only waits to be reaped).
bool alive(int pid) {
  if (::kill(pid, 0) != 0) return false;
  const std::string stat = read_text("/proc/" + std::to_string(pid) + "/stat");
  const std::size_t close = stat.rfind(')');
  return close != std::string::npos && close + 2 < stat.size() && stat[close + 2] != 'Z';
}

constexpr const char* kRing = "--planner ring --rig arm --views 4 --sim-speed 20 --no-log";

}  // namespace

// Two scans of different objects at once on one bus: each cloud lies on its own object's surface
// (28 % of one scan's points came from the other object before scans were told apart), and each
// covers what it covers alone.
TEST(Faults, TwoScansAtOnceOnOneBusEachKeepTheirOwnObject) {
  const fs::path dir = fresh_dir("two-scans");
  const fs::path sphere = dir / "sphere", box = dir / "box", alone = dir / "sphere-alone";
  const CommandResult together = run_command(netns_run() + " sh -c '" + scan_command(sphere, std::string("--object sphere ") + kRing) +
                                             " & " + scan_command(box, std::string("--object box ") + kRing) +
                                             " & wait %1; a=$?; wait %2; b=$?; exit $((a + b))'");
  ASSERT_EQ(together.exit_code, 0) << together.output << read_text(sphere.string() + ".stdout")
                                   << read_text(box.string() + ".stdout");
  const CommandResult solo = run_command(netns_run() + " sh -c '" + scan_command(alone, std::string("--object sphere ") + kRing) + "'");
  ASSERT_EQ(solo.exit_code, 0) << read_text(alone.string() + ".stdout");

  for (const fs::path& out : {sphere, box}) {
    const auto scan = read_json_file(out / "scan.json");
    EXPECT_EQ(scan["status"]["state"], "done") << out;
    EXPECT_EQ(scan["views"].size(), 4u) << out;
    const Distances d = cloud_to_mesh(out / "cloud.ply", out / "object.obj");
    std::cout << out.filename().string() << " with another scan on the bus: " << d.n << " points, median " << d.median * 1e3
              << " mm, 95th percentile " << d.p95 * 1e3 << " mm from its own surface; " << ignored_lines(out)
              << " log lines on ignored messages\n";
    EXPECT_LT(d.median, 0.1e-3) << out;  // 0.008 mm alone (docs/benchmark.md)
    EXPECT_LT(d.p95, 0.5e-3) << out;     // one point in 20 of the other object would break this
    EXPECT_GT(ignored_lines(out), 0) << "the other scan's traffic never reached " << out << "'s services?";
  }
  EXPECT_NE(read_json_file(sphere / "scan.json")["settings"]["scan_id"], read_json_file(box / "scan.json")["settings"]["scan_id"]);
  const double c_together = eval::evaluate_coverage(sphere).coverage_by_view.back();
  const double c_alone = eval::evaluate_coverage(alone).coverage_by_view.back();
  std::cout << "sphere coverage after 4 views: " << c_together << " % with another scan on the bus, " << c_alone << " % alone\n";
  EXPECT_NEAR(c_together, c_alone, 1.0);
}

// A recorded scan of another object played onto the bus while a scan runs (every channel: its
// rig statuses, depth frames, clouds, registered clouds, maps): nothing of it reaches the scan.
TEST(Faults, AnotherScansTrafficChangesNothing) {
  const fs::path dir = fresh_dir("foreign");
  const fs::path recorded = dir / "recorded", scan = dir / "scan", alone = dir / "alone";
  const std::string ring_with_log = "--planner ring --rig arm --views 4 --sim-speed 20";
  ASSERT_EQ(run_command(netns_run() + " sh -c '" + scan_command(recorded, "--object box " + ring_with_log) + "'").exit_code, 0)
      << read_text(recorded.string() + ".stdout");
  // The recording played four times over at twice its speed, from before the scan starts to after
  // it ends.
  const std::string play = "for i in 1 2 3 4; do lcm-logplayer -s 2 " + (recorded / "scan.lcmlog").string() + "; done";
  const CommandResult r = run_command(netns_run() + " sh -c '(" + play + ") & p=$!; sleep 1; " +
                                      scan_command(scan, std::string("--object sphere ") + kRing) + "; s=$?; kill $p; exit $s'");
  ASSERT_EQ(r.exit_code, 0) << r.output << read_text(scan.string() + ".stdout");
  ASSERT_EQ(run_command(netns_run() + " sh -c '" + scan_command(alone, std::string("--object sphere ") + kRing) + "'").exit_code, 0);

  const auto s = read_json_file(scan / "scan.json");
  EXPECT_EQ(s["status"]["state"], "done");
  ASSERT_EQ(s["views"].size(), 4u);
  for (const auto& v : s["views"]) EXPECT_TRUE(v["registration"]["accepted"].get<bool>()) << v["registration"].dump();
  const Distances d = cloud_to_mesh(scan / "cloud.ply", scan / "object.obj");
  const Distances d_alone = cloud_to_mesh(alone / "cloud.ply", alone / "object.obj");
  std::cout << "sphere scanned while a box scan is replayed: " << d.n << " points (alone " << d_alone.n << "), median "
            << d.median * 1e3 << " mm (alone " << d_alone.median * 1e3 << " mm); " << ignored_lines(scan)
            << " log lines on ignored messages\n";
  EXPECT_LT(d.median, 0.1e-3);
  EXPECT_LT(d.p95, 0.5e-3);
  EXPECT_NEAR(static_cast<double>(d.n), static_cast<double>(d_alone.n), 0.01 * d_alone.n);
  EXPECT_GT(ignored_lines(scan), 0);
  EXPECT_NEAR(eval::evaluate_coverage(scan).coverage_by_view.back(), eval::evaluate_coverage(alone).coverage_by_view.back(), 1.0);
}

// 1 % and 5 % of the LCM port's UDP packets dropped at random (nftables in the namespace): the
// scan completes every view with the coverage of a clean run; at 1 % in at most twice its time.
// (At 1 % a raw 1.8 MB depth frame, 28 fragments, is lost one time in four; each loss cost a 10 s
// trigger timeout and lost REGISTERED_CLOUD / VOXEL_MAP answers were never asked for again.)
// The three scans run at once, each in its own namespace: the clean and the lossy scan share
// whatever else loads the machine, so the ratio of their wall times holds beside other tests.
TEST(Faults, PacketLossOfOneAndFivePercentCostsNoViewAndNoCoverage) {
  const fs::path dir = fresh_dir("loss");
  // At the default --sim-speed (4), as a user runs it.
  const std::string ring10 = "--object bunny --planner ring --rig arm --views 10 --no-log";
  struct Run {
    int loss;
    double wall_s = 0;
    CommandResult result;
  };
  std::vector<Run> runs(3);
  runs[0].loss = 0;
  runs[1].loss = 1;
  runs[2].loss = 5;
  std::vector<std::thread> threads;
  for (Run& run : runs) {
    threads.emplace_back([&run, &dir, &ring10] {
      const fs::path out = dir / ("loss" + std::to_string(run.loss));
      const auto t0 = std::chrono::steady_clock::now();
      run.result = run_command(netns_run() + " --loss " + std::to_string(run.loss) + " sh -c '" + scan_command(out, ring10) + "'");
      run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    });
  }
  for (std::thread& t : threads) t.join();
  std::vector<std::vector<double>> coverage;
  for (const Run& run : runs) {
    const fs::path out = dir / ("loss" + std::to_string(run.loss));
    ASSERT_EQ(run.result.exit_code, 0) << "at " << run.loss << " % loss: " << run.result.output
                                       << read_text(out.string() + ".stdout");
    coverage.push_back(eval::evaluate_coverage(out).coverage_by_view);
    const int views = read_json_file(out / "scan.json")["status"]["views_done"].get<int>();
    std::cout << run.loss << " % packet loss: " << views << " views in " << run.wall_s << " s, coverage after view 10 "
              << (coverage.back().empty() ? 0.0 : coverage.back().back()) << " %\n";
    EXPECT_EQ(views, 10) << run.loss << " %";
    ASSERT_EQ(coverage.back().size(), 10u) << run.loss << " %";
    EXPECT_NEAR(coverage.back().back(), coverage.front().back(), 1.0) << run.loss << " %";
  }
  EXPECT_LE(runs[1].wall_s, 2.0 * runs[0].wall_s) << "1 % loss took " << runs[1].wall_s << " s against " << runs[0].wall_s;
}

// SIGKILL of each service (and of the twin) in a 10-view NBV scan on the arm rig, four per scan
// (once views 2, 4, 6 and 8 are recorded: each restarted before the next), and SIGSTOP of the mapping
// service at view 3: the launcher starts each again (a stopped one once its heartbeat has been
// missing for 10 s), the restarted service continues from the scan's folder and the
// coordinator's re-sent requests, and the scan completes every view with the coverage of an
// undisturbed run. (lcm-logger: AKilledLoggerGoesOnInASecondFileAndTheAuditSaysWhatItLacks.)
namespace {

// `pbnbv scan` of a 10-view bunny scan on the arm rig (small images; at --sim-speed 20 unless
// recorded: lcm-logger keeps up with the twin's statuses at the default 4x, at 20x it lost some)
// into dir/<victims joined by '+'>, in its own network namespace; SIGNAL sent to victims[k] (by
// its processes.json pid) once view 2 + 2k is recorded (one victim: view 3).
fs::path run_killing(const fs::path& dir, const std::vector<std::string>& victims, int sig = SIGKILL, bool log = false) {
  std::string name = victims.empty() ? std::string("undisturbed") : victims[0];
  for (std::size_t k = 1; k < victims.size(); ++k) name += "+" + victims[k];
  const fs::path out = dir / (name + (sig == SIGKILL ? "" : "-stopped"));
  const std::string scan10 = std::string("--object bunny --rig arm --views 10 ") + kSmallImageOptions +
                             (log ? "" : " --no-log --sim-speed 20");
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = netns_run() + " " + scan_command(out, scan10);
    ::execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  for (std::size_t k = 0; k < victims.size(); ++k) {
    const int view = victims.size() == 1 ? 3 : 2 + 2 * static_cast<int>(k);
    EXPECT_TRUE(wait_for_views(out, view, 120)) << victims[k] << ": " << read_text(out.string() + ".stdout");
    int victim_pid = -1;
    const nlohmann::json procs_json = read_json_file(out / "processes.json");
    for (const auto& p : procs_json["processes"]) {
      if (p["name"] == victims[k]) victim_pid = p["pid"].get<int>();
    }
    EXPECT_GT(victim_pid, 0) << victims[k];
    if (victim_pid > 0) ::kill(victim_pid, sig);
  }
  EXPECT_EQ(wait_exit(pid, 300), 0) << name << ": " << read_text(out.string() + ".stdout");
  return out;
}

// How often processes.json says `name` was started again.
int restarts_of(const fs::path& out, const std::string& name) {
  int restarts = -1;
  const nlohmann::json procs_json = read_json_file(out / "processes.json");
  for (const auto& p : procs_json["processes"]) {
    if (p["name"] == name) restarts = p["restarts"].get<int>();
  }
  return restarts;
}

}  // namespace

TEST(Faults, EachKilledServiceIsRestartedAndTheScanCompletes) {
  const fs::path dir = fresh_dir("killed-service");
  const fs::path undisturbed = run_killing(dir, {});
  const std::vector<double> reference = eval::evaluate_coverage(undisturbed).coverage_by_view;
  ASSERT_EQ(reference.size(), 10u);
  const std::vector<std::vector<std::string>> groups = {{"twin", "motion", "camera", "registration"},
                                                        {"mapping", "ellipsoids", "scorer", "coordinator"}};
  for (const std::vector<std::string>& victims : groups) {
    const fs::path out = run_killing(dir, victims);
    const auto scan = read_json_file(out / "scan.json");
    const std::vector<double> coverage = eval::evaluate_coverage(out).coverage_by_view;
    const std::string name = out.filename().string();
    std::cout << name << " killed at views 2, 4, 6 and 8: " << scan["status"]["views_done"] << " views in "
              << scan["status"]["elapsed_s"].get<double>() << " s, coverage after view 10 "
              << (coverage.empty() ? 0.0 : coverage.back()) << " % (undisturbed " << reference.back() << " %), restarts";
    for (const std::string& victim : victims) std::cout << " " << restarts_of(out, victim);
    std::cout << "\n";
    EXPECT_EQ(scan["status"]["state"], "done") << name;
    EXPECT_EQ(scan["status"]["views_done"], 10) << name;
    for (const std::string& victim : victims) EXPECT_EQ(restarts_of(out, victim), 1) << victim;
    ASSERT_EQ(coverage.size(), 10u) << name;
    EXPECT_NEAR(coverage.back(), reference.back(), 1.0) << name;
  }
  // Hung, not dead: SIGSTOP (never continued). Its heartbeat stops; 10 s later the launcher kills
  // it and starts it again.
  const fs::path hung = run_killing(dir, {"mapping"}, SIGSTOP);
  const auto s2 = read_json_file(hung / "scan.json");
  const std::vector<double> c2 = eval::evaluate_coverage(hung).coverage_by_view;
  std::cout << "mapping stopped (SIGSTOP) at view 3: " << s2["status"]["views_done"] << " views in "
            << s2["status"]["elapsed_s"].get<double>() << " s, coverage after view 10 " << (c2.empty() ? 0.0 : c2.back())
            << " %\n";
  EXPECT_EQ(s2["status"]["views_done"], 10);
  EXPECT_EQ(restarts_of(hung, "mapping"), 1);
  ASSERT_EQ(c2.size(), 10u);
  EXPECT_NEAR(c2.back(), reference.back(), 1.0);
  EXPECT_NE(read_text(hung.string() + ".stdout").find("mapping sent no heartbeat for"), std::string::npos);
}

// SIGKILL of lcm-logger once view 3 is recorded: the launcher starts it again and it goes on in
// scan.lcmlog.00. lcm-logger writes from a queue and flushes every 100 ms, so what it had received
// and not yet written when killed (view 3's last message, at most) is gone: the launcher's audit
// must say exactly what the two files lack, and they must hold every message of views 4 to 10.
TEST(Faults, AKilledLoggerGoesOnInASecondFileAndTheAuditSaysWhatItLacks) {
  const fs::path out = run_killing(fresh_dir("killed-logger"), {"lcm-logger"}, SIGKILL, true);
  const auto scan = read_json_file(out / "scan.json");
  EXPECT_EQ(scan["status"]["state"], "done");
  EXPECT_EQ(scan["status"]["views_done"], 10);
  EXPECT_EQ(restarts_of(out, "lcm-logger"), 1);
  const std::vector<std::string> files = bus::scan_log_files(out.string());
  ASSERT_EQ(files.size(), 2u);
  const std::string scan_id = read_json_file(out / "processes.json")["scan_id"].get<std::string>();
  const std::vector<bus::ViewMessages> views = bus::view_messages(read_scan_record(out));
  ASSERT_EQ(views.size(), 10u);
  const std::vector<std::string> lacking = bus::missing_from_log(bus::read_scan_logs(files, scan_id), views);
  for (const std::string& line : lacking) {
    const int view = std::stoi(line.substr(5));  // "view 3: VOXEL_MAP"
    EXPECT_LE(view, 3) << line;                    // nothing sent after the restart is lost
  }
  // The second file alone holds views 4 to 10 whole.
  const std::vector<bus::ViewMessages> later(views.begin() + 3, views.end());
  EXPECT_TRUE(bus::missing_from_log(bus::read_scan_log(files[1], scan_id), later).empty());
  const std::string stdout_text = read_text(out.string() + ".stdout");
  if (lacking.empty()) {
    EXPECT_NE(stdout_text.find("scan.lcmlog (2 files): "), std::string::npos) << stdout_text;
    EXPECT_NE(stdout_text.find("every depth frame, cloud, registered cloud and map of the 10 views"), std::string::npos)
        << stdout_text;
  } else {
    std::cout << "lcm-logger lost " << lacking.size() << " message(s) it held when killed: " << lacking.front() << "\n";
    EXPECT_NE(stdout_text.find("warning: scan.lcmlog lacks " + std::to_string(lacking.size()) + " of the scan's messages"),
              std::string::npos)
        << stdout_text;
    for (const std::string& line : lacking) EXPECT_NE(stdout_text.find("    " + line), std::string::npos) << line;
  }
}

// SIGKILL of the launcher: the kernel stops every process it started (none is left after 2 s)
// and the coordinator records why the scan stopped; `pbnbv scan --resume` then completes the scan
// from its folder with the coverage of an uninterrupted one.
TEST(Faults, AKilledLauncherLeavesNoProcessBehindAndTheScanResumes) {
  const fs::path out = fresh_dir("killed-launcher") / "scan";
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = netns_run() + " " + scan_command(out, "--object sphere --planner ring --views 8 --sim-speed 2");
    ::execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ASSERT_TRUE(wait_for_views(out, 1, 60)) << read_text(out.string() + ".stdout");
  // First the coordinator dies and is restarted with --resume (processes.json then records that
  // argument): the later `--resume` of the whole scan must not give it twice.
  const nlohmann::json first = read_json_file(out / "processes.json");
  for (const auto& p : first["processes"]) {
    if (p["name"] == "coordinator") ::kill(p["pid"].get<int>(), SIGKILL);
  }
  ASSERT_TRUE(wait_for_views(out, 2, 60)) << read_text(out.string() + ".stdout");
  const auto procs = read_json_file(out / "processes.json");
  ASSERT_EQ(procs["launcher_pid"].get<int>(), pid);  // netns-run and sh exec the launcher
  std::vector<int> pids;
  for (const auto& p : procs["processes"]) pids.push_back(p["pid"].get<int>());
  ASSERT_GE(pids.size(), 5u);
  for (int p : pids) ASSERT_TRUE(alive(p)) << p;

  ::kill(pid, SIGKILL);
  EXPECT_EQ(wait_exit(pid, 5), 128 + SIGKILL);
  const auto t0 = std::chrono::steady_clock::now();
  int left = static_cast<int>(pids.size());
  while (left > 0 && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(2)) {
    left = 0;
    for (int p : pids) left += alive(p) ? 1 : 0;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const double gone_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cout << pids.size() << " processes, all gone " << gone_s << " s after the launcher's SIGKILL\n";
  EXPECT_EQ(left, 0) << "processes still running 2 s after the launcher died";
  const auto scan = read_json_file(out / "scan.json");
  EXPECT_EQ(scan["status"]["state"], "stopped");
  EXPECT_NE(scan["status"]["message"].get<std::string>().find("the launcher (pid " + std::to_string(pid) + ") died"),
            std::string::npos)
      << scan["status"].dump();
  EXPECT_GE(scan["status"]["views_done"].get<int>(), 1);

  const int before = scan["status"]["views_done"].get<int>();
  const CommandResult resumed = run_command(netns_run() + " " + bin_dir() + "/pbnbv scan --resume " + out.string());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  const auto done = read_json_file(out / "scan.json");
  EXPECT_EQ(done["status"]["state"], "done");
  EXPECT_EQ(done["status"]["views_done"], 8);
  ASSERT_EQ(done["views"].size(), 8u);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(done["views"][i]["view"], i + 1);  // counted from 1
  // The uninterrupted scan, for comparison.
  const fs::path whole = out.parent_path() / "whole";
  ASSERT_EQ(run_command(netns_run() + " " + scan_command(whole, "--object sphere --planner ring --views 8 --sim-speed 20"))
                .exit_code,
            0);
  const double c_resumed = eval::evaluate_coverage(out).coverage_by_view.back();
  const double c_whole = eval::evaluate_coverage(whole).coverage_by_view.back();
  std::cout << "killed after " << before << " views, resumed: " << c_resumed << " % after 8 views (uninterrupted "
            << c_whole << " %)\n";
  EXPECT_NEAR(c_resumed, c_whole, 1.0);
  // Resuming a complete scan does nothing.
  const CommandResult again = run_command(bin_dir() + "/pbnbv scan --resume " + out.string());
  EXPECT_EQ(again.exit_code, 0);
  EXPECT_NE(again.output.find("nothing to resume"), std::string::npos) << again.output;
}

namespace {

// Starts `pbnbv scan OPTIONS` into `out`, lets it record `views` views, then kills the launcher
// (SIGKILL: the kernel stops what it started) and waits until scan.json says "stopped" and none of
// its processes runs: a folder to resume.
void scan_then_kill_launcher(const fs::path& out, const std::string& options, std::size_t views) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = netns_run() + " " + scan_command(out, options);
    ::execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ASSERT_TRUE(wait_for_views(out, views, 180)) << read_text(out.string() + ".stdout");
  std::vector<int> pids;
  for (const auto& p : read_json_file(out / "processes.json")["processes"]) pids.push_back(p["pid"].get<int>());
  ::kill(pid, SIGKILL);
  ASSERT_EQ(wait_exit(pid, 5), 128 + SIGKILL);
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  const auto stopped = [&] {
    for (int p : pids) if (alive(p)) return false;
    try {
      return read_json_file(out / "scan.json")["status"]["state"] == "stopped";
    } catch (const std::exception&) {  // being replaced
      return false;
    }
  };
  while (!stopped() && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_TRUE(stopped()) << "the killed launcher's scan did not stop: " << read_json_file(out / "scan.json")["status"].dump();
  ASSERT_LT(read_json_file(out / "scan.json")["status"]["views_done"].get<int>(), 10) << "the scan ended before the kill";
}

// Every file under `dir` (path relative to it) with its size and modification time.
std::map<std::string, std::pair<std::uintmax_t, fs::file_time_type>> files_of(const fs::path& dir) {
  std::map<std::string, std::pair<std::uintmax_t, fs::file_time_type>> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) files[fs::relative(e.path(), dir).string()] = {e.file_size(), e.last_write_time()};
  }
  return files;
}

}  // namespace

// processes.json is a record: a command planted in it (every process's argv wrapped in a shell
// that first touches a file) does not run on `pbnbv scan --resume`, which builds every command
// again from settings.json and completes the scan. (Before: the planted command ran and the
// resume returned 0.)
TEST(Faults, ResumeNeverRunsTheCommandsOfProcessesJson) {
  const fs::path out = fresh_dir("planted") / "scan";
  scan_then_kill_launcher(out, "--object sphere --planner ring --rig arm --views 10 --sim-speed 4 --no-log", 2);
  if (HasFatalFailure()) return;
  const fs::path planted = fs::temp_directory_path() / ("pbnbv-pwned-" + std::to_string(::getpid()) + "-" +
                                                        std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()));
  nlohmann::json procs = read_json_file(out / "processes.json");
  for (auto& p : procs["processes"]) {
    std::vector<std::string> argv = {"/bin/sh", "-c", "touch " + planted.string() + "; exec \"$0\" \"$@\""};
    for (const auto& a : p["argv"]) argv.push_back(a.get<std::string>());
    p["argv"] = argv;
  }
  std::ofstream(out / "processes.json") << procs.dump(2);

  const CommandResult resumed = run_command(netns_run() + " " + bin_dir() + "/pbnbv scan --resume " + out.string());
  const bool ran = fs::exists(planted);
  fs::remove(planted);
  EXPECT_FALSE(ran) << "the command planted in processes.json ran";
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  const auto done = read_json_file(out / "scan.json");
  EXPECT_EQ(done["status"]["state"], "done");
  EXPECT_EQ(done["status"]["views_done"], 10);
  // The record now holds the commands that ran: the programs themselves, no shell.
  for (const auto& p : read_json_file(out / "processes.json")["processes"]) {
    const fs::path program = p["argv"][0].get<std::string>();
    EXPECT_EQ(program.filename(), "pbnbv-" + p["name"].get<std::string>()) << p.dump();
  }
}

// A copy of an interrupted scan's folder, resumed, completes in the copy (10 of 10 views, the
// resumed views' plan figures in the copy's plans/) and leaves the original as it was: every file
// with its size and time, scan.json still "stopped". (Before: the processes were started with the
// original's --out, wrote into it, and the copy stayed "stopped" with exit code 0.)
TEST(Faults, AResumedCopyCompletesInTheCopyAndLeavesTheOriginalAlone) {
  const fs::path dir = fresh_dir("copied");
  const fs::path original = dir / "original", copy = dir / "copy";
  scan_then_kill_launcher(original, "--object bunny --rig free --views 10 --sim-speed 4 --no-log", 3);
  if (HasFatalFailure()) return;
  const int before = read_json_file(original / "scan.json")["status"]["views_done"].get<int>();
  fs::copy(original, copy, fs::copy_options::recursive);
  const auto original_files = files_of(original);
  const std::string original_scan = read_text(original / "scan.json");

  const CommandResult resumed = run_command(netns_run() + " " + bin_dir() + "/pbnbv scan --resume " + copy.string());
  EXPECT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_TRUE(read_text(original / "scan.json") == original_scan)
      << "the original's scan.json changed: " << read_json_file(original / "scan.json")["status"].dump();
  EXPECT_TRUE(files_of(original) == original_files) << "files of the original were written or added";
  EXPECT_FALSE(fs::exists(original / "plans" / "view_010.png"));
  const auto done = read_json_file(copy / "scan.json");
  EXPECT_EQ(done["status"]["state"], "done") << done["status"].dump();
  EXPECT_EQ(done["status"]["views_done"], 10);
  EXPECT_TRUE(fs::exists(copy / "plans" / "view_010.png")) << "the last plan's figure, drawn into the copy";
  ASSERT_EQ(done["views"].size(), 10u);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(done["views"][i]["view"], i + 1);
  std::cout << "original stopped after " << before << " views; its copy resumed to "
            << done["status"]["views_done"] << " views, the original unchanged\n";
}

// `pbnbv stop` in the middle of a move: the motion executor holds the arm where it is (the twin's
// arm is still within a few status periods), the scan ends "stopped" with the reason and keeps
// the views it has.
TEST(Faults, StopMidMoveHaltsTheRigAndTheScanKeepsWhatItHas) {
  const fs::path out = fresh_dir("stop") / "scan";
  const std::string scan = scan_command(out, "--object sphere --planner ring --views 8 --sim-speed 1");
  // In one namespace: the scan, and `pbnbv stop` 0.5 s after the first view is recorded (the
  // 45-degree move to view 2 takes about 1.2 s at --sim-speed 1).
  const std::string wait_view = "until [ -f " + out.string() + "/scan.json ] && grep -q '\"frame_file\"' " + out.string() +
                                "/scan.json; do sleep 0.02; done";
  const CommandResult r = run_command(netns_run() + " sh -c '" + scan + " & p=$!; " + wait_view + "; sleep 0.5; " +
                                      bin_dir() + "/pbnbv stop --reason \"operator abort\"; wait $p; echo scan exit $?'");
  EXPECT_NE(r.output.find("scan exit 130"), std::string::npos) << r.output << read_text(out.string() + ".stdout");
  const auto j = read_json_file(out / "scan.json");
  EXPECT_EQ(j["status"]["state"], "stopped");
  EXPECT_EQ(j["status"]["message"], "operator abort (STOP)");
  EXPECT_GE(j["status"]["views_done"].get<int>(), 1);
  EXPECT_LT(j["status"]["views_done"].get<int>(), 8);
  EXPECT_NE(read_text(out / "logs" / "motion.log").find("STOP (operator abort): holding the rig"), std::string::npos);
  // The log: from 50 ms after STOP (5 status periods at --sim-speed 1) the arm's statuses show it
  // still.
  lcm::LogFile log((out / "scan.lcmlog").string(), "r");
  ASSERT_TRUE(log.good());
  int64_t stop_at = -1, still_from = -1;
  double speed_after = 0;
  int statuses_after = 0;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel == "STOP" && stop_at < 0) stop_at = e->timestamp;
    if (e->channel == "ARM_STATUS" && stop_at >= 0 && e->timestamp > stop_at + 50000) {
      arm_status_t s;
      if (!bus::decode_logged(*e, &s)) continue;
      double v = 0;
      for (double q : s.joint_velocity_rad_s) v = std::max(v, std::abs(q));
      speed_after = std::max(speed_after, v);
      ++statuses_after;
      if (still_from < 0) still_from = e->timestamp;
    }
  }
  ASSERT_GE(stop_at, 0) << "no STOP in the log";
  EXPECT_GT(statuses_after, 0);
  std::cout << "after STOP: " << statuses_after << " arm statuses from 50 ms on, largest joint speed " << speed_after
            << " rad/s\n";
  EXPECT_LT(speed_after, 1e-6);
}

// A folder that holds a scan is not mixed with a new one; --overwrite empties it first.
TEST(Faults, AFolderThatHoldsAScanIsRefusedUnlessOverwritten) {
  const fs::path out = fresh_dir("reused");
  std::ofstream(out / "scan.json") << "{}";
  fs::create_directories(out / "frames");
  const CommandResult refused = run_command(bin_dir() + "/pbnbv scan --object sphere --out " + out.string());
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.output.find("--out " + out.string() + " is not empty (frames, scan.json)"), std::string::npos)
      << refused.output;
  EXPECT_NE(refused.output.find("--overwrite"), std::string::npos) << refused.output;
  EXPECT_EQ(read_text(out / "scan.json"), "{}");  // untouched

  const CommandResult r = run_command(netns_run() + " " + bin_dir() + "/pbnbv scan --object sphere " + kRing +
                                      " --overwrite --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_json_file(out / "scan.json")["status"]["state"], "done");
}

// Objects no rig can scan are refused before anything starts, naming the file and the limit.
TEST(Faults, ObjectsNoRigCanScanAreRefusedUpFront) {
  const fs::path dir = fresh_dir("limits");
  // A 0.3 m square sheet 1 um thick (it would be scaled to a 90 km object).
  std::ofstream(dir / "sheet.obj") << "v 0 0 0\nv 0.3 0 0\nv 0.3 0.3 0\nv 0 0.3 0\n"
                                      "v 0 0 1e-6\nv 0.3 0 1e-6\nv 0.3 0.3 1e-6\nv 0 0.3 1e-6\n"
                                      "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
                                      "f 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";
  std::ofstream(dir / "triangle.obj") << "v 0 0 0\nv 0.3 0 0.1\nv 0 0.3 0.2\nf 1 2 3\n";
  for (const char* name : {"sheet.obj", "triangle.obj"}) {
    const auto t0 = std::chrono::steady_clock::now();
    const CommandResult r = run_command(bin_dir() + "/pbnbv scan --object " + (dir / name).string() + " --out " +
                                        (dir / (std::string(name) + "-out")).string());
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find((dir / name).string() + "' is flat"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("Usage"), std::string::npos) << r.output;  // an error, not a usage text
    EXPECT_LT(s, 10.0) << "refused before any process starts";
    EXPECT_FALSE(fs::exists(dir / (std::string(name) + "-out") / "processes.json"));
  }
  // A slab 1.4 x 0.2 x 0.3 m (--size 0.2: as it is) on the UR5e rig, whose pedestal's near face is
  // 0.60 m from the turntable axis: its corners reach hypot(0.7, 0.1) = 0.707 m, so turning it
  // would jam it against the pedestal. It clears when scaled to reach under 0.595 m (the 5 mm
  // margin): by 0.595 / 0.7071 = 0.8415, a shortest edge of 0.168 m: --size 0.16 (in cm, down).
  std::ofstream slab(dir / "slab.obj");
  for (int k = 0; k < 8; ++k) slab << "v " << ((k & 1) ? 0.7 : -0.7) << " " << ((k & 2) ? 0.1 : -0.1) << " " << ((k & 4) ? 0.3 : 0.0) << "\n";
  slab << "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
  slab.close();
  const CommandResult r = run_command(bin_dir() + "/pbnbv scan --object " + (dir / "slab.obj").string() +
                                      " --size 0.2 --rig-model " + source_dir() + "/models/rig_ur5e.xml --out " +
                                      (dir / "slab-out").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("slab.obj', turned on the turntable, would strike the rig's pedestal"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("it reaches 0.707 m from the turntable axis"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("at --size 0.16 or less (now 0.20) it turns clear"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "slab-out" / "processes.json"));
  // An external rig's working volume likewise, before any driver is waited for: a cylinder of
  // radius 0.62 m on the UR5e strikes the pedestal; 0.595 / 0.62 = 96 % of it turns clear.
  const CommandResult wide = run_command(bin_dir() + "/pbnbv scan --external-rig --working-volume cylinder:0.62,0.3 --rig-model " +
                                         source_dir() + "/models/rig_ur5e.xml --driver-timeout 60 --out " + (dir / "wide-out").string());
  EXPECT_EQ(wide.exit_code, 2) << wide.output;
  EXPECT_NE(wide.output.find("the working volume cylinder:0.62,0.3, turned on the turntable, would strike the rig's pedestal"),
            std::string::npos) << wide.output;
  EXPECT_NE(wide.output.find("(96 % of it turns clear)"), std::string::npos) << wide.output;
  EXPECT_EQ(wide.output.find("waiting for them"), std::string::npos) << wide.output;
}

// The README's first command, run as a user runs it (the default bus, no namespace): its log
// holds every depth frame, cloud, registered cloud and map of the scan (it held 1 of 10 depth
// frames when lcm-logger listened with a small receive buffer), and the launcher says so.
TEST(Faults, TheMainJobsLogHoldsEveryMessageOfItsScan) {
  const fs::path out = fresh_dir("main-job") / "scan";
  const CommandResult r = run_command(bin_dir() + "/pbnbv scan --object bunny --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto scan = read_json_file(out / "scan.json");
  const std::string scan_id = scan["settings"]["scan_id"];
  const bus::LogContents log = bus::read_scan_log((out / "scan.lcmlog").string(), scan_id);
  const std::size_t views = scan["views"].size();
  std::cout << "scan.lcmlog of " << views << " views: " << log.depth_frames.size() << " DEPTH_FRAME, " << log.clouds.size()
            << " CLOUD, " << log.registered_clouds.size() << " REGISTERED_CLOUD, " << log.voxel_maps.size() << " VOXEL_MAP of "
            << log.events << " messages\n";
  EXPECT_EQ(views, 10u);
  EXPECT_GE(log.depth_frames.size(), views);
  EXPECT_EQ(log.clouds.size(), views);
  EXPECT_EQ(log.registered_clouds.size(), views);
  EXPECT_EQ(log.voxel_maps.size(), views);
  EXPECT_EQ(log.undecodable, 0);
  EXPECT_TRUE(bus::missing_from_log(log, bus::view_messages(read_scan_record(out))).empty());
  EXPECT_NE(r.output.find("scan.lcmlog: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("every depth frame, cloud, registered cloud and map of the 10 views"), std::string::npos)
      << r.output;
}

// Hostile traffic from view 2 to the end of a 10-view pbnbv scan on the free rig
// (pbnbv-test-hostile, every 100 ms: garbage of random length on every channel; a depth frame, a
// cloud and a voxel map of ~100 bytes claiming 2^31 - 1 elements; a zlib frame declaring 8192 x
// 8192; forged VIEW_PLAN "stop", MOVE_RESULT "unreachable" and failed CLOUD answers for request ids
// 0..60 and random ones; a VOXEL_MAP and ELLIPSOIDS of view 2^31 - 1; a PLAN_REQUEST for view
// 5000). The scan completes 10 of 10 views "done" with no process restarted and the coverage of
// the same scan without it (the free rig is reproducible: equal to 0.05 points), every process
// stays under 1 GB, and the services said what they refused. (Before: the forged stops ended the
// scan at view 7 with exit 0; the 2 GB counts got the camera and mapping killed as hung.)
TEST(Faults, HostileTrafficFromView2TakesNothingOver) {
  const fs::path dir = fresh_dir("hostile");
  const fs::path hostile = dir / "hostile", clean = dir / "clean";
  const std::string nbv = std::string("--object bunny --rig free --views 10 --sim-speed 4 ") + kSmallImageOptions;
  const std::string sender = bin_dir() + "/../tests/pbnbv-test-hostile --out " + hostile.string() + " --from-view 2 --deadline 600";
  const CommandResult r = run_command(netns_run() + " sh -c '" + sender + " > " + hostile.string() + ".hostile 2>&1 & p=$!; " +
                                      scan_command(hostile, nbv) + "; s=$?; wait $p; exit $s'");
  const std::string report = read_text(hostile.string() + ".hostile");
  std::cout << report;
  ASSERT_EQ(r.exit_code, 0) << r.output << read_text(hostile.string() + ".stdout");
  ASSERT_NE(report.find("hostile traffic for scan"), std::string::npos) << "the sender never started";
  ASSERT_EQ(run_command(netns_run() + " sh -c '" + scan_command(clean, nbv + " --no-log") + "'").exit_code, 0)
      << read_text(clean.string() + ".stdout");

  const auto s = read_json_file(hostile / "scan.json");
  EXPECT_EQ(s["status"]["state"], "done");
  EXPECT_EQ(s["status"]["views_done"], 10);
  for (const auto& p : read_json_file(hostile / "processes.json")["processes"]) {
    EXPECT_EQ(p["restarts"], 0) << p["name"];
  }
  const std::vector<double> with = eval::evaluate_coverage(hostile).coverage_by_view;
  const std::vector<double> without = eval::evaluate_coverage(clean).coverage_by_view;
  ASSERT_EQ(with.size(), 10u);
  ASSERT_EQ(without.size(), 10u);
  for (int i = 0; i < 10; ++i) EXPECT_NEAR(with[i], without[i], 0.05) << "view " << i + 1;
  // Peak memory: "peak RSS (VmHWM, MB): camera 93.1 coordinator 120.4 ..."
  const std::size_t at = report.find("peak RSS (VmHWM, MB):");
  ASSERT_NE(at, std::string::npos);
  std::istringstream peaks(report.substr(at + 21));
  std::string name;
  double mb = 0;
  int read = 0;
  while (peaks >> name >> mb) {
    EXPECT_LT(mb, 1024.0) << name;
    ++read;
  }
  EXPECT_GE(read, 8) << "peaks of the launcher and its processes";
  int rejected = 0;
  for (const auto& e : fs::directory_iterator(hostile / "logs")) {
    const std::string log = read_text(e.path());
    for (std::size_t k = log.find("rejected message on"); k != std::string::npos; k = log.find("rejected message on", k + 1)) ++rejected;
  }
  EXPECT_GT(rejected, 0) << "the services name what they refused";
  std::cout << "hostile traffic: coverage after view 10 " << with.back() << " % (without it " << without.back()
            << " %); " << rejected << " log lines on rejected messages\n";
}

// A full disk under --out (a 24 MB tmpfs in a private mount namespace; the scan's log fills it):
// the scan ends "failed" saying no space is left (exit 1, not the launcher dying with 2 and
// scan.json "running" as before), leaves no .tmp file and no empty record file, and once there is
// space `pbnbv scan --resume` completes it.
TEST(Faults, AFullDiskFailsTheScanSayingSoAndItResumesOnceThereIsSpace) {
  const fs::path dir = fresh_dir("diskfull");
  const fs::path small = dir / "small", after = dir / "after", resumed = dir / "resumed";
  fs::create_directories(small);
  const std::string scan = "--object bunny --rig free --views 10 --stop-rule off --out " + (small / "scan").string();
  const std::string script =
      "mount -t tmpfs -o size=24m tmpfs " + small.string() + " || exit 97; " +
      netns_run() + " " + bin_dir() + "/pbnbv scan " + scan + " > " + dir.string() + "/full.stdout 2>&1; echo $? > " +
      dir.string() + "/full.code; cp -a " + (small / "scan").string() + " " + after.string() + "; " +
      "mount -o remount,size=1g " + small.string() + " && " + netns_run() + " " + bin_dir() + "/pbnbv scan --resume " +
      (small / "scan").string() + " > " + dir.string() + "/resume.stdout 2>&1; echo $? > " + dir.string() +
      "/resume.code; cp -a " + (small / "scan").string() + " " + resumed.string();
  const CommandResult r = run_command("unshare -m sh -c '" + script + "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string full_out = read_text(dir / "full.stdout");
  EXPECT_EQ(read_text(dir / "full.code"), "1\n") << full_out;
  const auto s = read_json_file(after / "scan.json");
  EXPECT_EQ(s["status"]["state"], "failed");
  const std::string message = s["status"]["message"].get<std::string>();
  EXPECT_NE(message.find("o space left on device"), std::string::npos) << message;
  EXPECT_LT(s["status"]["views_done"].get<int>(), 10);
  std::cout << "full disk: " << s["status"]["views_done"] << " views, then: " << message << "\n";
  for (const auto& e : fs::recursive_directory_iterator(after)) {
    const std::string name = e.path().filename().string();
    EXPECT_EQ(name.find(".tmp"), std::string::npos) << e.path();
    if (e.is_regular_file() && e.path().parent_path().filename() != "logs" && name.find(".lcmlog") == std::string::npos) {
      EXPECT_GT(fs::file_size(e.path()), 0u) << e.path();
    }
  }
  EXPECT_FALSE(fs::exists(after / "state" / "coordinator.reserve")) << "the reserve was freed for the record";
  EXPECT_EQ(read_text(dir / "resume.code"), "0\n") << read_text(dir / "resume.stdout");
  const auto done = read_json_file(resumed / "scan.json");
  EXPECT_EQ(done["status"]["state"], "done");
  EXPECT_EQ(done["status"]["views_done"], 10);
}
