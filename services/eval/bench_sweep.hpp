#pragma once
// Sweeps: `pbnbv bench` with a list of values for some of its settings (--rig, --rig-model,
// --camera, --rig-errors, --resolution, --first-views) runs one benchmark per combination of the
// values, each in a folder of its own named for it (DIR/resolution=0.01,camera=d435/), all their
// scans together (here or on Slurm: run_benches), then writes one table across them
// (DIR/sweep.md, sweep.json, sweep.png) beside each combination's own summary and report.
#include <filesystem>
#include <iosfwd>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "eval/bench.hpp"

namespace pbnbv::eval {

// The values a sweep takes for each setting (one value: not swept).
struct SweepValues {
  std::vector<RigKind> rigs{kBenchRig.value};
  std::vector<std::string> rig_models{""};  // "": the rig kind's own file
  std::vector<CameraKind> cameras{kCamera.value};
  std::vector<RigErrors> rig_errors{kRigErrors.value};
  std::vector<double> resolutions{kMapResolution.value};
  std::vector<int> first_views{kFirstViews.value};
};

struct Sweep {
  std::filesystem::path out;            // the sweep's folder
  std::vector<std::string> parameters;  // the settings swept (more than one value), in the labels' order
  // Each combination: its label ("resolution=0.01,camera=d435"; "" when nothing is swept) and its
  // benchmark (out: the sweep's folder / label; the sweep's folder itself when nothing is swept).
  std::vector<std::pair<std::string, BenchSpec>> benches;
  std::vector<std::vector<std::string>> values;  // per bench, each swept parameter's value as its label has it
  std::map<std::string, std::string> lists;      // per swept parameter, its values as options take them ("0.03,0.01")
};

// Every combination of `values` over `base` (its other settings, and its out as the sweep's
// folder), in the order rig, rig model, camera, rig errors, resolution, first views (the last
// varying fastest). A rig model's value in a label is its file's name without the extension.
// Throws std::invalid_argument naming the option for an empty list or a value listed twice (two
// rig models of the same name), and naming the combination when its benchmark does not validate.
Sweep expand_sweep(const BenchSpec& base, const SweepValues& values);

// Runs a sweep's benchmarks together (run_benches, root: sweep.out), then write_sweep. A folder
// that holds a benchmark of its own (bench.json) is refused, as a bench refuses a sweep's folder.
std::vector<BenchResult> run_sweep(const Sweep& sweep, const std::filesystem::path& self, std::ostream& log,
                                   bool terminal = false);

// sweep.json, sweep.md and sweep.png in sweep.out, from the combinations' results (in the
// order of sweep.benches): per combination and planner the runs complete and failed, the mean
// coverage after the last view with its 95 % interval, views to 95 %, the planner's median time,
// the rig time per scan and to 95 % of the observable surface (when measured), the rig's contacts;
// the plot: the mean coverage after each view, one curve per combination and planner.
void write_sweep(const Sweep& sweep, const std::vector<BenchResult>& results);

}  // namespace pbnbv::eval
