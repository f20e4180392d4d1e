#pragma once
// The benchmark on a Slurm cluster: each scan one task of a job array (sbatch), run on whatever
// node Slurm gives it, writing into the bench folder on a file system every node shares. The
// launcher submits, watches the tasks (squeue, at most once a second), resubmits a failed or
// cancelled task once, and cancels the arrays (scancel) when stopped. What Slurm is asked to run
// is a batch script the launcher writes into the bench folder (slurm/submit-N.sh), readable by
// whoever wants to know what ran.
#include <chrono>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace pbnbv::eval {

// `pbnbv bench --slurm`: where and how long the tasks may run ("" : Slurm's defaults).
struct SlurmSpec {
  std::string partition;   // --partition
  std::string account;     // --account
  std::string time_limit;  // --time-limit, Slurm's form ("30", "1:00:00", "1-00:00:00")
};

// Throws std::invalid_argument naming the option when a value holds what sbatch would not take as
// one word (white space, quotes, control characters; over 100 characters), or the time limit is
// not minutes, M:S, H:M:S, D-H, D-H:M or D-H:M:S.
void validate(const SlurmSpec& s);

// One task: its command, its folder (it writes bench_task.json there) and its log.
struct SlurmTask {
  std::vector<std::string> argv;
  std::filesystem::path dir, log;
};

// The batch script of an array of `tasks`: task i (SLURM_ARRAY_TASK_ID) runs tasks[i].argv with
// its output into tasks[i].log, passes SIGTERM and SIGINT on to it as SIGINT (a scan keeps what it
// has), and writes tasks[i].dir/bench_task.json: {"exit_code", "wall_s", "host", "slurm_job"}.
// Every word is quoted for bash.
std::string slurm_task_script(const std::vector<SlurmTask>& tasks);

// sbatch's command for an array of `n` tasks (ids 0..n-1) of `script`: --parsable, one CPU a
// task, the job named `job_name`, Slurm's own output of each task into `slurm_dir`
// (slurm-<job>_<task>.out), the spec's partition, account and time limit; `exclusive`: one task
// per node (the scans share the node's bus when they cannot have namespaces of their own).
std::vector<std::string> sbatch_argv(const SlurmSpec& s, const std::filesystem::path& script, int n,
                                     const std::filesystem::path& slurm_dir, bool exclusive,
                                     const std::string& job_name = "pbnbv-bench");

// A task as squeue shows it.
struct SlurmTaskState {
  std::string state;   // PENDING, RUNNING, COMPLETED, FAILED, CANCELLED, TIMEOUT, ...
  std::string reason;  // Slurm's reason (Resources, NonZeroExitCode, ...)
  bool ended() const;  // a state a task does not leave
};
// The tasks of array `job_id` in squeue's output (`-h -r --states=all -o %i|%T|%r`): by task id.
// Lines of other jobs and a pending range not yet split ("12_[3-5]") are skipped.
std::map<int, SlurmTaskState> parse_squeue(const std::string& text, const std::string& job_id);

// Slurm's commands (sbatch, squeue, scancel on the PATH, SLURM_CONF from the environment), each
// with a deadline; their output goes through files in `slurm_dir`. `kind` names the arrays'
// scripts (<kind>-N.sh) and jobs: "submit" for the scans (jobs named pbnbv-bench), "evaluate"
// for the evaluations (pbnbv-evaluate).
class SlurmQueue {
 public:
  explicit SlurmQueue(std::filesystem::path slurm_dir, std::string kind = "submit")
      : dir_(std::move(slurm_dir)), kind_(std::move(kind)) {}
  // Submits the array; returns its job id. Throws std::runtime_error with sbatch's message.
  std::string submit(const SlurmSpec& s, const std::vector<SlurmTask>& tasks, bool exclusive);
  // The tasks of the arrays, by job id then task id (none when squeue does not answer in time:
  // ask again later). At most once a second, whatever the caller does: a call sooner returns the
  // last answer.
  std::optional<std::map<std::string, std::map<int, SlurmTaskState>>> states(const std::vector<std::string>& job_ids);
  // scancel of the arrays (every task: pending ones do not start, running ones are signalled).
  void cancel(const std::vector<std::string>& job_ids);

 private:
  int run(const std::vector<std::string>& argv, const std::string& name, std::string& output, double timeout_s);
  std::filesystem::path dir_;
  std::string kind_;
  int submissions_ = 0;
  std::chrono::steady_clock::time_point last_query_{};
  std::optional<std::map<std::string, std::map<int, SlurmTaskState>>> last_;
};

}  // namespace pbnbv::eval
