#include "core/base/args.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

namespace pbnbv {

Args::Args(int argc, char** argv, int first) {
  for (int i = first; i < argc; ++i) {
    std::string word = argv[i];
    if (word.rfind("--", 0) != 0 || word.size() == 2) {
      throw std::invalid_argument("unexpected argument '" + word + "' (options look like --name value)");
    }
    std::string name = word.substr(2);
    std::string value = "true";
    const auto eq = name.find('=');
    if (eq != std::string::npos) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
    } else if (i + 1 < argc) {
      const std::string next = argv[i + 1];
      // A following word is this option's value unless it is itself an option. Negative
      // numbers ("-0.5") are values.
      if (next.rfind("--", 0) != 0) {
        value = next;
        ++i;
      }
    }
    values_[name] = value;
  }
}

bool Args::has(const std::string& name) const {
  used_.insert(name);
  return values_.count(name) > 0;
}

bool Args::flag(const std::string& name) const {
  used_.insert(name);
  auto it = values_.find(name);
  if (it == values_.end()) return false;
  if (it->second == "true" || it->second == "1" || it->second == "yes") return true;
  if (it->second == "false" || it->second == "0" || it->second == "no") return false;
  throw std::invalid_argument("--" + name + " is a flag: expected no value, true or false, got '" +
                              it->second + "'");
}

std::string Args::str(const std::string& name, const std::string& fallback) const {
  used_.insert(name);
  auto it = values_.find(name);
  return it == values_.end() ? fallback : it->second;
}

std::string Args::str(const std::string& name) const {
  used_.insert(name);
  auto it = values_.find(name);
  if (it == values_.end()) throw std::invalid_argument("missing required option --" + name);
  return it->second;
}

namespace {
double parse_double(const std::string& name, const std::string& text) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(v)) {
    throw std::invalid_argument("--" + name + ": '" + text + "' is not a finite number");
  }
  return v;
}
}  // namespace

double Args::num(const std::string& name, double fallback, double lo, double hi) const {
  used_.insert(name);
  auto it = values_.find(name);
  const double v = it == values_.end() ? fallback : parse_double(name, it->second);
  if (v < lo || v > hi) {
    std::ostringstream os;
    os << "--" << name << " = " << v << " is out of range [" << lo << ", " << hi << "]";
    throw std::invalid_argument(os.str());
  }
  return v;
}

long Args::integer(const std::string& name, long fallback, long lo, long hi) const {
  used_.insert(name);
  auto it = values_.find(name);
  long v = fallback;
  if (it != values_.end()) {
    errno = 0;
    char* end = nullptr;
    v = std::strtol(it->second.c_str(), &end, 10);
    if (it->second.empty() || end != it->second.c_str() + it->second.size() || errno == ERANGE) {
      throw std::invalid_argument("--" + name + ": '" + it->second + "' is not a whole number");
    }
  }
  if (v < lo || v > hi) {
    std::ostringstream os;
    os << "--" << name << " = " << v << " is out of range [" << lo << ", " << hi << "]";
    throw std::invalid_argument(os.str());
  }
  return v;
}

Eigen::Vector3d Args::vec3(const std::string& name, const Eigen::Vector3d& fallback) const {
  used_.insert(name);
  auto it = values_.find(name);
  if (it == values_.end()) return fallback;
  Eigen::Vector3d v;
  std::stringstream ss(it->second);
  std::string part;
  int n = 0;
  while (std::getline(ss, part, ',')) {
    if (n >= 3) break;
    v[n++] = parse_double(name, part);
  }
  if (n != 3 || ss.rdbuf()->in_avail() > 0) {
    throw std::invalid_argument("--" + name + ": '" + it->second + "' is not three numbers x,y,z");
  }
  return v;
}

void Args::reject_unknown() const {
  std::string unknown;
  for (const auto& kv : values_) {
    if (!used_.count(kv.first)) unknown += (unknown.empty() ? "--" : ", --") + kv.first;
  }
  if (!unknown.empty()) throw std::invalid_argument("unknown option(s): " + unknown);
}

}  // namespace pbnbv
