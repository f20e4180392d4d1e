#pragma once
// Numbers as the launcher writes them: on command lines (every digit, so a child process gets
// the exact value) and in reports (fixed decimals).
#include <sstream>
#include <string>

namespace pbnbv {

// 17 significant digits: reads back as the same double.
inline std::string exact(double x) {
  std::ostringstream os;
  os.precision(17);
  os << x;
  return os.str();
}

// x with `digits` decimals.
inline std::string fixed(double x, int digits = 1) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(digits);
  os << x;
  return os.str();
}

}  // namespace pbnbv
