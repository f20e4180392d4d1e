#pragma once
// Starting and supervising the scan's processes (POSIX fork/exec), for the launcher.
#include <sys/types.h>

#include <string>
#include <vector>

namespace pbnbv::process {

struct Child {
  std::string name;       // "twin", "motion", ...
  std::vector<std::string> argv;
  std::string log_path;   // stdout+stderr go here ("" = inherit)
  std::string cwd;        // the folder it runs in ("" = the caller's)
  bool append_log = false;  // append to the log (a restart) instead of starting it anew
  bool stdout_to_terminal = false;  // keep stdout on the terminal (progress), stderr to the log
  // What the child gets when the process that started it dies, however it dies (SIGKILL
  // included: the kernel sends it, PR_SET_PDEATHSIG): SIGKILL for what has nothing to save,
  // SIGTERM for what writes its record on the way out (the coordinator, lcm-logger).
  int death_signal = 9;
  pid_t pid = -1;
  bool running = false;
  int exit_code = 0;      // valid when !running: exit status, or 128 + signal
};

// Starts the child; throws std::runtime_error naming it when fork/exec fails. The child dies
// with the calling process (death_signal).
void start(Child& child);

// Starts the child and waits for its end, at most timeout_s: returns its exit code; at the
// deadline it is killed (SIGKILL) and 128 + SIGKILL returned. Throws as start.
int run(Child& child, double timeout_s);

// Reaps children that exited (non-blocking); returns the ones that just stopped.
std::vector<Child*> reap(std::vector<Child>& children);

// Sends SIGTERM to every running child, waits up to grace_s, then SIGKILLs what remains.
void stop_all(std::vector<Child>& children, double grace_s);

// Last `n` lines of a text file ("" when unreadable).
std::string tail_lines(const std::string& path, int n);

}  // namespace pbnbv::process
