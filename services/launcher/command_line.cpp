#include "launcher/command_line.hpp"

#include <algorithm>
#include <cctype>
#include <stdexcept>
#include <string>
#include <tuple>

#include "core/geometry/camera_options.hpp"
#include "core/metrics/metrics_options.hpp"
#include "core/base/units.hpp"
#include "core/perception/perception_options.hpp"
#include "eval/objects.hpp"
#include "rigcheck/rigcheck_options.hpp"

namespace fs = std::filesystem;

namespace pbnbv::launcher {

namespace {

const char* const kObjectHelp =
    "mesh file (.obj .stl .off .ply) or a known object: any of the tuning set's 30 (bunny, teapot, armadillo, ...; "
    "docs/benchmark.md; fetched by ./scripts/setup), sphere, box";

// Option groups of `pbnbv scan --help`.
const char* const kGroupObject = "Object";
const char* const kGroupPlanning = "Planning";
const char* const kGroupRig = "Rig and twin";
const char* const kGroupCamera = "Depth camera";
const char* const kGroupOutput = "Output";

// A whole number from --values, in the setting's range; throws naming --values, the setting and
// its range.
int ablation_number(const Setting<int>& s, const std::string& text) {
  long long v = 0;
  if (!cli::detail::parse_number(text, &v)) throw std::invalid_argument("--values: '" + text + "' is not a whole number");
  if (v < s.min || v > s.max) {
    throw std::invalid_argument("--values: --" + std::string(s.name) + " " + text + " is outside its range " +
                                s.range_text());
  }
  return static_cast<int>(v);
}

// A number from --values, in the setting's range; throws as ablation_number.
double ablation_real(const Setting<double>& s, const std::string& text) {
  double v = 0;
  if (!cli::detail::parse_number(text, &v)) throw std::invalid_argument("--values: '" + text + "' is not a number");
  if (!(v >= s.min && v <= s.max)) {
    throw std::invalid_argument("--values: --" + std::string(s.name) + " " + text + " is outside its range " +
                                s.range_text());
  }
  return v;
}

}  // namespace

std::vector<std::string> default_ablation_values(AblatedParameter p) {
  switch (p) {
    case AblatedParameter::kTMax:
      return {"5", "10", "20", "40"};
    case AblatedParameter::kBeta:
      return {"1", "2", "4", "8"};
    case AblatedParameter::kInitialView:
      return {"0.9,0,0", "0,0.9,0", "0,0,0.9", "0,0.63,0.63"};
    case AblatedParameter::kResolution:
      return {"0.03", "0.02", "0.01", "0.005"};
  }
  return {};
}

CommandLine::CommandLine()
    : app_("pbnbv: scan unknown objects with a depth camera on an arm and a turntable, choosing each next view "
           "with PB-NBV",
           "pbnbv") {
  cli::init(app_);
  app_.require_subcommand(0, 1);  // one command: `pbnbv help scan` describes scan

  scan_cmd_ = cli::add_command(app_, "scan", "scan an object: the twin in the loop, or a rig whose drivers run outside (--external-rig)");
  declare_scan();

  bench_cmd_ = cli::add_command(app_, "bench",
                                "every planner on every object in the twin: coverage per view, planner time, "
                                "report.md, plots");
  declare_bench_options(bench_cmd_, &bench_, &bench_pending_);

  ablate_cmd_ = cli::add_command(app_, "ablate",
                                 "the paper's ablations: one benchmark per value of tmax, beta, initial-view or the map "
                                 "resolution, one plot");
  ablate_cmd_->add_option("parameter", ablate_parameter_, "the parameter to vary")
      ->type_name("tmax|beta|initial-view|resolution")
      ->check(CLI::Validator([](std::string& text) { return cli::detail::check_choice<AblatedParameter>(text); }, ""));
  cli::add_text(*ablate_cmd_, "values", &ablate_values_,
                "the values, comma-separated (initial views x,y,z separated by /) [tmax 5,10,20,40; beta 1,2,4,8; "
                "initial-view 0.9,0,0/0,0.9,0/0,0,0.9/0,0.63,0.63; resolution 0.03,0.02,0.01,0.005]",
                "V,V,...");
  ablate_base_.planners = {PlannerKind::kPbnbv};
  declare_bench_options(ablate_cmd_, &ablate_base_, &ablate_pending_);

  spy_cmd_ = cli::add_command(app_, "spy", "lcm-spy with every pbnbv channel decoded");
  // Run by pbnbv-view (pbnbv_main.cpp passes the arguments on): listed here for `pbnbv help`.
  view_cmd_ = cli::add_command(app_, "view",
                               "the scan in 3-D in a browser: pbnbv view [DIR] [--port 8765] [--scan ID] (pbnbv view "
                               "--help: every option)");

  stop_cmd_ = cli::add_command(app_, "stop", "halt the rig now and end the scan (STOP on the bus); what it has is kept");
  cli::add_text(*stop_cmd_, "scan", &stop_.scan_id, "the scan to stop (its id, in scan.json) [every scan on the bus]", "ID");
  cli::add_text(*stop_cmd_, "reason", &stop_.reason, "why, for the record [stopped by the user]", "TEXT");

  rig_host_cmd_ = cli::add_command(app_, "rig-host",
                                   "on the rig's computer: run the motion executor and the camera service beside the "
                                   "drivers, for scans started on another host (pbnbv scan --external-rig --rig-host)");
  cli::add_text(*rig_host_cmd_, "rig-model", &rig_host_.rig_model, "the rig's MJCF file [models/rig_arm.xml]", "FILE");
  cli::add_text(*rig_host_cmd_, "logs", &rig_host_.logs, "folder for their logs [rig-host-logs]", "DIR");

  import_urdf_cmd_ = cli::add_command(app_, "import-urdf",
                                      "an arm's URDF as MJCF (MuJoCo's URDF compiler), the first step of a rig file "
                                      "(docs/real-rig.md, 'Bring your own rig')");
  import_urdf_cmd_->add_option("urdf", import_urdf_.urdf, "the arm's URDF file")->required()->type_name("FILE");
  cli::add_text(*import_urdf_cmd_, "out", &import_urdf_.out, "the MJCF to write [the URDF's name with .xml]", "FILE");
  rig_check_cmd_ = cli::add_command(app_, "rig-check",
                                    "exercise the rig's drivers on the bus (twin or real) and print a pass/fail table "
                                    "against the contract and the rig file; moves a wrist joint 3 deg and the "
                                    "turntable 5 deg, and back");
  rig_check_.rig_model = default_rig_path(RigKind::kArm);
  cli::add_text(*rig_check_cmd_, "rig-model", &rig_check_.rig_model,
                "the rig file (MJCF) the drivers are held to", "FILE");
  cli::add(*rig_check_cmd_, rigcheck::kDriverDeadline, &rig_check_.deadline_s);
  cli::add_flag(*rig_check_cmd_, "passive", &rig_check_.passive,
                "only the checks that move nothing (statuses, one triggered frame)");
  calibrate_cmd_ = cli::add_command(app_, "calibrate",
                                    "hand-eye and turntable calibration from depth: the rig's drivers (or the twin) on "
                                    "the bus, a sphere of known radius on the platter mark");
  {
    CLI::App& c = *calibrate_cmd_;
    cli::add_text(c, "rig-model", &calibrate_.rig_model, "the rig file (MJCF) to calibrate", "FILE")->required();
    cli::add(c, kSphereRadius, &calibrate_.sphere.radius_m)->required();
    cli::add(c, kSphereOffset, &calibrate_.sphere.offset_m);
    cli::add(c, Setting<int>{"views", 24, 6, 200, "", "arm poses looking at the sphere, each at its own turntable angle"},
             &calibrate_.views);
    cli::add(c, Setting<double>{"speed-scale", 0.5, 0.05, 1.0, "", "fraction of the joint speed limits"},
             &calibrate_.speed_scale);
    cli::add(c, Setting<double>{"status-wait", 5.0, 0.5, 120.0, "s", "the drivers' statuses must come within this"},
             &calibrate_.status_wait_s);
    cli::add_flag(c, "fixed-axis", &calibrate_.fixed_axis, "do not estimate the turntable axis (keep the model's)");
    cli::add_text(c, "out", &calibrate_.out,
                  "folder for rig_calibrated.xml, calibration.json and report.md [out/calibration-<date-time>]", "DIR");
  }
  replay_cmd_ = cli::add_command(app_, "replay",
                                 "run a recorded scan's frames and poses through the pipeline again (no twin, no rig) "
                                 "and compare its decisions with the recording's");
  replay_cmd_->add_option("dir", replay_.dir, "the recorded scan's folder (scan.json, settings.json, scan.lcmlog)")
      ->type_name("DIR");
  cli::add_text(*replay_cmd_, "out", &replay_.out, "the replay's folder [DIR-replay-<date-time>]", "DIR");
  cli::add(*replay_cmd_, kPlanner, &replay_.planner);
  cli::add_flag(*replay_cmd_, "overwrite", &replay_.overwrite, "delete what --out holds first");

  evaluate_cmd_ = cli::add_command(app_, "evaluate",
                                   "accuracy, completeness and precision / recall / F-score of a scan folder, a cloud or "
                                   "a mesh against a reference mesh (the scan's true mesh, or a CAD model)");
  evaluate_cmd_->add_option("model", evaluate_.target,
                            "a scan folder (its cloud.ply and mesh.ply), a cloud (.ply .pcd) or a mesh (.ply .obj .stl .off)")
      ->type_name("DIR|FILE");
  cli::add_text(*evaluate_cmd_, "reference", &evaluate_.reference,
                "the reference mesh (.obj .stl .off .ply), in the model's frame [a twin scan folder's object.stl]", "FILE");
  cli::add(*evaluate_cmd_,
           Setting<double>{"reference-scale", 1.0, 1e-6, 1e6, "", "multiply the reference's coordinates by this (0.001: a file in mm)"},
           &evaluate_.reference_scale);
  cli::add(*evaluate_cmd_, kMetricThreshold, &evaluate_.metrics.threshold_m);
  cli::add(*evaluate_cmd_, kMetricSampleDensity, &evaluate_.metrics.samples_per_cm2);
  cli::add_text(*evaluate_cmd_, "json", &evaluate_.json, "also write the figures to FILE (JSON)", "FILE");
  mesh_cmd_ = cli::add_command(app_, "mesh", "(re)build a finished scan folder's surface mesh (mesh.ply, mesh.obj)");
  mesh_cmd_->add_option("dir", mesh_.dir, "the scan's folder (scan.json, frames/)")->type_name("DIR");
  cli::add(*mesh_cmd_, kMeshMethod, &mesh_.surface.method);
  cli::add(*mesh_cmd_, kMeshVoxel, &mesh_.surface.voxel_m);
  cli::add(*mesh_cmd_, kMeshTruncation, &mesh_.surface.truncation_voxels);
  cli::add(*mesh_cmd_, kPoissonDepth, &mesh_.surface.poisson_depth);
  cli::add(*mesh_cmd_, kMeshFillHoles, &mesh_.surface.fill_holes_m);
  cli::add_flag(*mesh_cmd_, "stl", &mesh_.stl, "also write mesh.stl (binary)");
  cli::add(*mesh_cmd_, kMeshUnits, &mesh_.units);

  help_cmd_ = cli::add_command(app_, "help", "this usage (pbnbv help COMMAND: that command's options)");
  help_cmd_->add_option("command", help_topic_, "the command to describe");
}

void CommandLine::declare_scan() {
  CLI::App& c = *scan_cmd_;
  ScanSettings& s = scan_.settings;
  ScanPending& p = scan_pending_;
  cli::add_text(c, "object", &scan_.object, kObjectHelp, "PATH|NAME")->group(kGroupObject);
  cli::add(c, kObjectSize, &scan_.size_m)->group(kGroupObject);
  cli::add(c, kUp, &scan_.up)->group(kGroupObject);

  cli::add(c, kPlanner, &s.planner)->group(kGroupPlanning);
  cli::add(c, kPlannerSeed, &s.seed)->group(kGroupPlanning);
  cli::add(c, kViews, &s.views)->group(kGroupPlanning);
  cli::add(c, kArea, &s.area)->group(kGroupPlanning);
  cli::add(c, kCandidates, &s.candidates)->group(kGroupPlanning);
  cli::add(c, kParallels, &s.parallels)->group(kGroupPlanning);
  cli::add(c, kSectors, &s.sectors)->group(kGroupPlanning);
  cli::add(c, kTMax, &s.t_max)->group(kGroupPlanning);
  cli::add(c, kStopFraction, &s.stop_fraction)->group(kGroupPlanning);
  cli::add(c, kStopRule, &s.stop_rule)->group(kGroupPlanning);
  cli::add(c, kStopWindow, &s.surface_rule.window)->group(kGroupPlanning);
  cli::add(c, kStopNewSurface, &s.surface_rule.max_new_percent)->group(kGroupPlanning);
  cli::add(c, kStopMinViews, &s.surface_rule.min_views)->group(kGroupPlanning);
  cli::add(c, kStopRateViews, &s.seconds_rule.window)->group(kGroupPlanning);
  cli::add(c, kStopGainPerSecond, &s.seconds_rule.min_percent_per_s)->group(kGroupPlanning);
  cli::add(c, kStopRadius, &s.stop_radius_m)->group(kGroupPlanning);
  cli::add(c, kWhenDone, &s.when_done)->group(kGroupPlanning);
  cli::add(c, kMotion, &s.motion)->group(kGroupPlanning);
  cli::add(c, kMapPose, &s.map_pose)->group(kGroupPlanning);
  cli::add(c, kSecondsPerPoint, &s.seconds_per_point)->group(kGroupPlanning);
  cli::add_point(c, "initial-view", &p.initial_view,
                 "first camera position, object frame, m; looks at the origin [the ring's view at --ring-elevation, "
                 "azimuth 0]")
      ->group(kGroupPlanning);
  cli::add(c, kWorkingDistance, &s.working_distance_m)->group(kGroupPlanning);
  cli::add(c, kRingElevation, &p.ring_elevation_deg, "30 arm, 0 free")->group(kGroupPlanning);
  cli::add(c, kCloudVoxel, &s.voxel_m)->group(kGroupPlanning);
  cli::add(c, kMapResolution, &s.map_resolution_m)->group(kGroupPlanning);
  cli::add(c, kRegistration, &p.registration)->group(kGroupPlanning);
  cli::add(c, kMeshUnits, &scan_.mesh_units)->group(kGroupPlanning);
  cli::add(c, kDepthFilter, &p.depth_filter)->group(kGroupCamera);
  cli::add(c, kPoseSigmaMm, &p.pose_sigma_mm, "twin: from its errors; a real rig: 0.5")->group(kGroupRig);
  cli::add(c, kPoseSigmaDeg, &p.pose_sigma_deg, "twin: from its errors; a real rig: 0.1")->group(kGroupRig);
  cli::add(c, kIcpVoxel, &s.icp_voxel_m)->group(kGroupPlanning);

  cli::add(c, kRig, &s.rig)->group(kGroupRig);
  cli::add_text(c, "rig-model", &p.rig_model,
                "the rig's MJCF file (docs/real-rig.md, 'Bring your own rig'); its kind decides --rig [models/rig_<rig>.xml]", "FILE")
      ->group(kGroupRig);
  cli::add_flag(c, "external-rig", &scan_.external_rig,
                "the rig's drivers run outside (a physical rig, or a twin started on its own): start no twin; the object "
                "is unknown (no --object), only its working volume")
      ->group(kGroupRig);
  cli::add_text(c, "working-volume", &scan_.working_volume,
                "where the unknown object stands, on the turntable: cylinder:RADIUS,HEIGHT or box:X,Y,Z, m [the rig "
                "file's pbnbv_working_volume, else derived from the turntable]",
                "SHAPE")
      ->group(kGroupRig);
  cli::add(c, Setting<double>{"driver-timeout", 10.0, 0.5, 600.0, "s", "external rig: how long to wait for each driver"},
           &scan_.driver_timeout_s)
      ->group(kGroupRig);
  cli::add_flag(c, "rig-host", &scan_.rig_host,
                "external rig: the motion executor and the camera service run on the rig's computer (pbnbv rig-host "
                "there); this host starts the rest")
      ->group(kGroupRig);
  cli::add_flag(c, "dry-run", &scan_.dry_run,
                "external rig: check the drivers, plan the first view and check the reachability of the candidates, "
                "print what would be commanded, and move nothing")
      ->group(kGroupRig);
  cli::add(c, kSpeedScale, &s.speed_scale)->group(kGroupRig);
  cli::add(c, kSimSpeed, &s.sim_speed)->group(kGroupRig);
  cli::add(c, kDepthNoise, &scan_.noise_sigma)->group(kGroupRig);
  cli::add(c, kDropout, &scan_.dropout)->group(kGroupRig);
  cli::add(c, kHandEyeErrorMm, &scan_.hand_eye_error_mm)->group(kGroupRig);
  cli::add(c, kHandEyeErrorDeg, &scan_.hand_eye_error_deg)->group(kGroupRig);
  cli::add(c, kTurntableErrorDeg, &scan_.turntable_error_deg)->group(kGroupRig);
  cli::add(c, kJointErrorDeg, &scan_.joint_error_deg)->group(kGroupRig);
  cli::add(c, kTurntableBacklashDeg, &scan_.turntable_backlash_deg)->group(kGroupRig);
  cli::add(c, kRigErrors, &scan_.rig_errors)->group(kGroupRig);
  cli::add(c, kErrorSeed, &scan_.error_seed)->group(kGroupRig);

  cli::add(c, kCamera, &s.camera_model)->group(kGroupCamera);
  cli::add(c, kImageWidth, &s.camera.width)->group(kGroupCamera);
  cli::add(c, kImageHeight, &s.camera.height)->group(kGroupCamera);
  cli::add(c, kFocalX, &s.camera.fx)->group(kGroupCamera);
  cli::add(c, kFocalY, &s.camera.fy)->group(kGroupCamera);
  cli::add(c, kPrincipalX, &p.cx, "width / 2")->group(kGroupCamera);
  cli::add(c, kPrincipalY, &p.cy, "height / 2")->group(kGroupCamera);
  cli::add(c, kDepthMin, &s.depth_range.min_m)->group(kGroupCamera);
  cli::add(c, kDepthMax, &s.depth_range.max_m)->group(kGroupCamera);

  cli::add_text(c, "out", &scan_.out, "output folder [out/<object>-<date-time>-<4 digits of the scan id>]", "DIR")->group(kGroupOutput);
  cli::add_flag(c, "no-log", &scan_pending_.no_log, "do not record scan.lcmlog")->group(kGroupOutput);
  cli::add_flag(c, "no-surface-metrics", &scan_pending_.no_surface_metrics,
                "coverage.json without the surface metrics against the true mesh (accuracy, completeness, F-score; "
                "`pbnbv bench` computes them in its own evaluation)")
      ->group(kGroupOutput);
  cli::add_flag(c, "overwrite", &scan_.overwrite,
                "delete what --out holds before scanning (a folder that is not empty is refused otherwise)")
      ->group(kGroupOutput);
  cli::add_text(c, "resume", &scan_.resume,
                "continue the interrupted scan in DIR with its own settings and processes (other options are not used)",
                "DIR")
      ->group(kGroupOutput);
  cli::add_settings_file(c)->group(kGroupOutput);
}

void CommandLine::declare_bench_options(CLI::App* command, eval::BenchSpec* spec, BenchPending* pending) {
  CLI::App& c = *command;
  cli::add_words(c, "objects", &spec->objects,
                 "object sets (default, tuning, tune, confirm), object names or mesh paths, mixed [default]");
  cli::add_text(c, "object-dir", &pending->object_dir, "every .obj/.stl/.off/.ply in DIR instead", "DIR");
  cli::add_list(c, "planners", &spec->planners, "planners to compare");
  // A list of values for these sweeps: one benchmark per combination (README, "Sweeps").
  cli::add_list(c, eval::kBenchRig, &pending->sweep.rigs, "a list sweeps");
  cli::add_words(c, "rig-model", &pending->sweep.rig_models,
                 "the rig's MJCF file, e.g. models/rig_ur5e.xml [models/rig_<rig>.xml]; a list sweeps", "FILE[,...]");
  cli::add(c, eval::kBenchArea, &spec->area);
  cli::add(c, kViews, &spec->views);
  cli::add_values(c, kMapResolution, &pending->sweep.resolutions, "a list sweeps");
  cli::add(c, kCandidates, &spec->candidates);
  cli::add(c, kTMax, &spec->tmax);
  cli::add(c, kSectors, &spec->beta);
  cli::add(c, kObjectSize, &spec->size_m);
  cli::add(c, kWorkingDistance, &spec->working_distance_m);
  cli::add(c, kUp, &spec->up);
  cli::add_point(c, "initial-view", &spec->initial_view,
                 "first camera position, object frame, m [the scan's default first view]");
  cli::add_values(c, eval::kFirstViews, &pending->sweep.first_views, "a list sweeps");
  cli::add(c, kPlannerSeed, &spec->seed);
  cli::add(c, kWhenDone, &spec->when_done);
  cli::add(c, kMotion, &spec->motion);
  cli::add(c, kMapPose, &spec->map_pose);
  cli::add(c, kSimSpeed, &spec->sim_speed);
  cli::add(c, kSecondsPerPoint, &spec->seconds_per_point);
  cli::add_list(c, kCamera, &pending->sweep.cameras, "a list sweeps");
  cli::add_list(c, kRigErrors, &pending->sweep.rig_errors, "a list sweeps");
  // The scans run without a stop rule; the report says where the surface rule would have stopped each.
  cli::add(c, kStopWindow, &spec->stop_rule.window);
  cli::add(c, kStopNewSurface, &spec->stop_rule.max_new_percent);
  cli::add(c, kStopMinViews, &spec->stop_rule.min_views);
  cli::add(c, kStopRateViews, &spec->seconds_rule.window);  // and where the rule in seconds would have
  cli::add(c, kStopGainPerSecond, &spec->seconds_rule.min_percent_per_s);
  cli::add(c, kMetricThreshold, &spec->metrics.threshold_m);  // the surface metrics' precision / recall
  cli::add(c, eval::kJobs, &spec->jobs);
  cli::add_flag(c, "no-netns", &pending->no_netns,
                "run the scans on the current LCM bus (one at a time; with --slurm one per node)");
  cli::add_flag(c, "slurm", &pending->slurm,
                "run each scan as a task of a Slurm job array (sbatch; SLURM_CONF from the environment): the bench "
                "folder and pbnbv must be on a file system every node shares (README, 'On a Slurm cluster')");
  cli::add_text(c, "partition", &pending->slurm_spec.partition, "--slurm: the partition [Slurm's default]", "P");
  cli::add_text(c, "account", &pending->slurm_spec.account, "--slurm: the account [Slurm's default]", "A");
  cli::add_text(c, "time-limit", &pending->slurm_spec.time_limit,
                "--slurm: each scan's time limit, as sbatch --time takes it (30, 1:00:00) [the partition's]", "T");
  cli::add_text(c, "out", &pending->out, "results (required); a rerun skips the scans already complete there and resumes interrupted ones", "DIR");
  cli::add_settings_file(c);
}

std::optional<int> CommandLine::parse(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  if (const std::optional<int> code = cli::parse(app_, argc, argv, out, err)) return code;
  const CLI::App* given = app_.get_subcommands().empty() ? nullptr : app_.get_subcommands().front();
  try {
    if (given == nullptr || given == help_cmd_) {
      command_ = Command::kHelp;
      if (help_topic_.empty()) {
        out << usage();
        return 0;
      }
      for (const CLI::App* c : {scan_cmd_, bench_cmd_, ablate_cmd_, spy_cmd_, view_cmd_, stop_cmd_, rig_check_cmd_, rig_host_cmd_,
                                import_urdf_cmd_, calibrate_cmd_, replay_cmd_, evaluate_cmd_, mesh_cmd_, help_cmd_}) {
        if (c->get_name() == help_topic_) {
          out << c->help("pbnbv");
          return 0;
        }
      }
      throw std::invalid_argument("unknown command '" + help_topic_ +
                                  "' (expected scan, bench, ablate, spy, view, stop, rig-check, rig-host, import-urdf, calibrate, "
                                  "replay, evaluate, mesh or help)");
    }
    if (given == scan_cmd_) {
      command_ = Command::kScan;
      resolve_scan();
    } else if (given == bench_cmd_) {
      command_ = Command::kBench;
      resolve_bench(bench_cmd_, &bench_, bench_pending_, &sweep_);
    } else if (given == ablate_cmd_) {
      command_ = Command::kAblate;
      resolve_ablate();
    } else if (given == stop_cmd_) {
      command_ = Command::kStop;
    } else if (given == import_urdf_cmd_) {
      command_ = Command::kImportUrdf;
      if (import_urdf_.out.empty()) import_urdf_.out = fs::path(import_urdf_.urdf).replace_extension(".xml").string();
      if (fs::absolute(import_urdf_.out) == fs::absolute(import_urdf_.urdf)) {
        throw std::invalid_argument("--out " + import_urdf_.out + " would overwrite the URDF");
      }
    } else if (given == rig_host_cmd_) {
      command_ = Command::kRigHost;
      if (rig_host_.rig_model.empty()) rig_host_.rig_model = default_rig_path(RigKind::kArm);
      try {
        rig_host_.rig_model = load_rig(fs::absolute(rig_host_.rig_model).string()).model_path;
      } catch (const std::runtime_error& e) {
        throw std::invalid_argument(std::string("--rig-model: ") + e.what());
      }
    } else if (given == rig_check_cmd_) {
      command_ = Command::kRigCheck;
    } else if (given == calibrate_cmd_) {
      command_ = Command::kCalibrate;
      if (calibrate_.sphere.radius_m + calibrate_.sphere.offset_m > 0.2 + 1e-9) {
        throw std::invalid_argument("--sphere-radius " + std::to_string(calibrate_.sphere.radius_m) + " m at --sphere-offset " +
                                    std::to_string(calibrate_.sphere.offset_m) + " m reaches beyond the platter's 0.2 m radius");
      }
    } else if (given == replay_cmd_) {
      command_ = Command::kReplay;
      if (replay_.dir.empty()) throw std::invalid_argument("name the recorded scan's folder: pbnbv replay DIR");
    } else if (given == evaluate_cmd_) {
      command_ = Command::kEvaluate;
      if (evaluate_.target.empty()) {
        throw std::invalid_argument("name what to evaluate: pbnbv evaluate DIR|FILE [--reference MESH]");
      }
    } else if (given == mesh_cmd_) {
      command_ = Command::kMesh;
      if (mesh_.dir.empty()) throw std::invalid_argument("name the scan's folder: pbnbv mesh DIR");
    } else {
      command_ = Command::kSpy;
    }
  } catch (const std::invalid_argument& e) {
    err << "pbnbv " << given->get_name() << ": " << e.what() << "\n(pbnbv " << given->get_name()
        << " --help lists the options)" << std::endl;
    return 2;
  }
  return std::nullopt;
}

std::string CommandLine::usage() const {
  // The formatter directly: App::help() would describe the command given (help) instead.
  return app_.get_formatter()->make_help(&app_, "pbnbv", CLI::AppFormatMode::All);
}

void CommandLine::resolve_scan() {
  ScanSettings& s = scan_.settings;
  const ScanPending& p = scan_pending_;
  std::optional<RigModel> rig;  // read once, when something needs it
  if (!p.rig_model.empty()) {
    // The file decides the kind of rig: --rig may only agree with it.
    try {
      rig = load_rig(fs::absolute(p.rig_model).string());
    } catch (const std::runtime_error& e) {
      throw std::invalid_argument(std::string("--rig-model: ") + e.what());
    }
    if (scan_cmd_->get_option("--rig")->count() > 0 && s.rig != rig->kind) {
      throw std::invalid_argument("--rig " + to_string(s.rig) + " disagrees with --rig-model " + rig->model_path +
                                  ", which describes a rig of kind " + to_string(rig->kind));
    }
    s.rig = rig->kind;
    s.rig_model_path = rig->model_path;
  } else {
    s.rig_model_path = default_rig_path(s.rig);
  }
  s.seconds_rule.min_views = s.surface_rule.min_views;  // --stop-min-views: either rule
  s.ring_elevation_deg = p.ring_elevation_deg.value_or(s.rig == RigKind::kArm ? kRingElevation.value
                                                                                : kRingElevationFreeDeg);
  if (p.initial_view) s.initial_view_m = *p.initial_view;
  const auto given = [this](std::string_view name) { return scan_cmd_->get_option("--" + std::string(name))->count() > 0; };
  // The twin plays the camera the rig file names (pbnbv_camera_model) unless --camera says another.
  if (!scan_.external_rig && !given(kCamera.name) && rig && rig->camera && rig->camera->model) {
    s.camera_model = *rig->camera->model;
  }
  take_model_defaults(depth_sensor_model(s.camera_model), given, s.camera, s.depth_range);
  // The ideal camera makes no flying pixel or speckle: nothing for the filter to take there.
  s.depth_filter = p.depth_filter.value_or(depth_sensor_model(s.camera_model).exact() && !scan_.external_rig
                                               ? OnOff::kOff
                                               : OnOff::kOn) == OnOff::kOn;
  // --rig-errors: its figures for the error options not given one by one.
  const RigErrorFigures rig_errors = rig_error_figures(scan_.rig_errors);
  for (const auto& [setting, value, target] :
       {std::tuple{kHandEyeErrorMm, rig_errors.hand_eye_mm, &scan_.hand_eye_error_mm},
        std::tuple{kHandEyeErrorDeg, rig_errors.hand_eye_deg, &scan_.hand_eye_error_deg},
        std::tuple{kTurntableErrorDeg, rig_errors.turntable_deg, &scan_.turntable_error_deg},
        std::tuple{kJointErrorDeg, rig_errors.joint_deg, &scan_.joint_error_deg},
        std::tuple{kTurntableBacklashDeg, rig_errors.backlash_deg, &scan_.turntable_backlash_deg}}) {
    if (!given(setting.name)) *target = value;
  }
  s.camera.cx = p.cx.value_or(s.camera.width / 2.0);
  s.camera.cy = p.cy.value_or(s.camera.height / 2.0);
  // The free rig is the paper's idealised comparison setup (a camera placed exactly, as in the
  // paper's simulation): its kinematic poses are exact, so registration is off by default there.
  scan_.registration = p.registration.value_or(s.rig == RigKind::kArm ? OnOff::kOn : OnOff::kOff) == OnOff::kOn;
  scan_.record_log = !p.no_log;
  scan_.surface_metrics = !p.no_surface_metrics;
  // Registration's prior: what the user says of the rig, else on the twin what its errors make
  // (each a random direction of its size: about size / sqrt(3) per axis; a joint's error turns
  // the camera and moves it through the arm's reach; the turntable's turns the object under it).
  if (scan_.external_rig) {
    s.pose_sigma_m = p.pose_sigma_mm.value_or(kPoseSigmaMm.value) * 1e-3;
    s.pose_sigma_deg = p.pose_sigma_deg.value_or(kPoseSigmaDeg.value);
  } else {
    constexpr double kLeverM = 0.5;  // the arm's reach and the camera's distance to the object, about
    const double he_m = scan_.hand_eye_error_mm * 1e-3 / std::sqrt(3.0);
    const double he_rad = deg_to_rad(scan_.hand_eye_error_deg) / std::sqrt(3.0);
    const double joint_rad = deg_to_rad(scan_.joint_error_deg) * std::sqrt(2.0);  // six joints on three axes
    const double table_rad = std::hypot(deg_to_rad(scan_.turntable_error_deg) / std::sqrt(3.0),
                                        deg_to_rad(scan_.turntable_backlash_deg) / 2);
    const double rot_rad = std::sqrt(he_rad * he_rad + joint_rad * joint_rad + table_rad * table_rad);
    const double pos_m = std::sqrt(he_m * he_m + std::pow((joint_rad + table_rad) * kLeverM, 2));
    s.pose_sigma_m = p.pose_sigma_mm.value_or(std::max(pos_m * 1e3, 0.01)) * 1e-3;  // an exact twin: 10 um,
    s.pose_sigma_deg = p.pose_sigma_deg.value_or(std::max(rad_to_deg(rot_rad), 0.002));  // 0.002 deg
  }
  if (scan_.external_rig) {
    // The object is unknown: nothing of the twin's object or of its simulation applies.
    for (const char* twin_only : {"--object", "--size", "--up", "--sim-speed", "--noise-sigma", "--dropout",
                                  "--hand-eye-error-mm", "--hand-eye-error-deg", "--turntable-error-deg",
                                  "--joint-error-deg", "--turntable-backlash-deg", "--rig-errors", "--camera",
                                  "--error-seed", "--width", "--height", "--fx", "--fy", "--cx",
                                  "--cy", "--depth-min", "--depth-max"}) {
      if (scan_cmd_->get_option(twin_only)->count() > 0) {
        throw std::invalid_argument(std::string(twin_only) +
                                    " does not apply to --external-rig: the object is unknown and the camera and its "
                                    "range are the driver's (checked against the rig file)");
      }
    }
    if (uses_truth(s.planner)) {
      throw std::invalid_argument("--planner oracle does not apply to --external-rig: the oracle chooses by the "
                                  "object's true mesh, which only a twin scan has (it is the benchmark's yardstick)");
    }
    s.external_rig = true;
    if (scan_.working_volume.empty() && !rig) rig = load_rig(s.rig_model_path);
    s.working_volume = scan_.working_volume.empty() ? working_volume_of(*rig)
                                                    : parse_working_volume(scan_.working_volume);
  } else {
    for (const char* external_only : {"--working-volume", "--driver-timeout", "--dry-run", "--rig-host"}) {
      if (scan_cmd_->get_option(external_only)->count() > 0) {
        throw std::invalid_argument(std::string(external_only) + " applies to --external-rig only");
      }
    }
  }
  s.validate();
}

void CommandLine::resolve_bench(const CLI::App* command, eval::BenchSpec* spec, const BenchPending& pending,
                                eval::Sweep* sweep) {
  const bool objects_given = command->get_option("--objects")->count() > 0;
  if (objects_given && !pending.object_dir.empty()) throw std::invalid_argument("give --objects or --object-dir, not both");
  if (!pending.object_dir.empty()) {
    const fs::path dir = pending.object_dir;
    if (!fs::is_directory(dir)) throw std::invalid_argument("--object-dir " + dir.string() + ": not a folder");
    for (const auto& e : fs::directory_iterator(dir)) {
      std::string ext = e.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
      if (ext == ".obj" || ext == ".stl" || ext == ".off" || ext == ".ply") spec->objects.push_back(e.path().string());
    }
    std::sort(spec->objects.begin(), spec->objects.end());
    if (spec->objects.empty()) throw std::invalid_argument("--object-dir " + dir.string() + ": no .obj, .stl, .off or .ply file");
  } else if (!objects_given) {
    spec->objects = eval::object_set(eval::ObjectSet::kDefault);
  } else {
    spec->objects = eval::expand_objects(spec->objects);
  }
  spec->netns = !pending.no_netns;
  if (pending.slurm) {
    spec->slurm = pending.slurm_spec;
    eval::validate(*spec->slurm);
  } else {
    for (const char* o : {"--partition", "--account", "--time-limit"}) {
      if (command->get_option(o)->count() > 0) throw std::invalid_argument(std::string(o) + " is for --slurm");
    }
  }
  spec->seconds_rule.min_views = spec->stop_rule.min_views;  // --stop-min-views: either rule
  if (pending.out.empty()) throw std::invalid_argument("--out DIR is required");
  spec->out = fs::absolute(pending.out);
  eval::SweepValues values = pending.sweep;
  for (std::string& m : values.rig_models) {
    if (!m.empty()) m = fs::absolute(m).string();  // the scans run elsewhere
  }
  *sweep = eval::expand_sweep(*spec, values);
  *spec = sweep->benches.front().second;
}

void CommandLine::resolve_ablate() {
  if (ablate_parameter_.empty()) {
    throw std::invalid_argument("name the parameter: tmax, beta, initial-view or resolution (pbnbv ablate tmax [options])");
  }
  const AblatedParameter param = parse_name<AblatedParameter>(ablate_parameter_);
  eval::Sweep sweep;
  resolve_bench(ablate_cmd_, &ablate_base_, ablate_pending_, &sweep);
  if (sweep.benches.size() > 1) {
    throw std::invalid_argument("--" + sweep.parameters.front() +
                                " lists several values: pbnbv ablate varies one parameter (--values); a sweep over "
                                "lists is pbnbv bench's");
  }
  ablate_.parameter = param;
  ablate_.out = ablate_base_.out;
  const std::vector<std::string> values =
      ablate_values_.empty() ? default_ablation_values(param)
                             : cli::detail::split_list(ablate_values_, param == AblatedParameter::kInitialView ? '/' : ',');
  if (values.empty()) throw std::invalid_argument("--values '" + ablate_values_ + "' lists no value");
  ablate_.runs.clear();
  for (const std::string& v : values) {
    eval::BenchSpec s = ablate_base_;
    if (param == AblatedParameter::kTMax) s.tmax = ablation_number(kTMax, v);
    if (param == AblatedParameter::kBeta) s.beta = ablation_number(kSectors, v);
    if (param == AblatedParameter::kResolution) s.resolution_m = ablation_real(kMapResolution, v);
    if (param == AblatedParameter::kInitialView) {
      s.initial_view = cli::detail::parse_point(v);
      if (!s.initial_view) throw std::invalid_argument("--values: initial view '" + v + "' is not x,y,z");
    }
    std::string folder = std::string(name_of(param)) + "=" + v;
    std::replace(folder.begin(), folder.end(), ',', '_');
    s.out = ablate_.out / folder;
    try {
      s.validate();
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("--values " + v + ": " + e.what());
    }
    ablate_.runs.emplace_back(v, s);
  }
}

}  // namespace pbnbv::launcher
