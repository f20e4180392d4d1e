// A scan's processes from its settings (scan_processes.hpp).
#include "launcher/scan_processes.hpp"

#include <algorithm>

#include "bus/bus.hpp"
#include "core/base/format.hpp"
#include "core/io/json.hpp"
#include "core/scan/scan_file.hpp"
#include "launcher/command_line.hpp"
#include "launcher/supervise.hpp"

namespace fs = std::filesystem;

namespace pbnbv::launcher {

namespace {

// launch[key] as T, `setting` its option (range and name); throws naming the file and the field.
template <class T>
T launch_value(const nlohmann::json& launch, const char* key, const Setting<T>& setting, const std::string& file) {
  if (!launch.contains(key)) throw std::invalid_argument(file + ": \"launch\" has no \"" + key + "\"");
  const nlohmann::json& v = launch.at(key);
  if (!v.is_number() || (std::is_integral_v<T> && !v.is_number_integer())) {
    throw std::invalid_argument(file + ": launch." + key + " is " + v.dump() + ", not " +
                                (std::is_integral_v<T> ? "an integer" : "a number"));
  }
  const T x = v.get<T>();
  if (!setting.allows(x)) {
    throw std::invalid_argument(file + ": launch." + key + " " + v.dump() + " is outside the range of --" +
                                std::string(setting.name) + " " + setting.range_text());
  }
  return x;
}

bool launch_flag(const nlohmann::json& launch, const char* key, const std::string& file) {
  if (!launch.contains(key)) throw std::invalid_argument(file + ": \"launch\" has no \"" + key + "\"");
  if (!launch.at(key).is_boolean()) {
    throw std::invalid_argument(file + ": launch." + key + " is " + launch.at(key).dump() + ", not true or false");
  }
  return launch.at(key).get<bool>();
}

// A scan id as new_scan_id makes it: letters, digits, '-', '_' and '.', not starting with '-'
// (it is a process argument, after --scan).
bool plain_scan_id(const std::string& id) {
  if (id.empty() || id.size() > 200 || id.front() == '-') return false;
  return std::all_of(id.begin(), id.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_' || c == '.';
  });
}

// The scan folder (a folder holding settings.json) that `path` lies in, nearest first; none: "".
fs::path enclosing_scan_folder(const fs::path& path) {
  for (fs::path p = path.parent_path(); !p.empty(); p = p.parent_path()) {
    std::error_code ec;
    if (fs::is_regular_file(p / "settings.json", ec)) return p;
    if (p == p.root_path()) break;
  }
  return {};
}

}  // namespace

LaunchSettings launch_settings_of(const ScanOptions& o) {
  LaunchSettings l;
  l.record_log = o.record_log;
  l.surface_metrics = o.surface_metrics;
  l.registration = o.registration;
  l.rig_host = o.rig_host;
  l.noise_sigma = o.noise_sigma;
  l.dropout = o.dropout;
  l.hand_eye_error_mm = o.hand_eye_error_mm;
  l.hand_eye_error_deg = o.hand_eye_error_deg;
  l.turntable_error_deg = o.turntable_error_deg;
  l.joint_error_deg = o.joint_error_deg;
  l.turntable_backlash_deg = o.turntable_backlash_deg;
  l.error_seed = o.error_seed;
  l.mesh_units = o.mesh_units;
  return l;
}

nlohmann::json to_json(const LaunchSettings& l) {
  return {{"record_log", l.record_log},
          {"surface_metrics", l.surface_metrics},
          {"registration", l.registration},
          {"rig_host", l.rig_host},
          {"noise_sigma", l.noise_sigma},
          {"dropout", l.dropout},
          {"hand_eye_error_mm", l.hand_eye_error_mm},
          {"hand_eye_error_deg", l.hand_eye_error_deg},
          {"turntable_error_deg", l.turntable_error_deg},
          {"joint_error_deg", l.joint_error_deg},
          {"turntable_backlash_deg", l.turntable_backlash_deg},
          {"error_seed", l.error_seed},
          {"mesh_units", unit_symbol(l.mesh_units)}};
}

LaunchSettings launch_settings_from_json(const nlohmann::json& launch, const std::string& file) {
  if (!launch.is_object()) throw std::invalid_argument(file + ": \"launch\" is " + launch.dump() + ", not an object");
  LaunchSettings l;
  l.record_log = launch_flag(launch, "record_log", file);
  if (launch.contains("surface_metrics")) l.surface_metrics = launch_flag(launch, "surface_metrics", file);  // since 0.13
  l.registration = launch_flag(launch, "registration", file);
  l.rig_host = launch_flag(launch, "rig_host", file);
  l.noise_sigma = launch_value(launch, "noise_sigma", kDepthNoise, file);
  l.dropout = launch_value(launch, "dropout", kDropout, file);
  l.hand_eye_error_mm = launch_value(launch, "hand_eye_error_mm", kHandEyeErrorMm, file);
  l.hand_eye_error_deg = launch_value(launch, "hand_eye_error_deg", kHandEyeErrorDeg, file);
  l.turntable_error_deg = launch_value(launch, "turntable_error_deg", kTurntableErrorDeg, file);
  l.joint_error_deg = launch_value(launch, "joint_error_deg", kJointErrorDeg, file);
  if (launch.contains("turntable_backlash_deg")) {  // since stop 37
    l.turntable_backlash_deg = launch_value(launch, "turntable_backlash_deg", kTurntableBacklashDeg, file);
  }
  l.error_seed = launch_value(launch, "error_seed", kErrorSeed, file);
  if (launch.contains("mesh_units")) {  // since 0.11
    const nlohmann::json& u = launch["mesh_units"];
    try {
      if (!u.is_string()) throw std::invalid_argument("not a string");
      l.mesh_units = parse_length_unit(u.get<std::string>());
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(file + ": launch.mesh_units = " + u.dump() + " is not \"m\" or \"mm\"");
    }
  }
  return l;
}

void write_scan_settings(const ScanSettings& s, const LaunchSettings& l, const fs::path& out) {
  nlohmann::json j = to_json(s);
  j["launch"] = to_json(l);
  write_json_atomic(j, (out / "settings.json").string());
}

std::vector<process::Child> scan_processes(const ScanSettings& s, const LaunchSettings& l, const fs::path& out,
                                           const fs::path& bin) {
  std::vector<process::Child> children;
  // The logger listens with the services' receive buffer (bus::lcm_url()).
  if (l.record_log) {
    children.push_back(scan_process(
        "lcm-logger", {"/usr/bin/lcm-logger", "-q", "--lcm-url=" + bus::lcm_url(), "-f", (out / "scan.lcmlog").string()}, s,
        out));
  }
  if (!s.external_rig) {
    children.push_back(scan_process(
        "twin",
        {(bin / "pbnbv-twin").string(), "--model", s.rig_model_path, "--mesh",
         (out / (fs::exists(out / "object.ply") ? "object.ply" : "object.stl")).string(),
         "--object-z", exact(s.object_z_m), "--model-out", (out / "twin_model.xml").string(),
         "--width", std::to_string(s.camera.width), "--height", std::to_string(s.camera.height),
         "--fx", exact(s.camera.fx), "--fy", exact(s.camera.fy), "--cx", exact(s.camera.cx), "--cy", exact(s.camera.cy),
         "--depth-min", exact(s.depth_range.min_m), "--depth-max", exact(s.depth_range.max_m),
         "--noise-sigma", exact(l.noise_sigma), "--dropout", exact(l.dropout), "--speed", exact(s.sim_speed),
         "--hand-eye-error-mm", exact(l.hand_eye_error_mm), "--hand-eye-error-deg", exact(l.hand_eye_error_deg),
         "--turntable-error-deg", exact(l.turntable_error_deg), "--joint-error-deg", exact(l.joint_error_deg),
         "--turntable-backlash-deg", exact(l.turntable_backlash_deg), "--camera", std::string(name_of(s.camera_model)),
         "--error-seed", std::to_string(l.error_seed), "--truth-out", (out / "twin_truth.jsonl").string(),
         "--truth-rig-out", (out / "twin_rig.json").string()},
        s, out));
  }
  add_services(children, s, out, bin, l.registration, {}, s.external_rig && l.rig_host, l.mesh_units);
  return children;
}

Resumable read_resumable(const fs::path& out) {
  const std::string where = "--resume " + out.string();
  if (!fs::is_directory(out)) throw std::invalid_argument(where + ": no such folder");
  const fs::path settings_file = out / "settings.json";
  if (!fs::is_regular_file(settings_file)) {
    throw std::invalid_argument(where + ": no scan to resume there (settings.json is missing)");
  }
  const nlohmann::json j = read_json(settings_file.string());
  Resumable r;
  try {
    r.settings = scan_settings_from_json(j);
  } catch (const std::exception& e) {
    throw std::invalid_argument(where + ": " + settings_file.string() + ": " + e.what());
  }
  ScanSettings& s = r.settings;
  if (!plain_scan_id(s.scan_id)) {
    throw std::invalid_argument(where + ": " + settings_file.string() + ": scan_id " + nlohmann::json(s.scan_id).dump() +
                                " is not a scan id (letters, digits, '-', '_' and '.', not starting with '-')");
  }
  if (!j.contains("launch")) {
    throw std::invalid_argument(where + ": " + settings_file.string() +
                                " has no \"launch\" settings: the folder was not made by `pbnbv scan` of this version (a "
                                "replay's folder, or an older scan), so its processes cannot be rebuilt; start the scan again");
  }
  r.launch = launch_settings_from_json(j.at("launch"), settings_file.string());
  const fs::path scan_json = out / "scan.json";
  if (fs::exists(scan_json)) {
    const std::string recorded = recorded_scan_id(scan_json);
    if (recorded != s.scan_id) {
      throw std::invalid_argument(where + ": " + scan_json.string() + " is a record of scan \"" + recorded + "\", " +
                                  settings_file.string() + " of scan \"" + s.scan_id + "\": the folder mixes two scans");
    }
  }
  if (!s.external_rig && !fs::is_regular_file(out / "object.stl")) {
    throw std::invalid_argument(where + ": " + (out / "object.stl").string() + " is missing (the twin's object)");
  }
  // The rig file: a copied folder's settings may still name a file in the original's folder.
  const fs::path rig = fs::absolute(s.rig_model_path).lexically_normal();
  const fs::path owner = enclosing_scan_folder(rig);
  if (!owner.empty() && owner != out) {
    const fs::path inside = out / rig.lexically_relative(owner);
    if (!fs::is_regular_file(inside)) {
      throw std::invalid_argument(where + ": " + settings_file.string() + "'s rig_model_path " + rig.string() +
                                  " lies in another scan's folder (" + owner.string() + ") and " + out.string() +
                                  " has no " + inside.lexically_relative(out).string() + ": the scan would use that folder");
    }
    r.rerooted = "rig_model_path " + rig.string() + " -> " + inside.string();
    s.rig_model_path = inside.string();
  }
  if (!fs::is_regular_file(s.rig_model_path)) {
    throw std::invalid_argument(where + ": " + settings_file.string() + "'s rig_model_path " + s.rig_model_path +
                                " is not a file");
  }
  return r;
}

}  // namespace pbnbv::launcher
