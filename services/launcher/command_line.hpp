#pragma once
// The command line of `pbnbv` (CLI11, cli/options.hpp): the commands scan, bench, ablate, spy, stop,
// replay, evaluate and help, each with its options from the table of scan options (defaults, ranges and help text
// written once, in core/*/..._options.hpp and eval/bench.hpp), per-command --help, --version,
// and settings files (--config FILE, TOML; the command line overrides the file). Parsing only:
// running a command is scan_command.hpp / commands.hpp.
#include <Eigen/Core>

#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "core/io/mesh_file.hpp"
#include "cli/options.hpp"
#include "core/metrics/surface_metrics.hpp"
#include "core/rig/calibration.hpp"
#include "core/scan/scan_settings.hpp"
#include "core/surface/surface.hpp"
#include "eval/bench.hpp"
#include "eval/bench_sweep.hpp"

namespace pbnbv::launcher {

enum class Command { kHelp, kScan, kBench, kAblate, kSpy, kStop, kRigCheck, kRigHost, kImportUrdf, kCalibrate, kReplay, kEvaluate, kMesh };

// What `pbnbv calibrate` was asked for (core/rig/calibration.hpp).
struct CalibrateOptions {
  std::string rig_model;          // the rig file to calibrate
  CalibrationSphere sphere;
  int views = 24;                 // arm poses (each at its own turntable angle)
  double speed_scale = 0.5;       // fraction of the joint speed limits
  double status_wait_s = 5;       // the drivers' first statuses must come within this
  bool fixed_axis = false;        // keep the model's turntable axis (else estimated and reported)
  std::string out;                // empty: out/calibration-<date-time>
};

// What `pbnbv stop` was asked for.
struct StopOptions {
  std::string scan_id;  // "" : every scan on the bus
  std::string reason = "stopped by the user";
};

// What `pbnbv rig-host` was asked for: the rig's computer runs the motion executor and the camera
// service beside the drivers; the scans come from another host (pbnbv scan --external-rig --rig-host).
struct RigHostOptions {
  std::string rig_model;            // the rig file ("" : models/rig_arm.xml)
  std::string logs = "rig-host-logs";  // their logs
};

// What `pbnbv import-urdf` was asked for.
struct ImportUrdfOptions {
  std::string urdf;  // the arm's URDF
  std::string out;   // the MJCF to write ("" : the URDF's name with .xml)
};

// What `pbnbv rig-check` was asked for.
struct RigCheckOptions {
  std::string rig_model;  // the rig file the drivers are held to
  double deadline_s = 5;  // per driver answer
  bool passive = false;   // --passive: the preflight only, nothing commanded to move
};

// What `pbnbv evaluate` was asked for: a scan folder, cloud or mesh against a reference mesh.
struct EvaluateOptions {
  std::string target;            // a scan folder, a cloud (.ply .pcd) or a mesh (.ply .obj .stl .off)
  std::string reference;         // the reference mesh ("": the scan folder's object.stl)
  double reference_scale = 1.0;  // the reference's coordinates times this (0.001: a file in mm)
  MetricParams metrics;          // threshold, sample density
  std::string json;              // write the figures here too ("": no file)
};

// What `pbnbv replay` was asked for.
struct ReplayOptions {
  std::string dir;                     // the recorded scan's folder
  std::string out;                     // empty: DIR-replay-<date-time> beside it
  std::optional<PlannerKind> planner;  // none: the recording's
  bool overwrite = false;
};

// What `pbnbv mesh` was asked for: the scan folder and the surface settings.
struct MeshOptions {
  std::string dir;
  SurfaceSettings surface;
  bool stl = false;  // --stl: mesh.stl too
  LengthUnit units = LengthUnit::kMetre;  // --units: of mesh.obj and mesh.stl
};

// What `pbnbv scan` was asked for: the object, the scan's settings (ScanSettings, before the
// object places them), what the launcher passes to the twin and the other processes.
struct ScanOptions {
  std::string object = "bunny";  // a mesh path or a built-in name
  double size_m = kObjectSize.value;
  std::optional<UpAxis> up;      // none: the object's own
  ScanSettings settings;         // rig, planner, views, ..., camera, with every default resolved
  bool registration = true;      // --registration on|off, resolved (on arm, off free)
  // The twin's depth noise and pose-error model.
  double noise_sigma = kDepthNoise.value;
  double dropout = kDropout.value;
  double hand_eye_error_mm = kHandEyeErrorMm.value;
  double hand_eye_error_deg = kHandEyeErrorDeg.value;
  double turntable_error_deg = kTurntableErrorDeg.value;
  double joint_error_deg = kJointErrorDeg.value;
  double turntable_backlash_deg = kTurntableBacklashDeg.value;
  RigErrors rig_errors = kRigErrors.value;  // --rig-errors: the figures above where not given one by one
  int64_t error_seed = kErrorSeed.value;
  bool record_log = true;        // not --no-log
  bool surface_metrics = true;   // not --no-surface-metrics
  LengthUnit mesh_units = LengthUnit::kMetre;  // --units: mesh.obj's (and `pbnbv mesh --stl`'s) length unit
  // A rig whose drivers run outside (--external-rig): no twin, an unknown object.
  bool external_rig = false;
  std::string working_volume;    // --working-volume: "cylinder:R,H" | "box:X,Y,Z" ("": the rig file's)
  double driver_timeout_s = 10;  // --driver-timeout: how long to wait for the rig's drivers
  bool dry_run = false;          // --dry-run: plan and check the first views, move nothing
  bool rig_host = false;         // --rig-host: the motion executor and the camera run on the rig's computer
  std::string out;               // empty: out/<object>-<date-time>-<last 4 digits of the scan id>
  bool overwrite = false;        // --overwrite: empty a non-empty --out first
  std::string resume;            // --resume DIR: continue the interrupted scan there
};

// The paper's three ablations and the map resolution: which parameter varies.
enum class AblatedParameter { kTMax, kBeta, kInitialView, kResolution };

// What `pbnbv ablate` was asked for: one benchmark per value (the value as given, its spec).
struct AblateOptions {
  AblatedParameter parameter = AblatedParameter::kTMax;
  std::vector<std::pair<std::string, eval::BenchSpec>> runs;
  std::filesystem::path out;
};

// The values the paper's ablations try (text as on the command line: --values).
std::vector<std::string> default_ablation_values(AblatedParameter p);

class CommandLine {
 public:
  // Declares every command and its options.
  CommandLine();
  CommandLine(const CommandLine&) = delete;
  CommandLine& operator=(const CommandLine&) = delete;

  // Parses argv (argv[0] is the program). std::nullopt: run command(); else the exit code, the
  // help / version printed to `out` (0) or what is wrong printed to `err` naming the option (2).
  // Every default that depends on other options is resolved here (the ring elevation and the
  // registration by rig, the principal point by image size) and the settings are validated, so
  // a bad command line never starts a process.
  std::optional<int> parse(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

  Command command() const { return command_; }
  const StopOptions& stop() const { return stop_; }
  const RigHostOptions& rig_host() const { return rig_host_; }
  const ImportUrdfOptions& import_urdf() const { return import_urdf_; }
  const RigCheckOptions& rig_check() const { return rig_check_; }
  const CalibrateOptions& calibrate() const { return calibrate_; }
  const ReplayOptions& replay() const { return replay_; }
  const EvaluateOptions& evaluate() const { return evaluate_; }
  const MeshOptions& mesh() const { return mesh_; }
  const ScanOptions& scan() const { return scan_; }
  // `pbnbv bench`: the spec (with several values of a swept setting, its first combination's), and
  // the sweep (one bench when no setting lists more than one value).
  const eval::BenchSpec& bench() const { return bench_; }
  const eval::Sweep& sweep() const { return sweep_; }
  const AblateOptions& ablate() const { return ablate_; }

  // The whole usage: every command with its options.
  std::string usage() const;

 private:
  // The raw values of the options whose defaults depend on others, or that need a file system
  // look-up, before parse() resolves them.
  struct ScanPending {
    std::optional<double> ring_elevation_deg, cx, cy;
    std::optional<OnOff> registration, depth_filter;
    std::optional<double> pose_sigma_mm, pose_sigma_deg;
    std::optional<Eigen::Vector3d> initial_view;
    std::string rig_model;  // --rig-model FILE
    bool no_log = false;
    bool no_surface_metrics = false;
  };
  struct BenchPending {
    std::string object_dir;
    std::string out;
    bool no_netns = false;
    bool slurm = false;
    eval::SlurmSpec slurm_spec;
    eval::SweepValues sweep;  // the settings a bench may sweep: each combination one benchmark
  };

  // The options of `scan`, bound to scan_ and scan_pending_.
  void declare_scan();
  // The options `bench` and `ablate` share, bound to *spec and *pending.
  void declare_bench_options(CLI::App* command, eval::BenchSpec* spec, BenchPending* pending);
  // The defaults that depend on other options (ring elevation and registration by rig, the
  // principal point by image size), then ScanSettings::validate. Throws std::invalid_argument.
  void resolve_scan();
  // The object list (--objects, --object-dir or the default set), the output folder, then
  // BenchSpec::validate; *spec takes the first value of each swept setting, *sweep one bench per
  // combination of their values. Throws std::invalid_argument.
  void resolve_bench(const CLI::App* command, eval::BenchSpec* spec, const BenchPending& pending, eval::Sweep* sweep);
  // The ablated parameter and one benchmark per value of --values. Throws std::invalid_argument.
  void resolve_ablate();

  CLI::App app_;
  CLI::App* scan_cmd_ = nullptr;
  CLI::App* bench_cmd_ = nullptr;
  CLI::App* ablate_cmd_ = nullptr;
  CLI::App* spy_cmd_ = nullptr;
  CLI::App* view_cmd_ = nullptr;
  CLI::App* stop_cmd_ = nullptr;
  StopOptions stop_;
  CLI::App* rig_check_cmd_ = nullptr;
  RigCheckOptions rig_check_;
  CLI::App* calibrate_cmd_ = nullptr;
  CalibrateOptions calibrate_;
  CLI::App* replay_cmd_ = nullptr;
  ReplayOptions replay_;
  CLI::App* evaluate_cmd_ = nullptr;
  EvaluateOptions evaluate_;
  CLI::App* mesh_cmd_ = nullptr;
  MeshOptions mesh_;
  CLI::App* help_cmd_ = nullptr;
  Command command_ = Command::kHelp;
  ScanOptions scan_;
  ScanPending scan_pending_;
  eval::BenchSpec bench_;
  BenchPending bench_pending_;
  eval::Sweep sweep_;
  eval::BenchSpec ablate_base_;
  BenchPending ablate_pending_;
  std::string ablate_parameter_, ablate_values_;
  AblateOptions ablate_;
  std::string help_topic_;
  CLI::App* rig_host_cmd_ = nullptr;
  RigHostOptions rig_host_;
  CLI::App* import_urdf_cmd_ = nullptr;
  ImportUrdfOptions import_urdf_;
};

}  // namespace pbnbv::launcher

namespace pbnbv {
template <>
struct EnumNames<launcher::AblatedParameter> {
  static constexpr std::string_view what = "ablation parameter";
  static constexpr std::array<NamedValue<launcher::AblatedParameter>, 4> names{
      {{launcher::AblatedParameter::kTMax, "tmax"},
       {launcher::AblatedParameter::kBeta, "beta"},
       {launcher::AblatedParameter::kInitialView, "initial-view"},
       {launcher::AblatedParameter::kResolution, "resolution"}}};
};
}  // namespace pbnbv
