#pragma once
// scan.json as a file: the format this pbnbv writes (format_version, and pbnbv_version naming the
// writer) and the one way to read it. Every command that reads a scan folder's scan.json (resume,
// replay, evaluate, mesh, the view page, the bench) goes through read_scan_json, so that a record
// of another format is refused by name instead of being read by key and misunderstood. The record
// itself is written by ScanRecord (scan_record.hpp).
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>


namespace pbnbv {

// The format of scan.json this pbnbv writes and reads. 1: the first with a version (pbnbv 0.11),
// views[].view counted from 0; 2: views[].view counted from 1, as the files (view_001) and the
// console count them. A record without format_version was written by pbnbv 0.10 or older.
inline constexpr int kScanFormatVersion = 2;

// scan.json (a path to the file, or to the scan folder holding it) parsed and checked: a JSON
// object of format kScanFormatVersion. Throws std::invalid_argument naming the file for a missing
// or unreadable file, and for another format, naming both formats and the pbnbv that wrote it:
//   "DIR/scan.json: format 1 (written by pbnbv 0.11.0); this pbnbv (0.12.0) reads format 2 only".
nlohmann::json read_scan_json(const std::filesystem::path& scan_json_or_folder);

// scan.json's "status" object (state, message, views_done, views_planned, ...), of a record of any
// format (every format has it): what `pbnbv bench` and `pbnbv scan --resume` ask of a folder
// before reading it. Throws naming the file when it is missing or unreadable.
nlohmann::json read_scan_status(const std::filesystem::path& scan_folder);
// The scan id its settings name ("" when they name none: a record the launcher started with its
// last word only, write_scan_state), of a record of this format: what `pbnbv scan --resume`
// checks against the folder's settings.json before anything runs. Throws as read_scan_json.
std::string recorded_scan_id(const std::filesystem::path& scan_json_or_folder);
// Its "state" ("running", "done", "stopped", "failed"), or "" when the folder holds no readable
// record.
std::string recorded_state(const std::filesystem::path& scan_folder);

// Sets the status's state and message in the folder's scan.json (written atomically): the
// launcher's word on how a scan ended when the coordinator could not say it (it died, or the scan
// was stopped around it). A folder without a record gets one holding only this status.
void write_scan_state(const std::filesystem::path& scan_folder, const std::string& state, const std::string& message);

// A view entry's frame file: "frames/view_NNN.ply" for its "view" N (counted from 1: 1 ..
// kViews.max, NNN = N), or "" when the entry names none. Throws naming `scan_json` and the view when it names any other path:
// no path is taken from the file.
std::string view_frame_file(const nlohmann::json& view, const std::filesystem::path& scan_json);

}  // namespace pbnbv
