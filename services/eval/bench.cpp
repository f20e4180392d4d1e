// The benchmark and the ablations (bench.hpp).
#include "eval/bench.hpp"
#include "core/base/version.hpp"

#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <sstream>
#include <thread>

#include "core/base/signals.hpp"
#include "core/io/json.hpp"
#include "core/planning/planner.hpp"
#include "core/rig/rig.hpp"
#include "core/scan/scan_file.hpp"
#include "core/scan/scan_record.hpp"
#include "core/scan/scan_sequencer.hpp"
#include "core/scan/scan_settings.hpp"
#include "core/geometry/views.hpp"
#include "eval/bench_evaluation.hpp"
#include "eval/bench_progress.hpp"
#include "eval/evaluate.hpp"
#include "eval/objects.hpp"
#include "process/processes.hpp"
#include "core/base/format.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv::eval {

using process::Child;
using process::reap;
using process::start;
using process::stop_all;
using process::tail_lines;

namespace {

// The command that runs one scan of the benchmark, in a private network namespace (as
// scripts/netns-run does) when `netns`.
// `initial_view`: the run's drawn first view (none: --initial-view, else the scan's default).
std::vector<std::string> scan_argv(const BenchSpec& s, const fs::path& self, const std::string& object,
                                   PlannerKind planner, const std::optional<Eigen::Vector3d>& initial_view,
                                   const fs::path& out) {
  std::vector<std::string> a;
  if (s.netns) {
    if (::geteuid() == 0) a = {"unshare", "-n"};
    else a = {"unshare", "-r", "-n"};
    a.insert(a.end(), {"sh", "-c",
                       "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo || "
                       "{ echo 'pbnbv bench: cannot set up loopback multicast in a network namespace' >&2; exit 97; }; "
                       "sysctl -q -w net.core.rmem_max=67108864 net.core.rmem_default=33554432 2>/dev/null; exec \"$@\"",
                       "netns"});
  }
  if (scan_resumable(out)) {
    a.insert(a.end(), {self.string(), "scan", "--resume", out.string()});  // an interrupted scan goes on
    return a;
  }
  a.insert(a.end(), {self.string(), "scan", "--object", object, "--planner", std::string(name_of(planner)), "--rig",
                     std::string(name_of(s.rig)), "--area", std::string(name_of(s.area)),
                     "--views", std::to_string(s.views), "--resolution", exact(s.resolution_m), "--candidates",
                     std::to_string(s.candidates), "--tmax", std::to_string(s.tmax), "--beta", std::to_string(s.beta),
                     "--size", exact(s.size_m), "--working-distance", exact(s.working_distance_m), "--seed", std::to_string(s.seed), "--when-done",
                     std::string(name_of(s.when_done)), "--motion", std::string(name_of(s.motion)), "--seconds-per-point", exact(s.seconds_per_point), "--map-pose", std::string(name_of(s.map_pose)), "--stop-rule", "off", "--no-log", "--no-surface-metrics", "--out", out.string(),
                     "--camera", std::string(name_of(s.camera)), "--rig-errors", std::string(name_of(s.rig_errors)),
                     "--sim-speed", exact(s.sim_speed)});
  if (const std::optional<Eigen::Vector3d>& first = initial_view ? initial_view : s.initial_view) {
    const Eigen::Vector3d& v = *first;
    a.insert(a.end(), {"--initial-view", exact(v.x()) + "," + exact(v.y()) + "," + exact(v.z())});
  }
  if (s.up) a.insert(a.end(), {"--up", std::string(name_of(*s.up))});
  if (!s.rig_model.empty()) a.insert(a.end(), {"--rig-model", s.rig_model});
  return a;
}

// True when a network namespace can be made here (root, or unprivileged user namespaces).
bool netns_available() {
  const std::string cmd = std::string(::geteuid() == 0 ? "unshare -n" : "unshare -r -n") +
                          " sh -c 'ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo'"
                          " >/dev/null 2>&1";
  return std::system(cmd.c_str()) == 0;
}

json machine_info() {
  json m;
  char host[256] = {0};
  ::gethostname(host, sizeof(host) - 1);
  m["host"] = host;
  m["cores"] = std::thread::hardware_concurrency();
  std::istringstream cpu(read_text("/proc/cpuinfo"));
  for (std::string line; std::getline(cpu, line);) {
    if (line.rfind("model name", 0) == 0) {
      m["cpu"] = line.substr(line.find(':') + 2);
      break;
    }
  }
  std::istringstream mem(read_text("/proc/meminfo"));
  for (std::string line; std::getline(mem, line);) {
    if (line.rfind("MemTotal", 0) == 0) {
      std::istringstream ls(line.substr(9));
      double kb = 0;
      ls >> kb;
      m["memory_gib"] = std::round(kb / 1048576.0 * 10) / 10;
      break;
    }
  }
  utsname u{};
  if (::uname(&u) == 0) m["kernel"] = std::string(u.sysname) + " " + u.release;
  double load[3] = {0, 0, 0};
  if (::getloadavg(load, 3) == 3) m["load_average_at_end"] = {load[0], load[1], load[2]};
  const std::time_t t = std::time(nullptr);
  char b[64];
  std::strftime(b, sizeof(b), "%Y-%m-%dT%H:%M:%S%z", std::localtime(&t));
  m["date"] = b;
#ifdef NDEBUG
  m["build"] = "optimised (NDEBUG)";
#else
  m["build"] = "debug (asserts on)";
#endif
  return m;
}

// A task of the bench's runner: a scan, or the evaluation of one object's scans (`evaluation`: dir
// holds its request.json; name is the object's).
struct Job : ScanJob {
  const BenchSpec* spec = nullptr;  // the bench it is of
  std::string label;                // its bench's combination in a sweep ("": a bench alone)
  bool evaluation = false;
  std::string last_progress;
  int view = 0, views = 0;  // the scan's view in progress (its "[view k/N]" line), 0: none yet
  std::chrono::steady_clock::time_point started;
};

}  // namespace

std::string scan_failure_reason(const fs::path& dir, const fs::path& log) {
  const std::string where = " (log: " + log.string() + ")";
  try {
    if (fs::exists(dir / "scan.json")) {
      const json st = read_scan_status(dir);
      const std::string state = st.value("state", std::string("?"));
      std::string msg = "scan " + state + " after " + std::to_string(st.value("views_done", 0)) + " of " +
                        std::to_string(st.value("views_planned", 0)) + " views";
      const std::string m = st.value("message", std::string());
      if (!m.empty()) msg += ": " + m;
      return msg + where;
    }
  } catch (const std::exception& e) {
    return "scan.json unreadable: " + std::string(e.what()) + where;
  }
  std::string last;
  if (fs::exists(log)) {
    std::istringstream in(tail_lines(log.string(), 20));
    for (std::string line; std::getline(in, line);) {
      const size_t a = line.find_first_not_of(" \t\r");  // tail_lines indents its lines
      if (a != std::string::npos) last = line.substr(a);
    }
  }
  if (!last.empty()) return "no scan.json; the log ends: " + last + where;
  return fs::exists(log) ? "no scan.json and an empty log" + where : "no scan.json and no log" + where;
}

std::string objects_text(const BenchResult& r) {
  const int n_objects = static_cast<int>(r.spec.objects.size());
  const int first_views = r.spec.first_views;
  const int total = n_objects * first_views;
  int lo = std::numeric_limits<int>::max(), hi = 0;
  std::string failed;
  for (const auto& p : r.planners) {
    lo = std::min(lo, p.complete);
    hi = std::max(hi, p.complete);
    if (p.failed > 0) failed += (failed.empty() ? "" : ", ") + std::string(name_of(p.planner)) + " " + std::to_string(p.failed);
  }
  auto objects = [](int n) { return std::to_string(n) + (n == 1 ? " object" : " objects"); };
  if (first_views > 1) {
    const std::string grid = objects(n_objects) + " x " + std::to_string(first_views) + " first views";
    if (r.planners.empty() || failed.empty()) return grid + " (" + std::to_string(total) + " runs)";
    if (lo == hi) return std::to_string(hi) + " of " + std::to_string(total) + " runs (" + grid + "), " + std::to_string(total - hi) + " failed";
    return std::to_string(lo) + "-" + std::to_string(hi) + " of " + std::to_string(total) + " runs (" + grid + "; failed: " + failed + ")";
  }
  if (r.planners.empty()) return objects(total);
  if (failed.empty()) return objects(hi);
  if (lo == hi) return objects(hi) + ", " + std::to_string(total - hi) + " of " + std::to_string(total) + " failed";
  return std::to_string(lo) + "-" + objects(hi) + " (failed: " + failed + " of " + std::to_string(total) + ")";
}

void BenchSpec::validate() const {
  if (objects.empty()) throw std::invalid_argument("--objects: no object to benchmark");
  if (planners.empty()) throw std::invalid_argument("--planners: no planner to benchmark");
  kViews.checked(views);
  metrics.validate();
  kMapResolution.checked(resolution_m);
  kCandidates.checked(candidates);
  // The scans place the candidates on the default number of parallels.
  if (candidates < kParallels.value) {
    throw std::invalid_argument(fmt::format("--{} {}: the candidates lie on {} parallels, so at least {} are needed",
                                            kCandidates.name, candidates, kParallels.value, kParallels.value));
  }
  kTMax.checked(tmax);
  kSectors.checked(beta);
  kObjectSize.checked(size_m);
  kWorkingDistance.checked(working_distance_m);
  kPlannerSeed.checked(seed);
  kJobs.checked(jobs);
  kFirstViews.checked(first_views);
  if (initial_view) check_initial_view(*initial_view);
  if (initial_view && first_views > 1) {
    throw std::invalid_argument(fmt::format("--first-views {} draws the first views 2..{} while --initial-view fixes "
                                            "the first view of every scan: give one or the other",
                                            first_views, first_views));
  }
  if (out.empty()) throw std::invalid_argument("--out: an output folder is needed");
}

json to_json(const BenchSpec& s) {
  std::vector<std::string> planners;
  for (const PlannerKind p : s.planners) planners.emplace_back(name_of(p));
  json j = {{"objects", s.objects}, {"planners", planners}, {"rig", std::string(name_of(s.rig))},
            {"area", std::string(name_of(s.area))}, {"views", s.views},
            {"resolution_m", s.resolution_m}, {"candidates", s.candidates}, {"tmax", s.tmax}, {"beta", s.beta},
            {"size_m", s.size_m}, {"working_distance_m", s.working_distance_m}, {"up", s.up ? std::string(name_of(*s.up)) : std::string("per object")}, {"seed", s.seed},
            {"when_done", std::string(name_of(s.when_done))}, {"motion", std::string(name_of(s.motion))}, {"seconds_per_point", s.seconds_per_point}, {"map_pose", std::string(name_of(s.map_pose))}, {"stop_rule", to_json(s.stop_rule)},
            {"coverage", {{"samples", s.coverage.num_samples}, {"seed", s.coverage.seed}, {"radius_m", s.coverage.radius_m}}},
            {"surface_metrics", to_json(s.metrics)}};
  j["initial_view"] = s.initial_view ? json{s.initial_view->x(), s.initial_view->y(), s.initial_view->z()} : json(nullptr);
  j["first_views"] = s.first_views;
  j["first_view_seed"] = kFirstViewSeed;
  j["camera"] = name_of(s.camera);
  j["rig_errors"] = name_of(s.rig_errors);
  j["sim_speed"] = s.sim_speed;
  j["rig_model"] = s.rig_model;  // "": the rig kind's own file
  j["seconds_rule"] = to_json(s.seconds_rule);
  return j;
}

std::vector<Eigen::Vector3d> first_view_directions(const BenchSpec& s) {
  return uniform_sphere_points(std::max(0, s.first_views - 1), 1.0, s.area == CandidateArea::kHemisphere, kFirstViewSeed);
}

double default_first_view_distance(const std::string& object, double size_m, double working_distance_m,
                                   std::optional<UpAxis> up) {
  ObjectSpec o = resolve_object(object);
  ScanSettings s;
  s.working_distance_m = working_distance_m;
  s.normalisation = normalise_mesh(o.mesh, size_m, up.value_or(o.up));
  return views_known_at_start(s).front().translation().norm();
}

std::string run_folder(const std::string& name, int first_view) {
  return first_view <= 1 ? name : name + "-fv" + std::to_string(first_view);
}

std::vector<Interval> bootstrap_mean_ci95(const std::vector<std::vector<double>>& rows, int resamples, std::uint64_t seed) {
  if (rows.empty()) return {};
  if (resamples < 1) throw std::invalid_argument("bootstrap_mean_ci95: resamples must be >= 1, got " + std::to_string(resamples));
  const std::size_t n = rows.size(), cols = rows.front().size();
  for (std::size_t i = 0; i < n; ++i) {
    if (rows[i].size() != cols) {
      throw std::invalid_argument("bootstrap_mean_ci95: row " + std::to_string(i) + " has " + std::to_string(rows[i].size()) +
                                  " values, row 0 " + std::to_string(cols));
    }
  }
  std::mt19937_64 rng(seed);
  std::vector<std::vector<double>> means(cols, std::vector<double>(resamples, 0.0));
  std::vector<double> sum(cols);
  for (int b = 0; b < resamples; ++b) {
    std::fill(sum.begin(), sum.end(), 0.0);
    for (std::size_t k = 0; k < n; ++k) {
      // A uniform index from the 53 high bits (the same draws on any platform).
      const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;
      const std::size_t i = std::min(n - 1, static_cast<std::size_t>(u * static_cast<double>(n)));
      for (std::size_t c = 0; c < cols; ++c) sum[c] += rows[i][c];
    }
    for (std::size_t c = 0; c < cols; ++c) means[c][b] = sum[c] / static_cast<double>(n);
  }
  const auto percentile = [](const std::vector<double>& sorted, double q) {
    const double at = q * static_cast<double>(sorted.size() - 1);
    const std::size_t i = static_cast<std::size_t>(std::floor(at));
    if (i + 1 >= sorted.size()) return sorted.back();
    return sorted[i] + (at - static_cast<double>(i)) * (sorted[i + 1] - sorted[i]);
  };
  std::vector<Interval> out;
  for (auto& m : means) {
    std::sort(m.begin(), m.end());
    out.push_back({percentile(m, 0.025), percentile(m, 0.975)});
  }
  return out;
}

std::vector<ObjectMean> object_means(const std::vector<ObjectRun>& runs, int views) {
  std::vector<ObjectMean> out;
  for (const auto& r : runs) {
    auto it = std::find_if(out.begin(), out.end(), [&](const ObjectMean& m) { return m.object == r.object; });
    if (it == out.end()) {
      out.emplace_back();
      out.back().object = r.object;
      it = out.end() - 1;
    }
    if (!r.complete || r.coverage_by_view.empty()) {
      ++it->runs_failed;
      continue;
    }
    const std::vector<double> c = pad_views(r.coverage_by_view, views);
    if (it->coverage_by_view.empty()) it->coverage_by_view.assign(views, 0.0);
    for (int i = 0; i < views; ++i) it->coverage_by_view[i] += c[i];
    ++it->runs_complete;
    if (r.views_to_95) {
      it->views_to_95 = it->views_to_95.value_or(0.0) + *r.views_to_95;
      ++it->runs_reaching_95;
    }
  }
  for (auto& m : out) {
    for (double& c : m.coverage_by_view) c /= m.runs_complete;
    if (m.views_to_95) *m.views_to_95 /= m.runs_reaching_95;
  }
  return out;
}

std::optional<int> views_to_reach(const std::vector<double>& c, double percent) {
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (c[i] >= percent) return static_cast<int>(i) + 1;
  }
  return std::nullopt;
}

std::vector<double> pad_views(std::vector<double> v, int n) {
  if (v.empty()) return v;
  if (static_cast<int>(v.size()) > n) v.resize(n);
  while (static_cast<int>(v.size()) < n) v.push_back(v.back());
  return v;
}

std::optional<double> rig_time_to_reach(const std::vector<double>& coverage_by_view,
                                        const std::vector<double>& rig_time_by_view, double percent) {
  const std::optional<int> view = views_to_reach(coverage_by_view, percent);
  if (!view || *view > static_cast<int>(rig_time_by_view.size())) return std::nullopt;
  const double t = rig_time_by_view[*view - 1];
  if (!std::isfinite(t)) return std::nullopt;
  return t;
}

std::vector<double> rig_time_grid(double max_s, int points) {
  if (!(max_s > 0) || !std::isfinite(max_s) || points < 1) return {0.0};
  // The step m x 10^e; each time k m 10^e computed as one division or product of whole numbers,
  // so that a time such as 25 s is exactly 25 (k x 0.2 would not always be).
  int e = -3;
  double m = 0;
  const auto scale = [](double x, int e10) { return e10 >= 0 ? x * std::pow(10.0, e10) : x / std::pow(10.0, -e10); };
  while (m == 0) {
    for (const double candidate : {1.0, 2.0, 5.0}) {
      if (max_s / scale(candidate, e) <= points) {
        m = candidate;
        break;
      }
    }
    if (m == 0) ++e;
  }
  std::vector<double> t;
  for (double k = 0;; ++k) {
    t.push_back(scale(k * m, e));
    if (t.back() >= max_s) break;
  }
  return t;
}

namespace {

// A run whose observable coverage and rig time can be drawn against each other: complete, with
// both per view and every view's rig time known.
bool has_rig_time(const ObjectRun& r) {
  return r.complete && r.rig_time && !r.observable_by_view.empty() && !r.rig_time_by_view.empty() &&
         std::all_of(r.rig_time_by_view.begin(), r.rig_time_by_view.end(), [](double t) { return std::isfinite(t); });
}

}  // namespace

CoverageOverTime coverage_at_rig_times(const std::vector<ObjectRun>& runs, const std::vector<double>& times) {
  CoverageOverTime c;
  c.mean.assign(times.size(), 0.0);
  c.lo.assign(times.size(), INFINITY);
  c.hi.assign(times.size(), -INFINITY);
  for (const ObjectRun& r : runs) {
    if (!has_rig_time(r)) continue;
    ++c.runs;
    const std::size_t n = std::min(r.observable_by_view.size(), r.rig_time_by_view.size());
    for (std::size_t i = 0; i < times.size(); ++i) {
      double covered = 0;  // before its first view
      for (std::size_t k = 0; k < n && r.rig_time_by_view[k] <= times[i]; ++k) covered = r.observable_by_view[k];
      c.mean[i] += covered;
      c.lo[i] = std::min(c.lo[i], covered);
      c.hi[i] = std::max(c.hi[i], covered);
    }
  }
  if (c.runs == 0) return CoverageOverTime{};
  for (double& m : c.mean) m /= c.runs;
  return c;
}

MeanSurfaceMetrics mean_surface_metrics(const std::vector<ObjectRun>& runs,
                                        std::optional<SurfaceMetrics> ObjectRun::*which) {
  MeanSurfaceMetrics m;
  for (const auto& r : runs) {
    if (!r.complete || !(r.*which)) continue;
    const SurfaceMetrics& s = *(r.*which);
    ++m.objects;
    m.accuracy_mean_mm += s.accuracy.mean_m * 1e3;
    m.accuracy_median_mm += s.accuracy.median_m * 1e3;
    m.accuracy_rmse_mm += s.accuracy.rmse_m * 1e3;
    m.accuracy_p95_mm += s.accuracy.p95_m * 1e3;
    m.completeness_mean_mm += s.completeness.mean_m * 1e3;
    m.precision += s.precision;
    m.recall += s.recall;
    m.f_score += s.f_score;
  }
  if (m.objects > 0) {
    for (double* v : {&m.accuracy_mean_mm, &m.accuracy_median_mm, &m.accuracy_rmse_mm, &m.accuracy_p95_mm,
                      &m.completeness_mean_mm, &m.precision, &m.recall, &m.f_score}) {
      *v /= m.objects;
    }
  }
  return m;
}

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

PlannerSummary summarise(PlannerKind planner, const std::vector<ObjectRun>& runs, int views) {
  PlannerSummary p;
  p.planner = planner;
  p.runs = runs;
  p.coverage_by_view.assign(views, 0.0);
  p.coverage_min_by_view.assign(views, std::numeric_limits<double>::infinity());
  p.coverage_max_by_view.assign(views, -std::numeric_limits<double>::infinity());
  std::vector<double> observable(views, 0.0);
  int with_observable = 0;
  std::vector<double> times, critical, reached;
  for (const auto& r : runs) {
    p.rig_contacts += r.rig_contacts;
    if (r.rig_contacts > 0) p.runs_with_rig_contacts.push_back(run_folder(r.object, r.first_view));
    if (!r.complete || r.coverage_by_view.empty()) {
      ++p.failed;
      continue;
    }
    ++p.complete;
    const std::vector<double> c = pad_views(r.coverage_by_view, views);
    for (int i = 0; i < views; ++i) {
      p.coverage_by_view[i] += c[i];
      p.coverage_min_by_view[i] = std::min(p.coverage_min_by_view[i], c[i]);
      p.coverage_max_by_view[i] = std::max(p.coverage_max_by_view[i], c[i]);
    }
    if (!r.observable_by_view.empty()) {
      const std::vector<double> o = pad_views(r.observable_by_view, views);
      for (int i = 0; i < views; ++i) observable[i] += o[i];
      ++with_observable;
    }
    times.insert(times.end(), r.planner_ms.begin(), r.planner_ms.end());
    critical.insert(critical.end(), r.planner_critical_ms.begin(), r.planner_critical_ms.end());
    if (r.views_to_95) reached.push_back(*r.views_to_95);
  }
  if (p.complete == 0) {
    p.coverage_by_view.clear();
    p.coverage_min_by_view.clear();
    p.coverage_max_by_view.clear();
  } else {
    for (double& c : p.coverage_by_view) c /= p.complete;
  }
  if (with_observable > 0) {
    for (double& c : observable) c /= with_observable;
    p.observable_by_view = observable;
  }
  if (!times.empty()) {
    p.planner_ms_median = median_of(times);
    p.planner_ms_mean = std::accumulate(times.begin(), times.end(), 0.0) / times.size();
  }
  if (!critical.empty()) p.planner_critical_ms_median = median_of(critical);
  // Rig time over the complete runs that measured it at every view.
  std::vector<double> to_90, to_95;
  for (const auto& r : runs) {
    if (!has_rig_time(r)) continue;
    ++p.rig_time_runs;
    for (auto part : {&RigTime::motion_s, &RigTime::settle_s, &RigTime::capture_s, &RigTime::compute_s}) {
      p.rig_time_mean.*part += (*r.rig_time).*part;
    }
    const std::vector<double> t = pad_views(r.rig_time_by_view, views);
    if (p.rig_time_by_view.empty()) p.rig_time_by_view.assign(views, 0.0);
    for (int i = 0; i < views; ++i) p.rig_time_by_view[i] += t[i];
    if (const auto t90 = rig_time_to_reach(r.observable_by_view, r.rig_time_by_view, 90.0)) to_90.push_back(*t90);
    if (const auto t95 = rig_time_to_reach(r.observable_by_view, r.rig_time_by_view, 95.0)) to_95.push_back(*t95);
  }
  if (p.rig_time_runs > 0) {
    for (auto part : {&RigTime::motion_s, &RigTime::settle_s, &RigTime::capture_s, &RigTime::compute_s}) {
      p.rig_time_mean.*part /= p.rig_time_runs;
    }
    for (double& t : p.rig_time_by_view) t /= p.rig_time_runs;
  }
  p.rig_time_reaching_90 = static_cast<int>(to_90.size());
  p.rig_time_reaching_95 = static_cast<int>(to_95.size());
  if (!to_90.empty()) p.rig_time_to_90 = std::accumulate(to_90.begin(), to_90.end(), 0.0) / to_90.size();
  if (!to_95.empty()) p.rig_time_to_95 = std::accumulate(to_95.begin(), to_95.end(), 0.0) / to_95.size();
  p.stop_rule = summarise_stop_rule(runs, views);
  p.seconds_rule = summarise_stop_rule(runs, views, &ObjectRun::seconds_stop_view);
  p.cloud_metrics = mean_surface_metrics(runs, &ObjectRun::cloud_metrics);
  p.mesh_metrics = mean_surface_metrics(runs, &ObjectRun::mesh_metrics);
  p.reached_95 = static_cast<int>(reached.size());
  p.views_to_95_of_mean = views_to_reach(p.coverage_by_view, 95.0);
  if (!reached.empty()) p.views_to_95 = std::accumulate(reached.begin(), reached.end(), 0.0) / reached.size();
  // Per object, and the intervals by bootstrap over the objects.
  p.per_object = object_means(runs, views);
  std::vector<std::vector<double>> coverage_rows, views_rows;
  for (const ObjectMean& m : p.per_object) {
    if (m.runs_complete > 0) coverage_rows.push_back(m.coverage_by_view);
    if (m.views_to_95) views_rows.push_back({*m.views_to_95});
  }
  p.objects_complete = static_cast<int>(coverage_rows.size());
  p.objects_reaching_95 = static_cast<int>(views_rows.size());
  p.coverage_ci95_by_view = bootstrap_mean_ci95(coverage_rows);
  if (!views_rows.empty()) p.views_to_95_ci95 = bootstrap_mean_ci95(views_rows).front();
  return p;
}

int stop_view_or_budget(const ObjectRun& r, int views, StopViewOf stop) {
  return r.*stop ? std::min(*(r.*stop), views) : views;
}

double coverage_at_view(const ObjectRun& r, int view) {
  const std::vector<double> c = pad_views(r.coverage_by_view, std::max(view, 1));
  return c.empty() ? NAN : c[view - 1];
}

StopRuleSummary summarise_stop_rule(const std::vector<ObjectRun>& runs, int views, StopViewOf stop_of) {
  StopRuleSummary s;
  for (const auto& r : runs) {
    if (!r.complete || r.coverage_by_view.empty()) continue;
    const int stop = stop_view_or_budget(r, views, stop_of);
    const double shortfall = coverage_at_view(r, views) - coverage_at_view(r, stop);
    ++s.objects;
    if (stop < views) ++s.stopped;
    s.mean_stop_view += stop;
    s.mean_views_saved_percent += 100.0 * (views - stop) / views;
    s.mean_shortfall += shortfall;
    if (static_cast<int>(r.rig_time_by_view.size()) >= views && std::isfinite(r.rig_time_by_view[stop - 1]) &&
        std::isfinite(r.rig_time_by_view[views - 1]) && r.rig_time_by_view[views - 1] > 0) {
      s.mean_rig_time_saved_percent += 100.0 * (1.0 - r.rig_time_by_view[stop - 1] / r.rig_time_by_view[views - 1]);
      ++s.rig_time_runs;
    }
    if (s.worst_object.empty() || shortfall > s.worst_shortfall) {
      s.worst_shortfall = shortfall;
      s.worst_object = run_folder(r.object, r.first_view);
    }
    if (shortfall <= 0.5) ++s.within_half_point;
  }
  if (s.objects > 0) {
    s.mean_stop_view /= s.objects;
    s.mean_views_saved_percent /= s.objects;
    s.mean_shortfall /= s.objects;
  }
  if (s.rig_time_runs > 0) s.mean_rig_time_saved_percent /= s.rig_time_runs;
  return s;
}

void add_gaps_to_oracle(std::vector<PlannerSummary>& planners, int views) {
  const auto oracle = std::find_if(planners.begin(), planners.end(),
                                   [](const PlannerSummary& p) { return p.planner == PlannerKind::kOracle; });
  if (oracle == planners.end()) return;
  // The oracle's curve per complete run (object, first view).
  std::map<std::pair<std::string, int>, std::vector<double>> truth;
  for (const auto& o : oracle->runs) {
    if (o.complete && !o.coverage_by_view.empty()) truth[{o.object, o.first_view}] = pad_views(o.coverage_by_view, views);
  }
  for (auto& p : planners) {
    p.gap_to_oracle_by_view.assign(views, 0.0);
    p.gap_objects = 0;
    for (const auto& o : p.runs) {
      const auto t = truth.find({o.object, o.first_view});
      if (!o.complete || o.coverage_by_view.empty() || t == truth.end()) continue;
      const std::vector<double> c = pad_views(o.coverage_by_view, views);
      for (int i = 0; i < views; ++i) p.gap_to_oracle_by_view[i] += t->second[i] - c[i];
      ++p.gap_objects;
    }
    if (p.gap_objects == 0) {
      p.gap_to_oracle_by_view.clear();
    } else {
      for (double& g : p.gap_to_oracle_by_view) g /= p.gap_objects;
    }
  }
}

std::string surface_metrics_markdown(const std::vector<PlannerSummary>& planners, const MetricParams& params) {
  std::ostringstream md;
  for (const auto& p : planners) {
    for (const auto& [model, m] : {std::pair{"cloud", &p.cloud_metrics}, std::pair{"mesh", &p.mesh_metrics}}) {
      if (m->objects == 0) continue;
      md << "| " << name_of(p.planner) << " | " << model << " | " << m->objects << " | " << fixed(m->accuracy_mean_mm, 2)
         << " | " << fixed(m->accuracy_median_mm, 2) << " | " << fixed(m->accuracy_rmse_mm, 2) << " | "
         << fixed(m->accuracy_p95_mm, 2) << " | " << fixed(m->completeness_mean_mm, 2) << " | " << fixed(m->precision, 3)
         << " | " << fixed(m->recall, 3) << " | " << fixed(m->f_score, 3) << " |\n";
    }
  }
  if (md.str().empty()) return "";
  const std::string t = fixed(params.threshold_m * 1e3, 1);
  return "## Surface metrics after the last view (mean over the runs)\n\nAgainst the true mesh: accuracy is the distance "
         "from each model point (a mesh: samples on it) to the true surface, completeness the distance from true-surface "
         "samples (" + fixed(params.samples_per_cm2, 0) + " per cm^2) to the model; precision and recall are the "
         "fractions within " + t + " mm, F = 2PR / (P + R) (Knapitsch et al., Tanks and Temples). Distances in mm.\n\n"
         "| planner | model | runs | accuracy mean | median | RMSE | p95 | completeness mean | precision @" + t +
         " mm | recall | F-score |\n|---|---|---|---|---|---|---|---|---|---|---|\n" + md.str() + "\n";
}

namespace {

json interval_json(const Interval& i) { return json{i.lo, i.hi}; }

// A planner's means, spread and intervals over its runs: the summary's, and each half's.
json planner_means_json(const PlannerSummary& p, const BenchSpec& spec) {
  json ci = json::array();
  for (const Interval& i : p.coverage_ci95_by_view) ci.push_back(interval_json(i));
  json pj = {{"coverage_by_view", p.coverage_by_view},
             {"coverage_ci95_by_view", ci},
             {"planner_ms_median", p.planner_ms_median},
             {"planner_ms_mean", p.planner_ms_mean},
             {"planner_critical_ms_median", p.planner_critical_ms_median},
             {"views_to_95", p.views_to_95 ? json(*p.views_to_95) : json(nullptr)},
             {"runs_reaching_95", p.reached_95},
             {"views_to_95_ci95", p.views_to_95_ci95 ? interval_json(*p.views_to_95_ci95) : json(nullptr)},
             {"views_to_95_ci95_objects", p.objects_reaching_95},
             {"views_to_95_of_mean_curve", p.views_to_95_of_mean ? json(*p.views_to_95_of_mean) : json(nullptr)},
             {"runs_complete", p.complete},
             {"runs_failed", p.failed},
             {"objects_complete", p.objects_complete},
             {"rig_contacts", {{"events", p.rig_contacts}, {"runs_with_any", p.runs_with_rig_contacts}}}};
  if (!p.observable_by_view.empty()) pj["observable_coverage_by_view"] = p.observable_by_view;
  for (const auto& [name, m] : {std::pair{"cloud", &p.cloud_metrics}, std::pair{"mesh", &p.mesh_metrics}}) {
    if (m->objects == 0) continue;
    pj["surface_metrics"][name] = {{"runs", m->objects},
                                   {"accuracy_mean_mm", m->accuracy_mean_mm},
                                   {"accuracy_median_mm", m->accuracy_median_mm},
                                   {"accuracy_rmse_mm", m->accuracy_rmse_mm},
                                   {"accuracy_p95_mm", m->accuracy_p95_mm},
                                   {"completeness_mean_mm", m->completeness_mean_mm},
                                   {"precision", m->precision},
                                   {"recall", m->recall},
                                   {"f_score", m->f_score}};
  }
  if (!p.coverage_min_by_view.empty()) {
    pj["coverage_min_by_view"] = p.coverage_min_by_view;
    pj["coverage_max_by_view"] = p.coverage_max_by_view;
  }
  const auto rule_json = [](const json& rule, const StopRuleSummary& st) {
    json j = {{"rule", rule},
              {"runs", st.objects},
              {"runs_stopped_before_budget", st.stopped},
              {"mean_stop_view", st.mean_stop_view},
              {"mean_views_saved_percent", st.mean_views_saved_percent},
              {"mean_shortfall_points", st.mean_shortfall},
              {"worst_shortfall_points", st.worst_shortfall},
              {"worst_run", st.worst_object},
              {"runs_within_0_5_points", st.within_half_point}};
    if (st.rig_time_runs > 0) {
      j["mean_rig_time_saved_percent"] = st.mean_rig_time_saved_percent;
      j["rig_time_runs"] = st.rig_time_runs;
    }
    return j;
  };
  pj["stop_rule"] = rule_json(to_json(spec.stop_rule), p.stop_rule);
  pj["seconds_rule"] = rule_json(to_json(spec.seconds_rule), p.seconds_rule);
  if (!p.gap_to_oracle_by_view.empty()) {
    pj["gap_to_oracle_by_view"] = p.gap_to_oracle_by_view;
    pj["gap_to_oracle_runs"] = p.gap_objects;
  }
  pj["rig_time_runs"] = p.rig_time_runs;
  if (p.rig_time_runs > 0) {
    pj["rig_time_s"] = rig_time_json(p.rig_time_mean);
    pj["rig_time_s_by_view"] = p.rig_time_by_view;
    pj["rig_time_s_to_90"] = p.rig_time_to_90 ? json(*p.rig_time_to_90) : json(nullptr);
    pj["rig_time_s_to_90_runs"] = p.rig_time_reaching_90;
    pj["rig_time_s_to_95"] = p.rig_time_to_95 ? json(*p.rig_time_to_95) : json(nullptr);
    pj["rig_time_s_to_95_runs"] = p.rig_time_reaching_95;
  }
  return pj;
}

json run_json(const ObjectRun& o, int views) {
  json oj = {{"object", o.object},
             {"first_view", o.first_view},
             {"initial_view", o.initial_view ? json{o.initial_view->x(), o.initial_view->y(), o.initial_view->z()} : json(nullptr)},
             {"coverage_by_view", o.coverage_by_view},
             {"planner_ms", o.planner_ms},
             {"planner_critical_ms", o.planner_critical_ms},
             {"views_to_95", o.views_to_95 ? json(*o.views_to_95) : json(nullptr)},
             {"views_done", o.views_done},
             {"complete", o.complete},
             {"stop_reason", o.stop_reason},
             {"wall_s", o.wall_s},
             {"rig_contacts", o.rig_contacts}};
  if (!o.rig_contact_list.empty()) oj["rig_contact_list"] = o.rig_contact_list;
  if (!o.observable_by_view.empty()) oj["observable_coverage_by_view"] = o.observable_by_view;
  if (!o.rig_time_by_view.empty()) oj["rig_time_s_by_view"] = o.rig_time_by_view;
  if (o.rig_time) {
    oj["rig_time_s"] = rig_time_json(*o.rig_time);
    const auto to = [&](double percent) {
      const auto t = rig_time_to_reach(o.observable_by_view, o.rig_time_by_view, percent);
      return t ? json(*t) : json(nullptr);
    };
    oj["rig_time_s_to_90"] = to(90.0);
    oj["rig_time_s_to_95"] = to(95.0);
  }
  if (!o.error.empty()) oj["error"] = o.error;
  if (o.cloud_metrics) oj["surface_metrics"]["cloud"] = to_json(*o.cloud_metrics);
  if (o.mesh_metrics) oj["surface_metrics"]["mesh"] = to_json(*o.mesh_metrics);
  if (o.complete && !o.coverage_by_view.empty()) {
    const int stop = stop_view_or_budget(o, views);
    oj["stop_rule"] = {{"stop_view", o.stop_view ? json(*o.stop_view) : json(nullptr)},
                       {"reason", o.stop_view ? o.stop_rule_reason : "never stops before the budget"},
                       {"coverage_at_stop", coverage_at_view(o, stop)},
                       {"coverage_at_budget", coverage_at_view(o, views)},
                       {"shortfall_points", coverage_at_view(o, views) - coverage_at_view(o, stop)},
                       {"new_surface_by_view", o.new_surface_by_view}};
    const int seconds_stop = stop_view_or_budget(o, views, &ObjectRun::seconds_stop_view);
    oj["seconds_rule"] = {{"stop_view", o.seconds_stop_view ? json(*o.seconds_stop_view) : json(nullptr)},
                          {"reason", o.seconds_stop_view ? o.seconds_stop_reason : "never stops before the budget"},
                          {"coverage_at_stop", coverage_at_view(o, seconds_stop)},
                          {"shortfall_points", coverage_at_view(o, views) - coverage_at_view(o, seconds_stop)}};
  }
  return oj;
}

}  // namespace

std::vector<HalfSummary> summarise_halves(const BenchSpec& spec, const std::vector<PlannerSummary>& planners) {
  std::vector<HalfSummary> halves;
  for (const ObjectSet half : {ObjectSet::kTune, ObjectSet::kConfirm}) {
    HalfSummary h;
    h.half = half;
    for (const std::string& o : spec.objects) {
      if (tuning_half(o) == half) h.objects.push_back(o);
    }
    if (h.objects.empty()) return {};  // both halves or none
    for (const PlannerSummary& p : planners) {
      std::vector<ObjectRun> runs;
      for (const ObjectRun& r : p.runs) {
        if (std::find(h.objects.begin(), h.objects.end(), r.object) != h.objects.end()) runs.push_back(r);
      }
      h.planners.push_back(summarise(p.planner, runs, spec.views));
    }
    add_gaps_to_oracle(h.planners, spec.views);
    halves.push_back(std::move(h));
  }
  return halves;
}

json to_json(const BenchResult& r) {
  json j;
  j["pbnbv_version"] = std::string(pbnbv_version());
  std::vector<std::string> order;
  for (const auto& p : r.planners) {
    order.emplace_back(name_of(p.planner));
    json runs = json::object(), objects = json::object();
    for (const auto& o : p.runs) runs[run_folder(o.object, o.first_view)] = run_json(o, r.spec.views);
    for (const ObjectMean& m : p.per_object) {
      objects[m.object] = {{"coverage_by_view", m.coverage_by_view},
                           {"views_to_95", m.views_to_95 ? json(*m.views_to_95) : json(nullptr)},
                           {"runs_reaching_95", m.runs_reaching_95},
                           {"runs_complete", m.runs_complete},
                           {"runs_failed", m.runs_failed}};
    }
    json pj = planner_means_json(p, r.spec);
    pj["objects"] = objects;
    pj["runs"] = runs;
    j[std::string(name_of(p.planner))] = pj;
  }
  j["planners"] = order;
  if (!r.halves.empty()) {
    json halves = json::object();
    for (const HalfSummary& h : r.halves) {
      json hj = {{"objects", h.objects}};
      for (const PlannerSummary& p : h.planners) hj[std::string(name_of(p.planner))] = planner_means_json(p, r.spec);
      halves[std::string(name_of(h.half))] = hj;
    }
    j["halves"] = halves;
  }
  json failed = json::array();
  for (const auto& p : r.planners) {
    for (const auto& o : p.runs) {
      if (!o.complete) {
        failed.push_back({{"object", o.object}, {"first_view", o.first_view}, {"run", run_folder(o.object, o.first_view)},
                          {"planner", std::string(name_of(p.planner))}, {"reason", o.error}});
      }
    }
  }
  j["failed_scans"] = failed;
  j["objects_text"] = objects_text(r);
  j["first_views"] = r.spec.first_views;
  json directions = json::array();
  for (const Eigen::Vector3d& d : first_view_directions(r.spec)) directions.push_back({d.x(), d.y(), d.z()});
  j["first_view_directions"] = directions;
  j["settings"] = to_json(r.spec);
  j["machine"] = r.machine;
  j["coverage_rule"] = "mean over the complete runs (objects x first views) of the percent of " +
                       std::to_string(r.spec.coverage.num_samples) + " surface samples (seed " +
                       std::to_string(r.spec.coverage.seed) + ") with a captured point within " +
                       fixed(r.spec.coverage.radius_m * 1000, 0) +
                       " mm; a scan that stopped early keeps its last figure; views_to_95: mean over the runs that reach 95 %";
  j["first_view_rule"] = "first view 1 is the scan's default; first view k >= 2 is first_view_directions[k - 2] (drawn "
                         "uniformly on the " + std::string(r.spec.area == CandidateArea::kHemisphere ? "upper half of the " : "") +
                         "sphere, seed " + std::to_string(kFirstViewSeed) +
                         ") times the distance of the object's default first view from its centre";
  j["interval_rule"] = "95 % interval of the mean, percentile bootstrap over the objects (" +
                       std::to_string(kBootstrapResamples) + " resamples with replacement, seed " +
                       std::to_string(kBootstrapSeed) +
                       "): each object's value is its mean over its complete first views; views_to_95_ci95 over the "
                       "objects with a run reaching 95 % (views_to_95_ci95_objects; each its mean over those runs), an "
                       "object that never reaches 95 % is left out as in views_to_95";
  j["rig_time_rule"] = "rig time (scan.json rig_time_s, docs/scan.md): per view motion (command to within tolerance) "
                       "and settle (to settled) on the rig clock, capture (the settled move's answer to the frame's arrival "
                       "at the camera service) and compute (the rig waiting after the capture for the next command, or "
                       "for the scan to stop) on the wall clock; rig_time_s_by_view: from the start to the end of each view, mean over "
                       "the rig_time_runs runs measured at every view; rig_time_s_to_90 / _95: the rig time at the end "
                       "of the first view whose observable coverage reaches 90 / 95 %, mean over the runs that reach it "
                       "(rig_time_s_to_90_runs / _95_runs); rig_time_s: the mean per scan of each part";
  j["planner_ms_rule"] = "per planning iteration: map update + view selection (+ ellipsoid fitting for pbnbv; "
                         "view selection includes the reachability check and waiting for it)";
  j["planner_critical_ms_rule"] = "per planning iteration, as the scan waits for it: map update + the view scorer's time "
                                  "from the request to its answer (the ellipsoid fit runs beside the reachability check)";
  return j;
}

namespace {

// A folder holds one benchmark: a rerun with other settings must not mix results. Refuses a folder
// whose bench.json says other settings, naming the first; writes this run's.
void claim_folder(const BenchSpec& spec) {
  if (fs::exists(spec.out / "sweep.json")) {
    throw std::invalid_argument(spec.out.string() + " holds a sweep (sweep.json), not one benchmark: use another --out");
  }
  const fs::path spec_path = spec.out / "bench.json";
  json settings = to_json(spec);
  settings.erase("objects");  // objects may be added to a folder's benchmark
  settings.erase("planners");
  settings.erase("stop_rule");  // evaluated from the recorded figures, not run: it may change
  settings.erase("seconds_rule");
  settings.erase("first_views");  // first views may be added (the draws for N are the first of those for N + 1)
  if (fs::exists(spec_path)) {
    const json before = read_json(spec_path.string());
    for (auto it = settings.begin(); it != settings.end(); ++it) {
      if (before.contains(it.key()) && before[it.key()] != it.value()) {
        throw std::invalid_argument(spec.out.string() + " holds a benchmark with other settings (" + it.key() + ": " +
                                    before[it.key()].dump() + " there, " + it.value().dump() +
                                    " now): use another --out, or remove the folder");
      }
    }
  }
  write_json_atomic(settings, spec_path.string());
}

// The jobs, object by object (and first view by first view) so that a partial run has every
// planner on the first objects.
std::vector<Job> plan_jobs(const BenchSpec& spec) {
  std::vector<Job> jobs;
  std::map<std::string, std::string> names;  // object as given -> its name
  const std::vector<Eigen::Vector3d> directions = first_view_directions(spec);
  for (const auto& object : spec.objects) {
    const std::string name = fs::path(object).stem().string();
    for (const auto& [given, n] : names) {
      if (n == name && given != object) throw std::invalid_argument("--objects: '" + given + "' and '" + object + "' have the same name " + name);
    }
    names[object] = name;
    double distance = 0;  // of the object's default first view, for the drawn ones
    if (!directions.empty()) {
      try {
        distance = default_first_view_distance(object, spec.size_m, spec.working_distance_m, spec.up);
      } catch (const std::exception& e) {
        throw std::invalid_argument("--first-views " + std::to_string(spec.first_views) + ": the first views of '" + object +
                                    "' lie at its default first view's distance, which needs the object: " + e.what());
      }
    }
    for (int k = 1; k <= spec.first_views; ++k) {
      for (const auto& planner : spec.planners) {
        Job j;
        j.object = object;
        j.name = name;
        j.first_view = k;
        if (k > 1) j.initial_view = distance * directions[k - 2];
        j.run = run_folder(name, k);
        j.planner = planner;
        j.dir = spec.out / std::string(name_of(planner)) / j.run;
        j.log = spec.out / "logs" / (std::string(name_of(planner)) + "-" + j.run + ".log");
        jobs.push_back(std::move(j));
      }
    }
  }
  return jobs;
}

// How the runner runs its tasks: `jobs` at a time here, or as Slurm tasks.
struct RunnerOptions {
  int jobs = 1;
  bool netns = true;                // false: the scans share the bus (on Slurm: one task a node)
  std::optional<SlurmSpec> slurm;
  fs::path root;                    // the folder of the run: slurm/ is below it
};

// Runs the tasks of `todo` (of `jobs`), each a process: a `pbnbv scan`, or (`evaluation` jobs)
// a `pbnbv bench-evaluate` of one object's scans. Here options.jobs at a time, or as the tasks of
// Slurm job arrays. Prints each start, view and end (live, one line per running task and an
// estimate, on a terminal). SIGINT or SIGTERM stops every task (a scan keeps what it has) and throws.
class TaskRunner {
 public:
  TaskRunner(const RunnerOptions& options, std::vector<Job>& jobs, int complete, const fs::path& self, std::ostream& log,
             bool terminal)
      : options_(options), jobs_(jobs), self_(self), live_(log, terminal), finished_(complete) {
    evaluations_ = !jobs.empty() && jobs.front().evaluation;
    noun_ = evaluations_ ? "evaluations" : "scans";
  }

  void run(const std::vector<Job*>& todo) {
    install_stop_handlers();
    if (options_.slurm) {
      run_on_slurm(todo);
      return;
    }
    while (next_ < todo.size() || !running_.empty()) {
      if (stop_requested()) stop_every_task();
      while (static_cast<int>(running_.size()) < options_.jobs && next_ < todo.size()) start(todo[next_++]);
      reap_finished();
      read_progress();
      if (live_.live()) show_live(todo.size() - next_);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    live_.update({});  // the live block ends before the evaluation's lines
  }

 private:
  std::vector<std::string> argv_of(const Job* j) const {
    if (j->evaluation) return {self_.string(), "bench-evaluate", (j->dir / "request.json").string()};
    return scan_argv(*j->spec, self_, j->object, j->planner, j->initial_view, j->dir);
  }

  // The task's result is there: a complete scan, or an evaluation record (else why not in `error`).
  bool complete(const Job* j, std::string* error = nullptr) const {
    return j->evaluation ? read_evaluation(j->dir, error).has_value() : scan_complete(j->dir);
  }

  // Before a task starts: an interrupted scan is resumed (scan_argv), a folder that holds none
  // (no processes.json, or stopped before the coordinator's first scan.json: a task cancelled
  // while it started) starts anew; an evaluation's last record goes.
  void prepare(const Job* j) const {
    if (j->evaluation) {
      fs::remove(j->dir / "evaluation.json");
    } else if (fs::exists(j->dir) && !scan_resumable(j->dir)) {
      fs::remove_all(j->dir);
    }
  }

  std::string interrupted() const {
    return evaluations_ ? "interrupted during the evaluation: the scans are complete in " + options_.root.string() +
                              "; run the same command again to evaluate them"
                        : "interrupted: the scans completed so far are kept in " + options_.root.string() +
                              "; run the same command again to resume";
  }

  // The tasks as the tasks of Slurm job arrays: one array for `todo`, one more for the tasks that
  // ended without their result (once each); Slurm's queue and the scans' logs read once a second.
  void run_on_slurm(const std::vector<Job*>& todo) {
    SlurmQueue queue(options_.root / "slurm", evaluations_ ? "evaluate" : "submit");
    struct Array {
      std::string id;
      std::vector<Job*> jobs;  // task i: jobs[i]
    };
    std::vector<Array> arrays;
    std::map<Job*, std::pair<std::size_t, int>> task_of;  // the array (index) and task running it now
    std::map<Job*, int> submitted;                         // how often
    std::map<Job*, std::vector<std::string>> command;      // the task's command, as last submitted
    const auto submit = [&](const std::vector<Job*>& batch) {
      std::vector<SlurmTask> tasks;
      for (Job* j : batch) {
        prepare(j);
        fs::create_directories(j->dir);
        fs::remove(j->dir / "bench_task.json");
        command[j] = argv_of(j);
        tasks.push_back({command[j], j->dir, j->log});
        j->view = j->views = 0;
        j->last_progress.clear();
        j->started = {};
      }
      // Scans that cannot have a namespace share the node's bus: one a node.
      const std::string id = queue.submit(*options_.slurm, tasks, !evaluations_ && !options_.netns);
      for (std::size_t i = 0; i < batch.size(); ++i) {
        task_of[batch[i]] = {arrays.size(), static_cast<int>(i)};
        ++submitted[batch[i]];
      }
      arrays.push_back({id, batch});
      live_.event("bench: " + std::to_string(batch.size()) + " " + noun_ + " submitted to Slurm, job array " + id + " (" +
                  (options_.root / "slurm").string() + ")");
    };
    const auto ids = [&] {
      std::vector<std::string> out;
      for (const Array& a : arrays) out.push_back(a.id);
      return out;
    };
    if (!todo.empty()) submit(todo);
    std::size_t waiting = todo.size();
    // Slurm's queue not answering (slurmctld down, the network): the launcher gives up after this
    // long; the tasks go on, and the same command resumes.
    constexpr double kQueueSilenceS = 600;
    auto answered = std::chrono::steady_clock::now();
    while (!task_of.empty()) {
      if (stop_requested()) {
        queue.cancel(ids());
        throw std::runtime_error(interrupted() + " (Slurm job arrays " + fmt::format("{}", fmt::join(ids(), ", ")) +
                                 " cancelled)");
      }
      const auto states = queue.states(ids());
      if (!states && std::chrono::duration<double>(std::chrono::steady_clock::now() - answered).count() > kQueueSilenceS) {
        throw std::runtime_error("Slurm's queue has not answered for " + fixed(kQueueSilenceS, 0) + " s (squeue: " +
                                 tail_lines((options_.root / "slurm" / "squeue.out").string(), 3) + "); job arrays " +
                                 fmt::format("{}", fmt::join(ids(), ", ")) +
                                 " were not cancelled: run the same command again to resume once Slurm answers");
      }
      if (states) {
        answered = std::chrono::steady_clock::now();
        std::vector<Job*> again;
        std::map<std::string, int> pending;  // Slurm's reasons for the tasks that wait
        running_.clear();
        waiting = 0;
        for (auto it = task_of.begin(); it != task_of.end();) {
          Job* j = it->first;
          const Array& a = arrays[it->second.first];
          const int task = it->second.second;
          const auto& tasks = states->at(a.id);
          const auto st = tasks.find(task);
          if (!task_ended(j, tasks, task)) {
            if (st != tasks.end() && st->second.state == "RUNNING") {
              if (j->started == std::chrono::steady_clock::time_point{}) {
                j->started = std::chrono::steady_clock::now();
                live_.event(prefix(j) + "started (Slurm task " + a.id + "_" + std::to_string(task) + ")");
              }
              running_.push_back(j);
            } else {
              ++waiting;
              if (st != tasks.end()) ++pending[st->second.state + (st->second.reason.empty() ? "" : " (" + st->second.reason + ")")];
            }
            ++it;
            continue;
          }
          if (slurm_task_ended(j, a.id, task, st == tasks.end() ? nullptr : &st->second, command[j], submitted[j] < 2)) {
            again.push_back(j);
          }
          it = task_of.erase(it);
        }
        waiting_note_.clear();
        for (const auto& [why, n] : pending) waiting_note_ += (waiting_note_.empty() ? "" : ", ") + std::to_string(n) + " " + why;
        if (!again.empty()) submit(again);
      }
      read_progress();
      if (live_.live()) show_live(waiting);
      std::this_thread::sleep_for(std::chrono::seconds(1));
    }
    live_.update({});
  }

  // Whether Slurm task `task` (of `tasks`, the states of its array) running `j` has ended: Slurm
  // says so, or Slurm no longer knows the task and its record is written. A task Slurm says
  // COMPLETED is given kRecordGraceS for its record to show (a shared file system may show a
  // node's files here a little later).
  bool task_ended(Job* j, const std::map<int, SlurmTaskState>& tasks, int task) {
    constexpr double kRecordGraceS = 30;
    const auto st = tasks.find(task);
    const bool recorded = fs::exists(j->dir / "bench_task.json");
    if (st == tasks.end()) return recorded;
    if (!st->second.ended()) return false;
    if (recorded || st->second.state != "COMPLETED") return true;
    const auto first = completed_seen_.try_emplace(j, std::chrono::steady_clock::now()).first->second;
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - first).count() > kRecordGraceS;
  }

  // Slurm task `job_id`_`task` running `j` ended (`state`: Slurm's last word on it, none when
  // Slurm no longer lists it): its record read, reported (finished). Returns whether it is to run
  // again: not complete, and `may_retry`.
  bool slurm_task_ended(Job* j, const std::string& job_id, int task, const SlurmTaskState* state,
                        const std::vector<std::string>& command, bool may_retry) {
    completed_seen_.erase(j);
    const bool recorded = fs::exists(j->dir / "bench_task.json");
    int exit_code = -1;
    double wall = j->started == std::chrono::steady_clock::time_point{}
                      ? 0.0
                      : std::chrono::duration<double>(std::chrono::steady_clock::now() - j->started).count();
    json record = {{"command", command}, {"slurm_job", job_id + "_" + std::to_string(task)}};
    if (recorded) {
      try {
        const json r = read_json((j->dir / "bench_task.json").string());
        exit_code = r.at("exit_code").get<int>();
        wall = r.at("wall_s").get<double>();
        record["host"] = r.value("host", "");
      } catch (const std::exception&) {
      }
    }
    const std::string slurm = !state ? "Slurm no longer lists it"
                                     : "Slurm: " + state->state +
                                           (state->reason.empty() || state->reason == "None" ? std::string()
                                                                                             : " (" + state->reason + ")");
    const bool retry = may_retry && !(exit_code == 0 && complete(j));
    finished(j, exit_code, wall, record, slurm + (recorded ? "" : ", no task record"), retry);
    return retry;
  }

  std::string prefix(const Job* j) const {
    return "[" + std::to_string(j - jobs_.data() + 1) + "/" + std::to_string(jobs_.size()) + "] " +
           (j->label.empty() ? "" : j->label + " ") +
           (j->evaluation ? "evaluation of " + j->name : j->run + " - " + std::string(name_of(j->planner))) + ": ";
  }

  [[noreturn]] void stop_every_task() {
    for (const Child& c : children_) ::kill(c.pid, SIGINT);  // each scan keeps what it has and stops its processes
    for (int i = 0; i < 500; ++i) {
      reap(children_);
      if (std::none_of(children_.begin(), children_.end(), [](const Child& c) { return c.running; })) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    stop_all(children_, 5.0);
    throw std::runtime_error(interrupted());
  }

  void start(Job* j) {
    prepare(j);
    fs::create_directories(j->dir.parent_path());
    fs::create_directories(j->log.parent_path());
    Child c;
    c.name = j->evaluation ? "evaluate-" + j->name : std::string(name_of(j->planner)) + "-" + j->run;
    c.argv = argv_of(j);
    c.log_path = j->log.string();
    j->started = std::chrono::steady_clock::now();
    pbnbv::process::start(c);
    children_.push_back(std::move(c));
    running_.push_back(j);
    live_.event(prefix(j) + "started");
  }

  void reap_finished() {
    for (const Child* c : reap(children_)) {
      Job* j = running_[c - children_.data()];
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - j->started).count();
      finished(j, c->exit_code, wall, json{{"command", c->argv}}, "");
    }
    for (std::size_t i = children_.size(); i-- > 0;) {
      if (children_[i].running) continue;
      children_.erase(children_.begin() + i);
      running_.erase(running_.begin() + i);
    }
  }

  // A task that ended with `exit_code` after `wall` s: done (a scan's bench_run.json: its wall
  // time and `record`), or failed with its reason (`why` first, when given). With `again`, a failed
  // task is not counted: the caller runs it once more.
  void finished(Job* j, int exit_code, double wall, json record, const std::string& why, bool again = false) {
    std::string evaluation_error;
    if (exit_code == 0 && complete(j, &evaluation_error)) {
      ++finished_;
      walls_.push_back(wall);
      std::string line;
      if (!j->evaluation) {
        record["wall_s"] = wall;
        write_json_atomic(record, (j->dir / "bench_run.json").string());
        try {
          const json cov = read_json((j->dir / "coverage.json").string());
          const auto& cv = cov.at("coverage_by_view");
          if (!cv.empty()) line = ", coverage after view " + std::to_string(cv.size()) + " " + fixed(cv.back().get<double>()) + " %";
        } catch (const std::exception&) {
        }
      }
      live_.event(prefix(j) + "done in " + fixed(wall, 0) + " s" + line + " (" + std::to_string(finished_) + " of " +
                  std::to_string(jobs_.size()) + " " + noun_ + " complete)");
      return;
    }
    if (!again) {
      ++finished_;
      walls_.push_back(wall);
    }
    std::string tail = tail_lines(j->log.string(), 6);
    while (!tail.empty() && tail.back() == '\n') tail.pop_back();
    const std::string reason = j->evaluation ? (evaluation_error.empty() ? "the evaluation failed" : evaluation_error)
                                             : scan_failure_reason(j->dir, j->log);
    live_.event(prefix(j) + "FAILED (exit " + std::to_string(exit_code) + "): " + (why.empty() ? "" : why + "; ") +
                reason + "; the end of " + j->log.string() + ":\n" + tail +
                (again ? "\n" + prefix(j) + "submitted once more" : ""));
  }

  // Progress: each scan's "[view k/N] ..." line; off a terminal printed when the view changes.
  void read_progress() {
    for (Job* j : running_) {
      if (j->evaluation) continue;
      const std::string last = tail_lines(j->log.string(), 1);
      const auto a = last.rfind("[view ");
      if (a == std::string::npos) continue;
      const std::string tag = last.substr(a, last.find(']', a) - a + 1);
      if (tag != j->last_progress) {
        j->last_progress = tag;
        std::sscanf(tag.c_str(), "[view %d/%d]", &j->view, &j->views);
        if (!live_.live()) live_.event(prefix(j) + tag.substr(1, tag.size() - 2));
      }
    }
  }

  // One line per running task, then the whole run's estimate: the tasks to go at the mean wall
  // time of those finished (else, for scans, of the running ones' estimates), spread over the jobs.
  void show_live(std::size_t waiting) {
    const auto now = std::chrono::steady_clock::now();
    std::vector<std::string> lines;
    double left_running = 0, projected = 0;
    int with_estimate = 0;
    for (const Job* j : running_) {
      const double elapsed = std::chrono::duration<double>(now - j->started).count();
      if (j->evaluation) {
        lines.push_back(prefix(j) + "evaluating, " + duration_text(elapsed));
        continue;
      }
      const int views = j->views > 0 ? j->views : j->spec->views;
      // prefix(j) ends in ": ", as the progress line of an empty name starts.
      lines.push_back(prefix(j) + scan_progress_line("", j->view, views, elapsed).substr(2));
      if (const auto left = scan_time_left_s(j->view, views, elapsed)) {
        left_running += *left;
        projected += elapsed + *left;
        ++with_estimate;
      }
    }
    std::string summary = "bench: " + std::to_string(finished_) + " of " + std::to_string(jobs_.size()) + " " + noun_ +
                          " done, " + std::to_string(running_.size()) + " running";
    const double per_task = !walls_.empty() ? std::accumulate(walls_.begin(), walls_.end(), 0.0) / walls_.size()
                            : with_estimate > 0 ? projected / with_estimate
                                                : NAN;
    if (std::isfinite(per_task)) {
      summary += ", about " +
                 duration_text((left_running + static_cast<double>(waiting) * per_task) / std::max(1, options_.jobs)) +
                 " left";
    }
    if (!waiting_note_.empty()) summary += "; " + waiting_note_;
    lines.push_back(summary);
    live_.update(lines);
  }

  const RunnerOptions& options_;
  std::vector<Job>& jobs_;
  fs::path self_;
  LiveLines live_;
  bool evaluations_ = false;
  std::string noun_;
  std::vector<Child> children_;  // the tasks running now: their processes and, at the same index,
  std::vector<Job*> running_;    // their jobs
  std::size_t next_ = 0;         // in todo
  int finished_;
  std::vector<double> walls_;  // of the tasks finished in this run
  std::string waiting_note_;   // Slurm: how many tasks wait and why ("3 pending (Resources)")
  std::map<Job*, std::chrono::steady_clock::time_point> completed_seen_;  // Slurm said COMPLETED, no record yet
};

// The log of the evaluation task of `spec`'s object `name`.
fs::path evaluation_log(const BenchSpec& spec, const std::string& name) {
  return spec.out / "logs" / ("evaluate-" + name + ".log");
}

// The evaluation tasks of `jobs` (scans, benches[i].second's): one per object of each bench, its
// request written (below the bench's evaluation/<object>/).
std::vector<Job> evaluation_jobs(const std::vector<Job>& jobs) {
  std::vector<Job> out;
  std::map<std::pair<const BenchSpec*, std::string>, std::vector<ScanJob>> scans;
  for (const Job& j : jobs) {
    auto& s = scans[{j.spec, j.name}];
    if (s.empty()) {
      Job e;
      e.spec = j.spec;
      e.label = j.label;
      e.evaluation = true;
      e.object = j.object;
      e.name = e.run = j.name;
      e.dir = j.spec->out / "evaluation" / j.name;
      e.log = evaluation_log(*j.spec, j.name);
      out.push_back(std::move(e));
    }
    s.push_back(j);
  }
  for (const Job& e : out) {
    fs::create_directories(e.dir);
    write_json_atomic(evaluation_request(*e.spec, scans.at({e.spec, e.name})), (e.dir / "request.json").string());
  }
  return out;
}

// The run of scan `j` in its object's evaluation record (`records`, by bench and object: none when
// the task wrote none, with why in `errors`).
ObjectRun recorded_run(const Job& j, const std::map<std::pair<const BenchSpec*, std::string>, ObjectEvaluation>& records,
                       const std::map<std::pair<const BenchSpec*, std::string>, std::string>& errors) {
  const auto key = std::make_pair(j.spec, j.name);
  const auto r = records.find(key);
  if (r != records.end()) {
    for (const ObjectRun& run : r->second.runs) {
      if (run.first_view == j.first_view && run.planner == j.planner) return run;
    }
  }
  ObjectRun run;
  run.object = j.name;
  run.first_view = j.first_view;
  run.initial_view = j.initial_view;
  run.planner = j.planner;
  const auto e = errors.find(key);
  run.error = "not evaluated: " + (r != records.end() ? "the evaluation's record has no such run"
                                   : e != errors.end() ? e->second
                                                       : std::string("no evaluation")) +
              " (log: " + evaluation_log(*j.spec, j.name).string() +
              "); run the same command again to evaluate it";
  return run;
}

}  // namespace

std::vector<BenchResult> run_benches(const std::vector<std::pair<std::string, BenchSpec>>& benches_in,
                                     const fs::path& root, const fs::path& self, std::ostream& log, bool terminal) {
  if (benches_in.empty()) throw std::invalid_argument("no benchmark to run");
  std::vector<std::pair<std::string, BenchSpec>> benches = benches_in;
  RunnerOptions options;
  options.jobs = benches.front().second.jobs;
  options.netns = benches.front().second.netns;
  options.slurm = benches.front().second.slurm;
  options.root = root;
  if (options.slurm) validate(*options.slurm);
  if (options.netns && !netns_available()) {
    log << "pbnbv bench: cannot create a private network namespace here (needs root or unprivileged user "
           "namespaces): every scan runs on the current LCM bus, one at a time"
        << std::endl;
    options.netns = false;
  }
  const int evaluation_jobs_at_once = options.jobs;  // the evaluations need no bus
  if (!options.netns) options.jobs = 1;
  std::vector<Job> jobs;
  for (auto& [label, spec] : benches) {
    spec.validate();
    spec.netns = options.netns;
    spec.jobs = options.jobs;
    fs::create_directories(spec.out / "logs");
    claim_folder(spec);
    for (Job& j : plan_jobs(spec)) {
      j.spec = &spec;
      j.label = label;
      jobs.push_back(std::move(j));
    }
  }
  std::vector<Job*> todo;
  for (auto& j : jobs) {
    if (!scan_complete(j.dir)) todo.push_back(&j);
  }
  for (const auto& [label, spec] : benches) {
    const int total = static_cast<int>(std::count_if(jobs.begin(), jobs.end(), [&](const Job& j) { return j.spec == &spec; }));
    const int left = static_cast<int>(std::count_if(todo.begin(), todo.end(), [&](const Job* j) { return j->spec == &spec; }));
    log << "pbnbv bench: " << (label.empty() ? "" : label + ": ") << spec.objects.size() << " objects x "
        << (spec.first_views > 1 ? std::to_string(spec.first_views) + " first views x " : std::string())
        << spec.planners.size() << " planners = " << total << " scans (" << total - left << " already complete in "
        << spec.out.string() << ")" << std::endl;
  }
  log << "pbnbv bench: " << todo.size() << " scans to run"
      << (benches.size() > 1 ? " of " + std::to_string(jobs.size()) + " in " + std::to_string(benches.size()) + " benchmarks" : "")
      << ", " << (options.slurm ? std::string("each a Slurm task") : std::to_string(options.jobs) + " at a time") << std::endl;
  TaskRunner(options, jobs, static_cast<int>(jobs.size() - todo.size()), self, log, terminal).run(todo);

  // Evaluation of every scan against the ground truth: one task per object of each bench.
  std::vector<Job> evaluations = evaluation_jobs(jobs);
  std::vector<Job*> to_evaluate;
  for (Job& e : evaluations) {
    if (!evaluation_current(e.dir)) to_evaluate.push_back(&e);
  }
  log << "pbnbv bench: evaluating the scans against the ground truth, one task per object: " << to_evaluate.size()
      << " to run (" << evaluations.size() - to_evaluate.size() << " recorded from the same scans), "
      << (options.slurm ? std::string("each a Slurm task") : std::to_string(evaluation_jobs_at_once) + " at a time")
      << std::endl;
  RunnerOptions evaluation_options = options;
  evaluation_options.jobs = evaluation_jobs_at_once;
  TaskRunner(evaluation_options, evaluations, static_cast<int>(evaluations.size() - to_evaluate.size()), self, log,
             terminal)
      .run(to_evaluate);
  std::map<std::pair<const BenchSpec*, std::string>, ObjectEvaluation> records;
  std::map<std::pair<const BenchSpec*, std::string>, std::string> errors;
  for (const Job& e : evaluations) {
    std::string error;
    if (auto r = read_evaluation(e.dir, &error)) {
      if (!r->observable.empty()) log << (e.label.empty() ? "" : e.label + ": ") << r->observable << std::endl;
      records.emplace(std::make_pair(e.spec, e.name), std::move(*r));
    } else {
      errors.emplace(std::make_pair(e.spec, e.name), error);
    }
  }

  std::vector<BenchResult> results;
  for (std::size_t b = 0; b < benches.size(); ++b) {
    const BenchSpec& spec = benches[b].second;
    BenchResult result;
    result.spec = spec;
    result.spec.jobs = benches_in[b].second.jobs;
    std::map<PlannerKind, std::vector<ObjectRun>> runs;
    for (const auto& j : jobs) {
      if (j.spec == &spec) runs[j.planner].push_back(recorded_run(j, records, errors));
    }
    for (const auto& p : spec.planners) result.planners.push_back(summarise(p, runs[p], spec.views));
    add_gaps_to_oracle(result.planners, spec.views);
    result.halves = summarise_halves(spec, result.planners);
    result.machine = machine_info();
    if (spec.slurm) {
      result.machine["slurm"] = {{"partition", spec.slurm->partition}, {"account", spec.slurm->account},
                                 {"time_limit", spec.slurm->time_limit}};
    } else {
      result.machine["scans_at_once"] = spec.jobs;
    }
    write_json_atomic(to_json(result), (spec.out / "summary.json").string());
    write_report(result);
    results.push_back(std::move(result));
  }
  return results;
}

BenchResult run_bench(const BenchSpec& spec, const fs::path& self, std::ostream& log, bool terminal) {
  return run_benches({{"", spec}}, spec.out, self, log, terminal).front();
}

std::vector<std::pair<std::string, BenchResult>> run_ablation(const std::string& param,
                                                              const std::vector<std::pair<std::string, BenchSpec>>& runs,
                                                              const fs::path& out, const fs::path& self, std::ostream& log,
                                                              bool terminal) {
  std::vector<std::pair<std::string, BenchSpec>> labelled;
  for (const auto& [value, spec] : runs) labelled.emplace_back(param + "=" + value, spec);
  const std::vector<BenchResult> results = run_benches(labelled, out, self, log, terminal);
  std::vector<std::pair<std::string, BenchResult>> by_value;
  for (std::size_t i = 0; i < runs.size(); ++i) by_value.emplace_back(runs[i].first, results[i]);
  write_ablation(param, by_value, out);
  return by_value;
}

}  // namespace pbnbv::eval
