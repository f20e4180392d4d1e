#pragma once
// What `pbnbv scan` and `pbnbv replay` share: the scan's folder, its processes (the pipeline's
// services after the rig's driver, the coordinator last) and their supervision.
#include <filesystem>
#include <string>
#include <vector>

#include "core/io/mesh_file.hpp"
#include "bus/bus.hpp"
#include "core/scan/scan_settings.hpp"
#include "process/processes.hpp"

namespace pbnbv::launcher {

// A scan's folder: created if missing; one that holds anything is refused (a new scan would mix
// its files with the old run's) unless `overwrite`, which empties it first.
void prepare_out(const std::filesystem::path& out, bool overwrite);

// A process of the scan `s` (serving that scan only, --scan, but lcm-logger and the coordinator,
// which read it from elsewhere), its log in out/logs/<name>.log; `progress`: its stdout on the
// terminal.
process::Child scan_process(const std::string& name, std::vector<std::string> argv, const ScanSettings& s,
                            const std::filesystem::path& out, bool progress = false);

// The services after the rig's driver: motion, camera (unless `on_rig_host`: they run on the rig's
// computer, pbnbv rig-host), registration (off: `registration` false), mapping, the ellipsoid fitter
// and the view scorer as the planner needs, the coordinator last (its argv ending with
// `coordinator_extra`). Every service is given the scan's rig file (--model); the registration
// service writes mesh.obj in `mesh_units`.
void add_services(std::vector<process::Child>& children, const ScanSettings& s, const std::filesystem::path& out,
                  const std::filesystem::path& bin, bool registration,
                  const std::vector<std::string>& coordinator_extra = {}, bool on_rig_host = false,
                  LengthUnit mesh_units = LengthUnit::kMetre);

// Starts `children` (the coordinator last), keeps them running (restarts, hang detection) until
// the coordinator ends or the user stops the scan, stops them all, and reports: scan.json's final
// state, the log check and (`evaluate`: a twin scan) coverage against the true mesh, with the
// surface metrics unless `surface_metrics` is false. Returns the exit code.
int supervise(std::vector<process::Child>& children, const ScanSettings& s, const std::filesystem::path& out,
              bool record_log, bool evaluate = true, bool surface_metrics = true);

// STOP for `scan_id` ("" : every scan) with `reason`, sent three times 0.1 s apart (UDP may lose
// one): `pbnbv stop`, and the launcher when a scan ends failed or interrupted.
void send_stop(bus::Bus& bus, const std::string& scan_id, const std::string& reason);

// The local date and time as 20250131-142501 (folder names).
std::string timestamp();

}  // namespace pbnbv::launcher
