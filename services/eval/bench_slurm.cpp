#include "eval/bench_slurm.hpp"

#include <algorithm>
#include <cctype>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "core/io/json.hpp"
#include "process/processes.hpp"

namespace fs = std::filesystem;

namespace pbnbv::eval {

namespace {

// A word for bash: single-quoted, each ' as '\''.
std::string quoted(const std::string& w) {
  std::string out = "'";
  for (char c : w) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

void check_word(const std::string& option, const std::string& value) {
  if (value.size() > 100) throw std::invalid_argument(option + ": at most 100 characters, not " + std::to_string(value.size()));
  for (unsigned char c : value) {
    if (std::isspace(c) || std::iscntrl(c) || c == '\'' || c == '"' || c == '\\') {
      throw std::invalid_argument(option + " '" + value + "': one word, without white space, quotes or backslashes");
    }
  }
}

}  // namespace

void validate(const SlurmSpec& s) {
  check_word("--partition", s.partition);
  check_word("--account", s.account);
  check_word("--time-limit", s.time_limit);
  // sbatch --time: minutes, M:S, H:M:S, D-H, D-H:M, D-H:M:S.
  static const std::regex time(R"(\d{1,6}(:\d{1,2}){0,2}|\d{1,4}-\d{1,2}(:\d{1,2}){0,2})");
  if (!s.time_limit.empty() && !std::regex_match(s.time_limit, time)) {
    throw std::invalid_argument("--time-limit '" + s.time_limit +
                                "': minutes, M:S, H:M:S, D-H, D-H:M or D-H:M:S (Slurm's --time), e.g. 30 or 1:00:00");
  }
}

std::string slurm_task_script(const std::vector<SlurmTask>& tasks) {
  std::ostringstream s;
  s << "#!/bin/bash\n"
       "# Written by pbnbv bench: the scans (or evaluations) of one Slurm job array, task i the i-th below.\n"
       "# Each runs with its output into its log; SIGTERM or SIGINT (scancel, a time limit) reaches it as\n"
       "# SIGINT, on which a scan keeps what it has (a rerun of the bench resumes it); the task then\n"
       "# writes bench_task.json into its folder: its exit code, wall time, host and Slurm job.\n"
       "set -u\n"
       "case \"${SLURM_ARRAY_TASK_ID:-}\" in\n";
  for (std::size_t i = 0; i < tasks.size(); ++i) {
    s << "  " << i << ") dir=" << quoted(tasks[i].dir.string()) << "; log=" << quoted(tasks[i].log.string()) << "; cmd=(";
    for (std::size_t k = 0; k < tasks[i].argv.size(); ++k) s << (k ? " " : "") << quoted(tasks[i].argv[k]);
    s << ") ;;\n";
  }
  s << "  *) echo \"pbnbv bench: $0 has no task '${SLURM_ARRAY_TASK_ID:-}' (0.." << tasks.size() - 1 << ")\" >&2; exit 2 ;;\n"
       "esac\n"
       "mkdir -p \"$dir\" \"$(dirname \"$log\")\"\n"
       "rm -f \"$dir/bench_task.json\"\n"
       "start=$(date +%s.%N)\n"
       "\"${cmd[@]}\" >\"$log\" 2>&1 &\n"
       "pid=$!\n"
       "trap 'kill -INT \"$pid\" 2>/dev/null' TERM INT\n"
       "# wait returns early for a trapped signal: wait again until the scan has ended.\n"
       "while true; do\n"
       "  wait \"$pid\"\n"
       "  rc=$?\n"
       "  kill -0 \"$pid\" 2>/dev/null || break\n"
       "done\n"
       "wait \"$pid\" 2>/dev/null\n"
       "last=$?\n"
       "[ \"$last\" -ne 127 ] && rc=$last\n"
       "wall=$(awk -v a=\"$start\" -v b=\"$(date +%s.%N)\" 'BEGIN { printf \"%.3f\", b - a }')\n"
       "printf '{\"exit_code\": %d, \"wall_s\": %s, \"host\": \"%s\", \"slurm_job\": \"%s_%s\"}\\n' \"$rc\" \"$wall\" "
       "\"$(hostname)\" \"${SLURM_ARRAY_JOB_ID:-}\" \"${SLURM_ARRAY_TASK_ID:-}\" >\"$dir/bench_task.json.tmp\" &&\n"
       "  mv \"$dir/bench_task.json.tmp\" \"$dir/bench_task.json\"\n"
       "exit \"$rc\"\n";
  return s.str();
}

std::vector<std::string> sbatch_argv(const SlurmSpec& s, const fs::path& script, int n, const fs::path& slurm_dir,
                                     bool exclusive, const std::string& job_name) {
  std::vector<std::string> a = {"sbatch", "--parsable", "--job-name=" + job_name, "--array=0-" + std::to_string(n - 1),
                                "--cpus-per-task=1", "--output=" + (slurm_dir / "slurm-%A_%a.out").string()};
  if (!s.partition.empty()) a.push_back("--partition=" + s.partition);
  if (!s.account.empty()) a.push_back("--account=" + s.account);
  if (!s.time_limit.empty()) a.push_back("--time=" + s.time_limit);
  if (exclusive) a.push_back("--exclusive");
  a.push_back(script.string());
  return a;
}

bool SlurmTaskState::ended() const {
  static const std::vector<std::string> final_states = {"COMPLETED", "FAILED",    "CANCELLED", "TIMEOUT",  "NODE_FAIL",
                                                         "OUT_OF_MEMORY", "PREEMPTED", "BOOT_FAIL", "DEADLINE", "REVOKED",
                                                         "SPECIAL_EXIT"};
  return std::find(final_states.begin(), final_states.end(), state) != final_states.end();
}

std::map<int, SlurmTaskState> parse_squeue(const std::string& text, const std::string& job_id) {
  std::map<int, SlurmTaskState> out;
  std::istringstream in(text);
  std::string line;
  const std::string prefix = job_id + "_";
  while (std::getline(in, line)) {
    const auto bar = line.find('|');
    if (bar == std::string::npos || line.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string task = line.substr(prefix.size(), bar - prefix.size());
    if (task.empty() || task.size() > 9 || !std::all_of(task.begin(), task.end(), ::isdigit)) continue;  // "[3-5]"
    const auto bar2 = line.find('|', bar + 1);
    SlurmTaskState st;
    st.state = line.substr(bar + 1, bar2 == std::string::npos ? std::string::npos : bar2 - bar - 1);
    if (bar2 != std::string::npos) st.reason = line.substr(bar2 + 1);
    while (!st.reason.empty() && std::isspace(static_cast<unsigned char>(st.reason.back()))) st.reason.pop_back();
    out[std::stoi(task)] = st;
  }
  return out;
}

int SlurmQueue::run(const std::vector<std::string>& argv, const std::string& name, std::string& output, double timeout_s) {
  fs::create_directories(dir_);
  process::Child c;
  c.name = name;
  c.argv = argv;
  c.log_path = (dir_ / (name + ".out")).string();
  int code = 0;
  try {
    code = process::run(c, timeout_s);
  } catch (const std::exception& e) {
    throw std::runtime_error(argv[0] + " could not be run (" + e.what() + "): is Slurm installed here (slurm-wlm)?");
  }
  output = fs::exists(c.log_path) ? read_text(c.log_path) : std::string();
  return code;
}

std::string SlurmQueue::submit(const SlurmSpec& s, const std::vector<SlurmTask>& tasks, bool exclusive) {
  const fs::path script = dir_ / (kind_ + "-" + std::to_string(++submissions_) + ".sh");
  fs::create_directories(dir_);
  write_text_atomic(slurm_task_script(tasks), script.string());
  fs::permissions(script, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add);
  std::string out;
  const int code = run(sbatch_argv(s, script, static_cast<int>(tasks.size()), dir_, exclusive,
                                       kind_ == "submit" ? "pbnbv-bench" : "pbnbv-" + kind_),
                           "sbatch", out, 60);
  while (!out.empty() && std::isspace(static_cast<unsigned char>(out.back()))) out.pop_back();
  // --parsable: "<job id>" or "<job id>;<cluster>".
  const std::string id = out.substr(0, out.find(';'));
  if (code != 0 || id.empty() || !std::all_of(id.begin(), id.end(), ::isdigit)) {
    throw std::runtime_error("sbatch refused the scans (exit " + std::to_string(code) + "): " + out +
                             (std::getenv("SLURM_CONF") ? "" : " (SLURM_CONF is not set: scripts/slurm-local start prints it)"));
  }
  return id;
}

std::optional<std::map<std::string, std::map<int, SlurmTaskState>>> SlurmQueue::states(const std::vector<std::string>& job_ids) {
  const auto now = std::chrono::steady_clock::now();
  if (last_ && now - last_query_ < std::chrono::seconds(1)) return last_;
  last_query_ = now;
  std::map<std::string, std::map<int, SlurmTaskState>> all;
  for (const std::string& id : job_ids) {
    std::string out;
    const int code = run({"squeue", "-h", "-r", "--states=all", "-j", id, "-o", "%i|%T|%r"}, "squeue", out, 30);
    if (code != 0) {
      // A job Slurm has forgotten (past MinJobAge) is "Invalid job id": its tasks' own records tell.
      if (out.find("Invalid job id") != std::string::npos) {
        all[id] = {};
        continue;
      }
      return std::nullopt;  // no answer now: ask again
    }
    all[id] = parse_squeue(out, id);
  }
  last_ = all;
  return all;
}

void SlurmQueue::cancel(const std::vector<std::string>& job_ids) {
  if (job_ids.empty()) return;
  std::vector<std::string> argv = {"scancel"};
  argv.insert(argv.end(), job_ids.begin(), job_ids.end());
  std::string out;
  run(argv, "scancel", out, 30);
}

}  // namespace pbnbv::eval
