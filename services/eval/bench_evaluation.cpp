// The benchmark's evaluation, one object at a time, as a task (bench_evaluation.hpp).
#include "eval/bench_evaluation.hpp"

#include <cmath>
#include <limits>
#include <numeric>
#include <ostream>
#include <stdexcept>

#include "core/base/enum_names.hpp"
#include "core/base/format.hpp"
#include "core/base/version.hpp"
#include "core/geometry/views.hpp"
#include "core/geometry/visibility.hpp"
#include "core/io/json.hpp"
#include "core/io/json_fields.hpp"
#include "core/io/mesh_file.hpp"
#include "core/planning/planner.hpp"
#include "core/rig/rig.hpp"
#include "core/scan/scan_file.hpp"
#include "core/scan/scan_record.hpp"
#include "core/scan/scan_settings.hpp"
#include "eval/evaluate.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv::eval {

namespace {

constexpr const char* kRequestKind = "pbnbv bench evaluation request";
constexpr const char* kRecordKind = "pbnbv bench evaluation";
constexpr std::size_t kMaxRequestJobs = 1000;  // runs of one object: first views x planners
// A request or record of 1000 runs is a few MB; a file far larger is not one.
constexpr std::uintmax_t kMaxFileBytes = 256u << 20;

// A request's or record's JSON; throws naming the file when it is not a regular file of at most
// kMaxFileBytes or does not parse.
json read_task_file(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw std::runtime_error(path.string() + ": not a file");
  if (fs::file_size(path, ec) > kMaxFileBytes) {
    throw std::runtime_error(path.string() + ": over " + std::to_string(kMaxFileBytes >> 20) + " MiB, not one of pbnbv bench's");
  }
  return read_json(path.string());
}

// The samples of the object's coverage evaluation that at least one reachable candidate view can
// see: candidates as the planner generates them around the object's bounding box (B at the end
// of a scan), filtered by the rig's reachability check, visibility by ray casting the true mesh.
std::vector<uint8_t> observable_mask(const BenchSpec& spec, const fs::path& scan_dir, std::string* summary) {
  const ScanSettings s = scan_settings_from_json(read_json((scan_dir / "settings.json").string()));
  const TriangleMesh mesh = load_mesh((scan_dir / "object.stl").string());
  const SurfaceSamples samples = sample_surface_with_normals(mesh, spec.coverage.num_samples, spec.coverage.seed);
  const Eigen::Vector3d half = s.normalisation.extent_m / 2.0;
  CandidateSpec cs;
  cs.num_views = s.candidates;
  cs.num_parallels = s.parallels;
  cs.area = s.area;
  cs.working_distance_m = s.working_distance_m;
  const std::vector<Pose> candidates = candidate_views(Eigen::AlignedBox3d(-half, half), cs);
  const RigModel rig = load_rig(s.rig_model_path);
  ReachabilityChecker checker(rig);
  const Eigen::AlignedBox3d keepout(s.keepout_min_m, s.keepout_max_m);
  const std::vector<ViewSolution> reach = checker.solve_batch(candidates, rig.q_home, 0.0, keepout, s.object_z_m);
  std::vector<Pose> reachable;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (reach[i].reachable) reachable.push_back(candidates[i]);
  }
  VisibilityParams vp;
  vp.camera = s.camera;
  vp.range = s.depth_range;
  const std::vector<uint8_t> mask = visible_from_any(mesh, samples.points, samples.normals, reachable, vp);
  const double seen = std::accumulate(mask.begin(), mask.end(), 0.0);
  if (summary) {
    *summary = std::to_string(reachable.size()) + " of " + std::to_string(candidates.size()) +
               " candidates reachable; they see " + fixed(100.0 * seen / std::max<std::size_t>(mask.size(), 1)) +
               " % of the surface";
  }
  return mask;
}

// Doubles exactly, NaN (and infinities, which JSON has not either) as null.
json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
json numbers(const std::vector<double>& v) {
  json a = json::array();
  for (double x : v) a.push_back(number(x));
  return a;
}
json point(const std::optional<Eigen::Vector3d>& p) { return p ? pbnbv::to_json(*p) : json(nullptr); }
json stats(const DistanceStats& s) {
  return {{"count", s.count}, {"mean_m", number(s.mean_m)}, {"median_m", number(s.median_m)},
          {"rmse_m", number(s.rmse_m)}, {"p95_m", number(s.p95_m)}, {"max_m", number(s.max_m)}};
}
json metrics(const std::optional<SurfaceMetrics>& m) {
  if (!m) return nullptr;
  return {{"model", m->model},         {"threshold_m", number(m->threshold_m)}, {"accuracy", stats(m->accuracy)},
          {"completeness", stats(m->completeness)}, {"precision", number(m->precision)},
          {"recall", number(m->recall)}, {"f_score", number(m->f_score)}, {"skipped_points", m->skipped_points}};
}

// Reading back (core/io/json_fields.hpp): an error names the field and what is wrong with it.
using Fields = JsonFields;

// A whole number in [0, hi] or none (null).
std::optional<int> optional_count(const Fields& f, const char* key) {
  return f.has(key) ? std::optional<int>(f.count(key)) : std::nullopt;
}

DistanceStats stats_from(const Fields& f) {
  DistanceStats s;
  s.count = static_cast<std::size_t>(f.integer("count", 0, INT64_MAX));
  s.mean_m = f.number("mean_m");
  s.median_m = f.number("median_m");
  s.rmse_m = f.number("rmse_m");
  s.p95_m = f.number("p95_m");
  s.max_m = f.number("max_m");
  return s;
}
std::optional<SurfaceMetrics> metrics_from(const Fields& f, const char* key) {
  if (!f.has(key)) return std::nullopt;
  const Fields m = f.object(key);
  SurfaceMetrics s;
  s.model = m.text("model");
  s.threshold_m = m.number("threshold_m");
  s.accuracy = stats_from(m.object("accuracy"));
  s.completeness = stats_from(m.object("completeness"));
  s.precision = m.number("precision");
  s.recall = m.number("recall");
  s.f_score = m.number("f_score");
  s.skipped_points = static_cast<std::size_t>(m.integer("skipped_points", 0, INT64_MAX));
  return s;
}

PlannerKind planner_from(const Fields& f, const char* key) {
  try {
    return parse_name<PlannerKind>(f.text(key));
  } catch (const std::invalid_argument& e) {
    f.fail(key, e.what());
  }
}

// `p` lexically inside `root` (both absolute): no "..", no other root.
bool inside(const fs::path& p, const fs::path& root) {
  if (!p.is_absolute()) return false;
  const fs::path n = p.lexically_normal(), r = root.lexically_normal();
  const fs::path rel = n.lexically_relative(r);
  return !rel.empty() && *rel.begin() != ".." && rel != ".";
}

// The files at the top of a scan's folder, each with its size and time of last change (ns): what
// its evaluation reads, so a record made from the same is still the scan's.
json file_stamps(const fs::path& dir) {
  json files = json::object();
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file() || it->path().filename() == "bench_task.json") continue;
    const auto size = fs::file_size(it->path(), ec);
    const auto time = fs::last_write_time(it->path(), ec);
    if (ec) continue;
    files[it->path().filename().string()] = {size, static_cast<int64_t>(time.time_since_epoch().count())};
  }
  return files;
}

}  // namespace

bool scan_complete(const fs::path& dir) {
  try {
    if (!fs::exists(dir / "scan.json") || !fs::exists(dir / "processes.json")) return false;
    return recorded_state(dir) == "done";
  } catch (const std::exception&) {
    return false;
  }
}

bool scan_resumable(const fs::path& dir) {
  return fs::exists(dir / "processes.json") && fs::exists(dir / "settings.json") && fs::exists(dir / "scan.json");
}

ObjectRun evaluate_run(const BenchSpec& spec, const ScanJob& j, std::map<std::string, std::vector<uint8_t>>& masks,
                       std::ostream& log) {
  ObjectRun r;
  r.object = j.name;
  r.first_view = j.first_view;
  r.initial_view = j.initial_view;  // until the scan's record says where it started
  r.planner = j.planner;
  try {
    // The rig's contacts, whether the scan completed or not (a contact may be why it did not).
    if (fs::exists(j.dir / "scan.json")) {
      const std::vector<RigContactRecord> contacts = rig_contacts(read_scan_record(j.dir).views);
      r.rig_contacts = rig_contact_events(contacts);
      for (const RigContactRecord& c : contacts) r.rig_contact_list.push_back(to_string(c));
    }
    if (!scan_complete(j.dir)) throw std::runtime_error(scan_failure_reason(j.dir, j.log));
    if (!masks.count(j.name)) {
      std::string what;
      masks[j.name] = observable_mask(spec, j.dir, &what);
      log << j.name << ": observable surface: " << what << std::endl;
    }
    const ScanEvaluation e = evaluate_scan(j.dir, spec.coverage, &masks[j.name], spec.metrics);
    r.coverage_by_view = pad_views(e.coverage_by_view, spec.views);
    r.observable_by_view = pad_views(e.observable_by_view, spec.views);
    r.planner_ms = e.planner_ms;
    r.planner_critical_ms = e.planner_critical_ms;
    r.views_to_95 = views_to_reach(r.coverage_by_view, 95.0);
    r.views_done = e.views_done;
    r.stop_reason = e.stop_reason;
    r.new_surface_by_view = e.new_surface_by_view;
    r.rig_time_by_view = pad_views(e.rig_time_s_by_view, spec.views);
    if (e.rig_time.views > 0 && e.rig_time.views_incomplete == 0) r.rig_time = e.rig_time.sum;
    r.cloud_metrics = e.cloud_metrics;
    r.mesh_metrics = e.mesh_metrics;
    if (const auto d = first_surface_stop(e.new_surface_by_view, spec.stop_rule); d && d->after_views < spec.views) {
      r.stop_view = d->after_views;
      r.stop_rule_reason = d->reason;
    }
    if (const auto d = first_seconds_stop(e.view_gains, spec.seconds_rule); d && d->after_views < spec.views) {
      r.seconds_stop_view = d->after_views;
      r.seconds_stop_reason = d->reason;
    }
    r.complete = true;
    const std::optional<ScanPlanHeader> plan = read_scan_record(j.dir).plan;
    if (plan && plan->planner != "ring") r.initial_view = plan->initial_view.translation();
    if (fs::exists(j.dir / "bench_run.json")) r.wall_s = read_json((j.dir / "bench_run.json").string()).value("wall_s", 0.0);
  } catch (const std::exception& x) {
    r.error = x.what();
  }
  return r;
}

json run_record(const ObjectRun& r) {
  json j = {{"object", r.object},
            {"first_view", r.first_view},
            {"initial_view", point(r.initial_view)},
            {"planner", std::string(name_of(r.planner))},
            {"complete", r.complete},
            {"error", r.error},
            {"coverage_by_view", numbers(r.coverage_by_view)},
            {"observable_by_view", numbers(r.observable_by_view)},
            {"planner_ms", numbers(r.planner_ms)},
            {"planner_critical_ms", numbers(r.planner_critical_ms)},
            {"views_to_95", r.views_to_95 ? json(*r.views_to_95) : json(nullptr)},
            {"views_done", r.views_done},
            {"stop_reason", r.stop_reason},
            {"wall_s", number(r.wall_s)},
            {"rig_time_by_view", numbers(r.rig_time_by_view)},
            {"new_surface_by_view", numbers(r.new_surface_by_view)},
            {"stop_view", r.stop_view ? json(*r.stop_view) : json(nullptr)},
            {"stop_rule_reason", r.stop_rule_reason},
            {"seconds_stop_view", r.seconds_stop_view ? json(*r.seconds_stop_view) : json(nullptr)},
            {"seconds_stop_reason", r.seconds_stop_reason},
            {"cloud_metrics", metrics(r.cloud_metrics)},
            {"mesh_metrics", metrics(r.mesh_metrics)},
            {"rig_contacts", r.rig_contacts},
            {"rig_contact_list", r.rig_contact_list}};
  j["rig_time"] = r.rig_time ? json{{"motion_s", number(r.rig_time->motion_s)},
                                    {"settle_s", number(r.rig_time->settle_s)},
                                    {"capture_s", number(r.rig_time->capture_s)},
                                    {"compute_s", number(r.rig_time->compute_s)}}
                             : json(nullptr);
  return j;
}

ObjectRun run_from_record(const json& j) {
  const Fields f(j, "run");
  ObjectRun r;
  r.object = f.text("object");
  r.first_view = f.count("first_view");
  if (f.has("initial_view")) r.initial_view = f.vector3("initial_view");
  r.planner = planner_from(f, "planner");
  r.complete = f.flag("complete");
  r.error = f.text("error");
  r.coverage_by_view = f.list<double>("coverage_by_view");
  r.observable_by_view = f.list<double>("observable_by_view");
  r.planner_ms = f.list<double>("planner_ms");
  if (f.has("planner_critical_ms")) r.planner_critical_ms = f.list<double>("planner_critical_ms");
  r.views_to_95 = optional_count(f, "views_to_95");
  r.views_done = f.count("views_done");
  r.stop_reason = f.text("stop_reason");
  r.wall_s = f.number("wall_s");
  r.rig_time_by_view = f.list<double>("rig_time_by_view");
  if (f.has("rig_time")) {
    const Fields t = f.object("rig_time");
    r.rig_time = RigTime{t.number("motion_s"), t.number("settle_s"), t.number("capture_s"), t.number("compute_s")};
  }
  r.new_surface_by_view = f.list<double>("new_surface_by_view");
  r.stop_view = optional_count(f, "stop_view");
  r.stop_rule_reason = f.text("stop_rule_reason");
  r.seconds_stop_view = optional_count(f, "seconds_stop_view");
  r.seconds_stop_reason = f.text("seconds_stop_reason");
  r.cloud_metrics = metrics_from(f, "cloud_metrics");
  r.mesh_metrics = metrics_from(f, "mesh_metrics");
  r.rig_contacts = f.integer("rig_contacts", 0, INT64_MAX);
  r.rig_contact_list = f.list<std::string>("rig_contact_list");
  return r;
}

json evaluation_request(const BenchSpec& spec, const std::vector<ScanJob>& jobs) {
  json scans = json::array();
  for (const ScanJob& j : jobs) {
    scans.push_back({{"object", j.object}, {"name", j.name}, {"first_view", j.first_view},
                     {"initial_view", point(j.initial_view)}, {"run", j.run},
                     {"planner", std::string(name_of(j.planner))}, {"dir", j.dir.string()}, {"log", j.log.string()},
                     {"files", file_stamps(j.dir)}});
  }
  return {{"kind", kRequestKind},
          {"pbnbv_version", std::string(pbnbv_version())},
          {"bench", spec.out.string()},
          {"views", spec.views},
          {"coverage", {{"num_samples", spec.coverage.num_samples}, {"seed", spec.coverage.seed}, {"radius_m", spec.coverage.radius_m}}},
          {"metrics", {{"threshold_m", spec.metrics.threshold_m}, {"samples_per_cm2", spec.metrics.samples_per_cm2}, {"seed", spec.metrics.seed}}},
          {"stop_rule", {{"window", spec.stop_rule.window}, {"max_new_percent", spec.stop_rule.max_new_percent}, {"min_views", spec.stop_rule.min_views}}},
          {"seconds_rule", {{"window", spec.seconds_rule.window}, {"min_percent_per_s", spec.seconds_rule.min_percent_per_s}, {"min_views", spec.seconds_rule.min_views}}},
          {"scans", scans}};
}

void run_evaluation_task(const fs::path& request, std::ostream& log) {
  const json q = read_task_file(request);
  const Fields f(q, request.string());
  if (f.text("kind") != kRequestKind) f.fail("kind", "is not \"" + std::string(kRequestKind) + "\"");
  BenchSpec spec;
  spec.out = f.text("bench");
  if (!spec.out.is_absolute()) f.fail("bench", "is not an absolute path");
  spec.views = static_cast<int>(f.integer("views", kViews.min, kViews.max));
  const Fields c = f.object("coverage");
  spec.coverage.num_samples = static_cast<std::size_t>(c.integer("num_samples", 1, 10'000'000));
  spec.coverage.seed = static_cast<std::uint64_t>(c.integer("seed", 0, INT64_MAX));
  spec.coverage.radius_m = c.number("radius_m");
  if (!(spec.coverage.radius_m > 0 && spec.coverage.radius_m < 1)) c.fail("radius_m", "is not above 0 and under 1 m");
  const Fields m = f.object("metrics");
  spec.metrics.threshold_m = m.number("threshold_m");
  spec.metrics.samples_per_cm2 = m.number("samples_per_cm2");
  spec.metrics.seed = static_cast<std::uint64_t>(m.integer("seed", 0, INT64_MAX));
  spec.metrics.validate();
  const Fields s = f.object("stop_rule");
  spec.stop_rule = {static_cast<int>(s.integer("window", kStopWindow.min, kStopWindow.max)),
                    kStopNewSurface.checked(s.number("max_new_percent")),
                    static_cast<int>(s.integer("min_views", kStopMinViews.min, kStopMinViews.max))};
  const Fields t = f.object("seconds_rule");
  spec.seconds_rule = {static_cast<int>(t.integer("window", kStopRateViews.min, kStopRateViews.max)),
                       kStopGainPerSecond.checked(t.number("min_percent_per_s")),
                       static_cast<int>(t.integer("min_views", kStopMinViews.min, kStopMinViews.max))};
  const json& scans = f.at("scans");
  if (!scans.is_array() || scans.empty() || scans.size() > kMaxRequestJobs) {
    f.fail("scans", "is not a list of 1 to " + std::to_string(kMaxRequestJobs) + " scans");
  }
  ObjectEvaluation out;
  std::map<std::string, std::vector<uint8_t>> masks;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const Fields sj(scans[i], f.name("scans") + " " + std::to_string(i));
    ScanJob job;
    job.object = sj.text("object");
    job.name = sj.text("name");
    job.first_view = sj.count("first_view");
    if (sj.has("initial_view")) job.initial_view = sj.vector3("initial_view");
    job.run = sj.text("run");
    job.planner = planner_from(sj, "planner");
    job.dir = sj.text("dir");
    job.log = sj.text("log");
    if (!inside(job.dir, spec.out)) sj.fail("dir", job.dir.string() + " is not inside the bench folder " + spec.out.string());
    if (!inside(job.log, spec.out)) sj.fail("log", job.log.string() + " is not inside the bench folder " + spec.out.string());
    if (i == 0) out.object = job.name;
    if (job.name != out.object) sj.fail("name", job.name + " is another object than the request's " + out.object);
    log << "evaluating " << job.run << " - " << name_of(job.planner) << std::endl;
    std::ostringstream observable;
    out.runs.push_back(evaluate_run(spec, job, masks, observable));
    if (!observable.str().empty()) {
      log << observable.str();
      out.observable = observable.str().substr(0, observable.str().find_last_not_of('\n') + 1);
    }
    const ObjectRun& r = out.runs.back();
    log << "  " << (r.complete ? "evaluated" : "not evaluated: " + r.error) << std::endl;
  }
  json runs = json::array();
  for (const ObjectRun& r : out.runs) runs.push_back(run_record(r));
  write_json_atomic({{"kind", kRecordKind}, {"request", q}, {"object", out.object}, {"observable", out.observable}, {"runs", runs}},
                    (request.parent_path() / "evaluation.json").string());
}

std::optional<ObjectEvaluation> read_evaluation(const fs::path& dir, std::string* error) {
  const fs::path file = dir / "evaluation.json";
  try {
    if (!fs::exists(file)) throw std::runtime_error(file.string() + " was not written");
    const json j = read_task_file(file);
    const Fields f(j, file.string());
    if (f.text("kind") != kRecordKind) f.fail("kind", "is not \"" + std::string(kRecordKind) + "\": not an evaluation record");
    ObjectEvaluation e;
    e.request = f.at("request");
    e.object = f.text("object");
    e.observable = f.text("observable");
    const json& runs = f.at("runs");
    if (!runs.is_array()) f.fail("runs", "is not a list");
    for (const json& r : runs) e.runs.push_back(run_from_record(r));
    return e;
  } catch (const std::exception& x) {
    if (error) *error = x.what();
    return std::nullopt;
  }
}

bool evaluation_current(const fs::path& dir) {
  try {
    const std::optional<ObjectEvaluation> e = read_evaluation(dir);
    return e && e->request == read_task_file(dir / "request.json");
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace pbnbv::eval
