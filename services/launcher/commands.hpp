#pragma once
// Running the commands of `pbnbv` once the command line is parsed (command_line.hpp). Each
// returns the process exit code.
#include <filesystem>
#include <ostream>

#include "eval/bench.hpp"
#include "launcher/command_line.hpp"

namespace pbnbv::launcher {

// `pbnbv scan`: normalises the object, starts the twin and every service as separate processes
// (plus lcm-logger), supervises them while the coordinator scans, stops them all at the end, on
// Ctrl-C, or when one fails, and evaluates the scan against the twin's ground truth. `bin` is
// the folder of the pbnbv executables. 0: the scan is done; 130: interrupted; else failed.
int run_scan(const ScanOptions& o, const std::filesystem::path& bin);

// `pbnbv bench`: the benchmark (eval::run_bench), its report printed. `self`: the pbnbv
// executable that runs each scan. 1 when a scan did not complete.
int run_bench(const eval::BenchSpec& spec, const std::filesystem::path& self);
// `pbnbv bench` with lists (eval::run_sweep): every combination's benchmark, the table across
// them printed. 1 when a scan did not complete.
int run_sweep(const eval::Sweep& sweep, const std::filesystem::path& self);

// `pbnbv ablate`: one benchmark per value (eval::run_ablation), the ablation's table printed.
int run_ablate(const AblateOptions& o, const std::filesystem::path& self);

// `pbnbv spy`: lcm-spy with the project's message types (replaces this process).
int run_spy();

// `pbnbv calibrate`: hand-eye and turntable calibration with the drivers on the bus (the twin or
// the real rig): rig_calibrated.xml, calibration.json and report.md in the output folder. 0: done.
// Throws naming what is missing (a silent driver, too few views with the sphere).
int run_calibrate(const CalibrateOptions& o);
// `pbnbv replay`: the recorded scan in o.dir run through the pipeline again with its own frames and
// poses (pbnbv-replay-rig plays its scan.lcmlog instead of the twin; the coordinator follows its
// views and records this planner's plans), then replay.json and a table: per view, the recording's
// decisions against the replay's. Throws std::invalid_argument naming what is missing or wrong in
// the folder before anything starts. 0: the replay completed (see replay.json for differences).
int run_replay(const ReplayOptions& o, const std::filesystem::path& bin);
// `pbnbv mesh DIR`: the scan's surface mesh again (core/surface), into DIR and its scan.json.
int run_mesh(const MeshOptions& o);

// `pbnbv evaluate`: o.target against the reference mesh (core/metrics/surface_metrics.hpp), a table
// printed to `out` and, with o.json, the figures written there. A scan folder without --reference
// is evaluated as `pbnbv scan` does (coverage and the metrics against its object.stl). Throws
// std::runtime_error naming the file and what is wrong with it (missing, unreadable, a cloud
// without points, a mesh without faces, a folder without a model or a reference). 0: evaluated;
// 1: a twin scan folder's mesh.ply could not be (said, with why; the rest is evaluated).
int run_evaluate(const EvaluateOptions& o, std::ostream& out);

// `pbnbv stop`: STOP on the bus (three times over 0.2 s: UDP may lose one).
int run_stop(const StopOptions& o);

// `pbnbv rig-host`: the motion executor and the camera service, serving every scan on the bus,
// kept running (a crashed one is started again, up to 3 times) until Ctrl-C.
int run_rig_host(const RigHostOptions& o, const std::filesystem::path& bin);

// `pbnbv import-urdf`: writes the arm's MJCF and says what to do next with it.
int run_import_urdf(const ImportUrdfOptions& o);
// `pbnbv rig-check`: rigcheck::rig_check (or preflight with --passive) on the bus, its table
// printed. 0 only when every line passed; 1 otherwise.
int run_rig_check(const RigCheckOptions& o);

}  // namespace pbnbv::launcher
