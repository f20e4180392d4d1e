#include "core/io/json.hpp"

#include "core/base/atomic_file.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace pbnbv {

nlohmann::json to_json(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

Eigen::Vector3d vec3_from_json(const nlohmann::json& j, const std::string& what) {
  if (!j.is_array() || j.size() != 3) throw std::invalid_argument(what + " must be an array of 3 numbers");
  return Eigen::Vector3d(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
}

int64_t integer_from_json(const nlohmann::json& j, int64_t lo, int64_t hi, const std::string& what) {
  if (j.is_number_unsigned()) {
    const uint64_t u = j.get<uint64_t>();
    if (u <= static_cast<uint64_t>(hi) && static_cast<int64_t>(u) >= lo) return static_cast<int64_t>(u);
  } else if (j.is_number_integer()) {
    const int64_t v = j.get<int64_t>();
    if (v >= lo && v <= hi) return v;
  }
  throw std::invalid_argument(what + " = " + j.dump() + " is not a whole number in " + std::to_string(lo) + ".." +
                              std::to_string(hi));
}

nlohmann::json to_json(const Pose& p) {
  double pos[3], quat[4];
  pose_to_arrays(p, pos, quat);
  return {{"position_m", {pos[0], pos[1], pos[2]}}, {"quat_wxyz", {quat[0], quat[1], quat[2], quat[3]}}};
}

Pose pose_from_json(const nlohmann::json& j, const std::string& what) {
  double pos[3], quat[4];
  try {
    for (int i = 0; i < 3; ++i) pos[i] = j.at("position_m").at(i).get<double>();
    for (int i = 0; i < 4; ++i) quat[i] = j.at("quat_wxyz").at(i).get<double>();
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(what + " is not a pose {\"position_m\": [x, y, z], \"quat_wxyz\": [w, x, y, z]}");
  }
  return pose_from_arrays(pos, quat, what);  // checks finiteness and the quaternion's norm
}

void write_text_atomic(const std::string& text, const std::string& path) { write_file_atomic(path, text); }

void write_json_atomic(const nlohmann::json& j, const std::string& path) { write_text_atomic(j.dump(2) + "\n", path); }

nlohmann::json read_json(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + " is not valid JSON: " + e.what());
  }
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace pbnbv
