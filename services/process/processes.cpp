#include "process/processes.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <fstream>
#include <stdexcept>
#include <thread>

namespace pbnbv::process {

void start(Child& child) {
  std::vector<char*> argv;
  for (auto& a : child.argv) argv.push_back(a.data());
  argv.push_back(nullptr);
  int log_fd = -1;
  if (!child.log_path.empty()) {
    log_fd = ::open(child.log_path.c_str(), O_WRONLY | O_CREAT | (child.append_log ? O_APPEND : O_TRUNC) | O_CLOEXEC, 0644);
    if (log_fd < 0) throw std::runtime_error("cannot open log " + child.log_path + ": " + std::strerror(errno));
  }
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("cannot start " + child.name + ": " + std::strerror(errno));
  if (pid == 0) {
    // Die with the parent; if it died before this line, it will not tell us: leave at once.
    if (::prctl(PR_SET_PDEATHSIG, child.death_signal) != 0 || ::getppid() != parent) ::_exit(126);
    if (log_fd >= 0) {
      if (!child.stdout_to_terminal) ::dup2(log_fd, STDOUT_FILENO);
      ::dup2(log_fd, STDERR_FILENO);
    }
    if (!child.cwd.empty() && ::chdir(child.cwd.c_str()) != 0) {
      std::fprintf(stderr, "cannot run %s in %s: %s\n", argv[0], child.cwd.c_str(), std::strerror(errno));
      ::_exit(127);
    }
    ::execvp(argv[0], argv.data());  // a bare name is looked up on PATH
    std::fprintf(stderr, "cannot run %s: %s\n", argv[0], std::strerror(errno));
    ::_exit(127);
  }
  if (log_fd >= 0) ::close(log_fd);
  child.pid = pid;
  child.running = true;
}

int run(Child& child, double timeout_s) {
  start(child);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  int status = 0;
  for (;;) {
    const pid_t r = ::waitpid(child.pid, &status, WNOHANG);
    if (r == child.pid) break;
    if (r < 0 && errno != EINTR) {
      child.running = false;
      throw std::runtime_error("cannot wait for " + child.name + ": " + std::strerror(errno));
    }
    if (std::chrono::steady_clock::now() >= deadline) {
      ::kill(child.pid, SIGKILL);
      ::waitpid(child.pid, &status, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  child.running = false;
  child.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return child.exit_code;
}

std::vector<Child*> reap(std::vector<Child>& children) {
  std::vector<Child*> stopped;
  for (auto& c : children) {
    if (!c.running) continue;
    int status = 0;
    const pid_t r = ::waitpid(c.pid, &status, WNOHANG);
    if (r == c.pid) {
      c.running = false;
      c.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      stopped.push_back(&c);
    }
  }
  return stopped;
}

void stop_all(std::vector<Child>& children, double grace_s) {
  for (auto& c : children) {
    if (c.running) ::kill(c.pid, SIGTERM);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(grace_s);
  while (std::chrono::steady_clock::now() < deadline) {
    reap(children);
    bool any = false;
    for (auto& c : children) any = any || c.running;
    if (!any) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  for (auto& c : children) {
    if (c.running) {
      ::kill(c.pid, SIGKILL);
      int status = 0;
      ::waitpid(c.pid, &status, 0);
      c.running = false;
      c.exit_code = 128 + SIGKILL;
    }
  }
}

std::string tail_lines(const std::string& path, int n) {
  std::ifstream in(path);
  if (!in) return "";
  std::deque<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    lines.push_back(line);
    if (static_cast<int>(lines.size()) > n) lines.pop_front();
  }
  std::string out;
  for (const auto& l : lines) out += "    " + l + "\n";
  return out;
}

}  // namespace pbnbv::process
