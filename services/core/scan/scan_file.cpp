#include "core/scan/scan_file.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "core/base/version.hpp"
#include "core/base/format.hpp"
#include "core/io/json.hpp"
#include "core/scan/scan_settings.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv {

json read_scan_json(const fs::path& scan_json_or_folder) {
  const fs::path path =
      fs::is_directory(scan_json_or_folder) ? scan_json_or_folder / "scan.json" : scan_json_or_folder;
  json scan = read_json(path.string());
  if (!scan.is_object()) throw std::invalid_argument(path.string() + ": not a scan record (expected a JSON object)");
  const auto version = scan.find("format_version");
  if (version == scan.end()) {
    throw std::invalid_argument(fmt::format(
        "{}: a record without format_version (written by pbnbv 0.10 or older); this pbnbv ({}) reads format {} only",
        path.string(), pbnbv_version(), kScanFormatVersion));
  }
  const int64_t format = integer_from_json(*version, 0, 1'000'000, path.string() + " format_version");
  if (format != kScanFormatVersion) {
    const auto writer = scan.find("pbnbv_version");
    const std::string by =
        writer != scan.end() && writer->is_string() ? "pbnbv " + writer->get<std::string>() : "an unknown pbnbv";
    throw std::invalid_argument(fmt::format("{}: format {} (written by {}); this pbnbv ({}) reads format {} only",
                                            path.string(), format, by, pbnbv_version(), kScanFormatVersion));
  }
  return scan;
}

json read_scan_status(const fs::path& scan_folder) {
  const fs::path path = scan_folder / "scan.json";
  const json scan = read_json(path.string());
  if (!scan.is_object() || !scan.contains("status") || !scan["status"].is_object()) {
    throw std::invalid_argument(path.string() + ": no \"status\" object (not a scan record)");
  }
  return scan["status"];
}

std::string recorded_state(const fs::path& scan_folder) {
  try {
    const json status = read_scan_status(scan_folder);
    const auto state = status.find("state");
    return state != status.end() && state->is_string() ? state->get<std::string>() : "";
  } catch (const std::exception&) {
    return "";
  }
}

void write_scan_state(const fs::path& scan_folder, const std::string& state, const std::string& message) {
  const fs::path path = scan_folder / "scan.json";
  json scan = json::object();
  if (fs::exists(path)) scan = read_json(path.string());
  if (!scan.is_object()) throw std::invalid_argument(path.string() + ": not a scan record (expected a JSON object)");
  if (!scan.contains("format_version")) {
    scan["format_version"] = kScanFormatVersion;
    scan["pbnbv_version"] = std::string(pbnbv_version());
  }
  json& status = scan["status"];
  if (!status.is_object()) status = json::object();
  status["state"] = state;
  status["message"] = message;
  write_json_atomic(scan, path.string());
}

std::string recorded_scan_id(const fs::path& scan_json_or_folder) {
  const json scan = read_scan_json(scan_json_or_folder);
  const json& settings = scan.contains("settings") ? scan["settings"] : json();
  if (!settings.is_object() || !settings.contains("scan_id") || !settings["scan_id"].is_string()) return "";
  return settings["scan_id"].get<std::string>();
}

std::string view_frame_file(const json& v, const fs::path& scan_json) {
  if (!v.is_object() || !v.contains("frame_file")) return "";
  const json& n = v.contains("view") ? v["view"] : json();
  if (!n.is_number_integer() || n.get<int64_t>() < 1 || n.get<int64_t>() > kViews.max) {
    throw std::invalid_argument(scan_json.string() + ": a view entry with a frame_file has no view number 1.." +
                                std::to_string(kViews.max));
  }
  const int view = n.get<int>();  // counted from 1, as the file's name
  const std::string own = frame_file_of(view - 1);
  if (v["frame_file"] != own) {
    throw std::invalid_argument(scan_json.string() + " view " + std::to_string(view) + ": frame_file is not " + own);
  }
  return own;
}

}  // namespace pbnbv
