#pragma once
// Helpers for the integration tests: run a command, capture its output, find the binaries.
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <signal.h>
#include <unistd.h>
#include <cerrno>

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

// `pbnbv scan` options for a small image with the default camera's field of view (320 x 180 at
// fx = fy = 174 px): for the tests of what processes do (faults, restarts, replay), where the
// frame's size is not what is tested and a quarter of the pixels renders, filters and registers
// in a fraction of the time.
inline constexpr const char* kSmallImageOptions = "--width 320 --height 180 --fx 174 --fy 174";

// A text file's contents ("" when it cannot be read).
inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// A fresh empty folder under the system temp dir.
// An empty folder for one test, /tmp/pbnbv-test-NAME-PID. Folders of the same NAME left by earlier
// runs whose process is gone are removed first: each run of the suite left about 5 GB behind
// (scan folders, logs), and a few runs filled the disk.
inline std::filesystem::path fresh_dir(const std::string& name) {
  namespace fs = std::filesystem;
  const std::string prefix = "pbnbv-test-" + name + "-";
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(fs::temp_directory_path(), ec)) {
    const std::string n = e.path().filename().string();
    if (n.rfind(prefix, 0) != 0) continue;
    const std::string pid = n.substr(prefix.size());
    if (pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos) continue;
    if (::kill(static_cast<pid_t>(std::stol(pid)), 0) != 0 && errno == ESRCH) fs::remove_all(e.path(), ec);
  }
  const auto dir = fs::temp_directory_path() / (prefix + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

}  // namespace pbnbv::testing
