#pragma once
// Helpers for the integration tests: run a command, capture its output, find the binaries.
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace pbnbv::testing {

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

inline CommandResult run_command(const std::string& command) {
  CommandResult r;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

inline std::string env_or(const char* name, const std::string& fallback) {
  const char* v = std::getenv(name);
  return v && *v ? v : fallback;
}

// Compiled in by tests/CMakeLists.txt; the environment may override them.
inline std::string bin_dir() { return env_or("PBNBV_BIN_DIR", PBNBV_TEST_BIN_DIR); }
inline std::string source_dir() { return env_or("PBNBV_SOURCE_DIR", PBNBV_TEST_SOURCE_DIR); }
inline std::string netns_run() { return source_dir() + "/scripts/netns-run"; }

// A fresh empty folder under the system temp dir.
inline std::filesystem::path fresh_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("pbnbv-test-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace pbnbv::testing
