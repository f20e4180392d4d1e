#pragma once
// The benchmark's evaluation: each scan of a bench folder against the ground truth, one object at
// a time. An object's scans are evaluated together (they share its observable-surface mask) by a
// task of their own, a process the launcher runs beside the others, or a Slurm task on a node:
// the launcher writes the task's request (evaluation/<object>/request.json: the settings the
// evaluation reads and the object's scans), the task writes its record (evaluation.json: every
// run as an ObjectRun, exactly), and the launcher summarises the records as it would its own.
#include <Eigen/Core>
#include <filesystem>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "eval/bench.hpp"

namespace pbnbv::eval {

// One scan of a benchmark as its evaluation needs it.
struct ScanJob {
  std::string object;   // as given (a name or a mesh path)
  std::string name;     // the object's name
  int first_view = 1;   // 1: the scan's default; 2..N: initial_view, drawn
  std::optional<Eigen::Vector3d> initial_view;
  std::string run;      // run_folder(name, first_view)
  PlannerKind planner = PlannerKind::kPbnbv;
  std::filesystem::path dir;  // the scan's folder
  std::filesystem::path log;  // its log
};

// True when `dir` holds a scan that ended "done" (scan.json and processes.json).
bool scan_complete(const std::filesystem::path& dir);

// True when `dir` holds an interrupted scan that `pbnbv scan --resume` continues: its launcher
// wrote processes.json and settings.json and its coordinator wrote scan.json. A scan interrupted
// before its first record (no scan.json) has nothing to continue from: it is started anew.
bool scan_resumable(const std::filesystem::path& dir);

// One scan of the folder against the ground truth (its object's observable-surface mask made once
// and kept in `masks`, a line naming it written to `log`); a scan that is not complete, or fails
// to evaluate, is a run with its error. Reads spec.views, coverage, metrics, stop_rule and
// seconds_rule.
ObjectRun evaluate_run(const BenchSpec& spec, const ScanJob& job, std::map<std::string, std::vector<uint8_t>>& masks,
                       std::ostream& log);

// A run as an evaluation task records it: every field, doubles exact (17 digits; NaN as null),
// and back. run_from_record throws std::invalid_argument naming the field that is missing or of
// the wrong type.
nlohmann::json run_record(const ObjectRun& r);
ObjectRun run_from_record(const nlohmann::json& j);

// The request of the task evaluating `jobs` (the scans of one object) of `spec`: what evaluate_run
// reads of the spec, exactly, the bench folder, the scans and their files' stamps, the version.
nlohmann::json evaluation_request(const BenchSpec& spec, const std::vector<ScanJob>& jobs);

// `pbnbv bench-evaluate REQUEST`: evaluates the request's scans and writes evaluation.json beside
// the request (atomically). Refuses (std::invalid_argument naming the field) a request that is
// not one: a field missing or out of its range, a scan folder or log outside the bench folder.
void run_evaluation_task(const std::filesystem::path& request, std::ostream& log);

// True when `dir` holds a record made from its request.json as it is now: the same settings and
// pbnbv version, the same scans with the same files (each file's size and time of last change).
// A rerun of a finished bench keeps such records instead of evaluating again.
bool evaluation_current(const std::filesystem::path& dir);

// An evaluation task's record: its request, its object, the line on its observable surface, its runs.
struct ObjectEvaluation {
  nlohmann::json request;  // the request it was made from
  std::string object;
  std::string observable;  // "bunny: observable surface: 120 of 200 candidates reachable; they see 97.1 % of the surface" ("": none made)
  std::vector<ObjectRun> runs;
};
// The record in `dir` (evaluation.json); none with `error` saying why when there is none or it
// does not parse.
std::optional<ObjectEvaluation> read_evaluation(const std::filesystem::path& dir, std::string* error = nullptr);

}  // namespace pbnbv::eval
