#pragma once
// A scan's processes, built from what its folder's settings.json says: the same code for a new
// scan and for `pbnbv scan --resume`. processes.json records what ran (PIDs, argv, how each
// ended) for people and for `pbnbv stop`; it is never read back as commands.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/io/mesh_file.hpp"
#include "core/scan/scan_options.hpp"
#include "core/scan/scan_settings.hpp"
#include "process/processes.hpp"

namespace pbnbv::launcher {

struct ScanOptions;

// What the launcher gives the processes beyond ScanSettings, kept in settings.json under "launch"
// so that a resume starts the same processes: the log, registration, where motion and camera run,
// and the twin's depth noise and pose-error model.
struct LaunchSettings {
  bool record_log = true;    // lcm-logger into scan.lcmlog (not --no-log)
  bool surface_metrics = true;  // coverage.json with the surface metrics (not --no-surface-metrics)
  bool registration = true;  // --registration on|off, resolved
  bool rig_host = false;     // external rig: motion and camera run on the rig's computer (pbnbv rig-host)
  double noise_sigma = kDepthNoise.value;
  double dropout = kDropout.value;
  double hand_eye_error_mm = kHandEyeErrorMm.value;
  double hand_eye_error_deg = kHandEyeErrorDeg.value;
  double turntable_error_deg = kTurntableErrorDeg.value;
  double joint_error_deg = kJointErrorDeg.value;
  double turntable_backlash_deg = kTurntableBacklashDeg.value;
  int64_t error_seed = kErrorSeed.value;
  LengthUnit mesh_units = LengthUnit::kMetre;  // mesh.obj's length unit (--units)
};

LaunchSettings launch_settings_of(const ScanOptions& o);
nlohmann::json to_json(const LaunchSettings& l);
// settings.json's "launch" object; `file` names it in errors. Throws std::invalid_argument naming
// the file, the field and what is wrong (missing, of the wrong type, outside its option's range).
LaunchSettings launch_settings_from_json(const nlohmann::json& launch, const std::string& file);

// settings.json: the scan's settings with the launcher's ("launch").
void write_scan_settings(const ScanSettings& s, const LaunchSettings& l, const std::filesystem::path& out);

// Every process of the scan `s` in the folder `out`, its argv built from the settings and the
// executables in `bin`: lcm-logger (l.record_log), the twin (unless s.external_rig; its mesh is
// out/object.stl), the services of add_services, the coordinator last. Every path a process
// writes to lies in `out`.
std::vector<process::Child> scan_processes(const ScanSettings& s, const LaunchSettings& l, const std::filesystem::path& out,
                                           const std::filesystem::path& bin);

// What a folder to resume holds, checked before anything starts.
struct Resumable {
  ScanSettings settings;
  LaunchSettings launch;
  std::string rerooted;  // for the user: which setting was re-rooted into `out` ("": none)
};

// Reads and checks out/settings.json for `pbnbv scan --resume out` (out absolute and normal):
// the settings valid, a scan id that is a plain word, the "launch" settings in range, scan.json
// (when there) a record of the same scan, a twin scan's object.stl there. A rig file inside
// another scan's folder (a copied folder's settings still naming the original's) is re-rooted to
// the same file in `out`; when `out` has no such file the folder is refused. Throws
// std::invalid_argument naming the folder, the file and what is wrong.
Resumable read_resumable(const std::filesystem::path& out);

}  // namespace pbnbv::launcher
