#pragma once
// One logger: timestamped lines on stderr, prefixed with the program's name.
#include <string>

namespace pbnbv {

void set_log_name(const std::string& program);
void log_info(const std::string& message);
void log_warn(const std::string& message);
void log_error(const std::string& message);

}  // namespace pbnbv
