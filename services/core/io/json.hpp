#pragma once
// JSON helpers shared by everything that writes or reads the scan's files: poses and vectors as
// JSON, atomic writes (a reader never sees half a file), reads that name the file on error.
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <cstdint>
#include <string>

#include "core/base/pose.hpp"

namespace pbnbv {

nlohmann::json to_json(const Pose& p);  // {"position_m": [...], "quat_wxyz": [...]}
// The pose to_json wrote; throws std::invalid_argument naming `what` when a field is missing or
// not finite, or the quaternion is not a unit one (pose_from_arrays).
Pose pose_from_json(const nlohmann::json& j, const std::string& what);
nlohmann::json to_json(const Eigen::Vector3d& v);
Eigen::Vector3d vec3_from_json(const nlohmann::json& j, const std::string& what);
// A whole number in [lo, hi] (hi >= 0); throws std::invalid_argument naming `what` otherwise (a
// real, a string, a number out of range: get<int> would cast it without a word).
int64_t integer_from_json(const nlohmann::json& j, int64_t lo, int64_t hi, const std::string& what);

// Writes JSON to `path` atomically (temporary file + rename), so a reader never sees half.
void write_json_atomic(const nlohmann::json& j, const std::string& path);
void write_text_atomic(const std::string& text, const std::string& path);  // tmp + rename
nlohmann::json read_json(const std::string& path);  // throws naming the path
std::string read_text(const std::string& path);     // the whole file; throws naming the path

}  // namespace pbnbv
