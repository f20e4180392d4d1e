#pragma once
// Reading a JSON record field by field, each field checked as it is read (core/io).
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/base/pose.hpp"
#include "core/io/json.hpp"

namespace pbnbv {

// A JSON object read field by field, each error naming where it is and what is wrong
// ("DIR/scan.json view 3 move position_error_m is not a number"): std::invalid_argument. The
// readers of the project's own records (scan.json, a bench's evaluation records) read through it.
class JsonFields {
 public:
  JsonFields(const nlohmann::json& j, std::string where) : j_(j), where_(std::move(where)) {
    if (!j_.is_object()) fail("", "is not an object");
  }
  bool has(const char* key) const { return j_.contains(key) && !j_[key].is_null(); }
  const nlohmann::json& at(const char* key) const {
    if (!j_.contains(key)) fail(key, "is missing");
    return j_[key];
  }
  JsonFields object(const char* key) const { return JsonFields(at(key), where_ + " " + key); }
  double number(const char* key) const {
    const nlohmann::json& v = at(key);
    if (v.is_null()) return std::nan("");  // NaN is written as null
    if (!v.is_number()) fail(key, "is not a number");
    return v.get<double>();
  }
  int64_t integer(const char* key, int64_t lo, int64_t hi) const { return integer_from_json(at(key), lo, hi, name(key)); }
  int count(const char* key) const { return static_cast<int>(integer(key, 0, INT32_MAX)); }
  bool flag(const char* key) const {
    if (!at(key).is_boolean()) fail(key, "is not true or false");
    return at(key).get<bool>();
  }
  std::string text(const char* key) const {
    if (!at(key).is_string()) fail(key, "is not a string");
    return at(key).get<std::string>();
  }
  Pose pose(const char* key) const { return pose_from_json(at(key), name(key)); }
  Eigen::Vector3d vector3(const char* key) const {
    const nlohmann::json& v = at(key);
    if (!v.is_array() || v.size() != 3) fail(key, "is not 3 numbers");
    Eigen::Vector3d out;
    for (int k = 0; k < 3; ++k) {
      if (!v[k].is_number()) fail(key, "is not 3 numbers");
      out[k] = v[k].get<double>();
    }
    return out;
  }
  Vector6d vector6(const char* key) const {
    const nlohmann::json& v = at(key);
    if (!v.is_array() || v.size() != 6) fail(key, "is not 6 numbers");
    Vector6d out;
    for (int k = 0; k < 6; ++k) {
      if (!v[k].is_number()) fail(key, "is not 6 numbers");
      out[k] = v[k].get<double>();
    }
    return out;
  }
  // A list of numbers (null: NaN) or of strings, each checked.
  template <class T>
  std::vector<T> list(const char* key) const {
    const nlohmann::json& v = at(key);
    if (!v.is_array()) fail(key, "is not a list");
    std::vector<T> out;
    for (const nlohmann::json& x : v) {
      if constexpr (std::is_same_v<T, std::string>) {
        if (!x.is_string()) fail(key, "holds a value that is not a string");
        out.push_back(x.get<std::string>());
      } else if constexpr (std::is_integral_v<T>) {
        out.push_back(static_cast<T>(integer_from_json(x, INT32_MIN, INT32_MAX, name(key))));
      } else {
        if (!x.is_number() && !x.is_null()) fail(key, "holds a value that is not a number");
        out.push_back(x.is_null() ? std::nan("") : x.get<double>());
      }
    }
    return out;
  }
  std::string name(const char* key) const { return where_ + " " + key; }
  [[noreturn]] void fail(const char* key, const std::string& what) const {
    throw std::invalid_argument(where_ + (key && *key ? std::string(" ") + key : std::string()) + " " + what);
  }
  const std::string& where() const { return where_; }

 private:
  const nlohmann::json& j_;
  std::string where_;
};

}  // namespace pbnbv
