#pragma once
// Running the commands of `pbnbv` once the command line is parsed (command_line.hpp). Each
// returns the process exit code.
#include <filesystem>

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

// `pbnbv ablate`: one benchmark per value (eval::run_ablation), the ablation's table printed.
int run_ablate(const AblateOptions& o, const std::filesystem::path& self);

// `pbnbv spy`: lcm-spy with the project's message types (replaces this process).
int run_spy();

// `pbnbv replay`: the recorded scan in o.dir run through the pipeline again with its own frames and
// poses (pbnbv-replay-rig plays its scan.lcmlog instead of the twin; the coordinator follows its
// views and records this planner's plans), then replay.json and a table: per view, the recording's
// decisions against the replay's. Throws std::invalid_argument naming what is missing or wrong in
// the folder before anything starts. 0: the replay completed (see replay.json for differences).
int run_replay(const ReplayOptions& o, const std::filesystem::path& bin);

// `pbnbv stop`: STOP on the bus (three times over 0.2 s: UDP may lose one).
int run_stop(const StopOptions& o);

}  // namespace pbnbv::launcher
