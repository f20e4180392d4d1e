#pragma once
// Command-line options of every program: "--name value" and "--flag". One parser for all.
#include <Eigen/Core>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace pbnbv {

class Args {
 public:
  // Parses argv[first..argc). Throws std::invalid_argument for a stray positional word.
  Args(int argc, char** argv, int first = 1);

  bool has(const std::string& name) const;  // name without "--"
  bool flag(const std::string& name) const; // present as "--name" (no value) or "--name true"
  std::string str(const std::string& name, const std::string& fallback) const;
  std::string str(const std::string& name) const;  // required
  // Numbers: throw std::invalid_argument naming the option and the bad text, or a value
  // outside [lo, hi].
  double num(const std::string& name, double fallback, double lo, double hi) const;
  long integer(const std::string& name, long fallback, long lo, long hi) const;
  // "a,b,c" -> three numbers.
  Eigen::Vector3d vec3(const std::string& name, const Eigen::Vector3d& fallback) const;
  // Throws std::invalid_argument listing options that none of the getters asked for
  // (catches typos such as --veiws). Call after reading every option.
  void reject_unknown() const;

 private:
  std::map<std::string, std::string> values_;
  mutable std::set<std::string> used_;
};

}  // namespace pbnbv
