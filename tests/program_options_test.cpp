// The command line of every program, run as the user runs it: `pbnbv` and its commands, each
// service and the twin answer --help and --version (the project's version) with exit 0, and a
// missing value, a repeated option, a number out of its range, a bad choice and an unknown
// option each end the program with exit 2 and a message naming the option, before the program
// touches the bus, the renderer or the file system.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "test_util.hpp"

using namespace pbnbv::testing;

namespace {

struct Case {
  std::string args;     // after the program
  std::string message;  // expected in the output
};

struct Program {
  std::string name;        // the binary
  std::string command;     // "scan" for pbnbv, else ""
  std::vector<Case> bad;   // each exits 2 with its message
  std::string help_names;  // an option the help must list
};

std::vector<Program> programs() {
  return {
      {"pbnbv",
       "scan",
       {{"--views", "--views needs a value"},
        {"--out --views 3", "--out: missing value (the next word, '--views', is an option)"},
        {"--views 3 --views 4", "--views is given 2 times (3, 4): give it once"},
        {"--views 2000", "--views: 2000 is outside its range [1, 1000]"},
        {"--planner best", "--planner: unknown planner 'best' (expected pbnbv, pbnbv-paper, raycast, random, ring or oracle)"},
        {"--veiws 3", "unknown option --veiws (did you mean --views?)"}},
       "--tmax N"},
      {"pbnbv",
       "bench",
       {{"--out", "--out needs a value"},
        {"--jobs 2 --jobs 3 --out x", "--jobs is given 2 times (2, 3): give it once"},
        {"--jobs 100 --out x", "--jobs: 100 is outside its range [1, 64]"},
        {"--rig crane --out x", "--rig: unknown rig kind 'crane' (expected arm or free)"},
        {"--objets sphere --out x", "unknown option --objets (did you mean --objects?)"}},
       "--planners"},
      {"pbnbv",
       "rig-check",
       {{"--deadline 0", "--deadline: 0 is outside its range [0.5, 600] s"},
        {"--rig-model", "--rig-model needs a value"},
        {"--rig-model /nonexistent.xml", "pbnbv rig-check: rig model /nonexistent.xml: cannot open the file"},
        {"--dedline 3", "unknown option --dedline (did you mean --deadline?)"}},
       "--passive"},
      {"pbnbv-motion",
       "",
       {{"--rig", "--rig needs a value"},
        {"--rig arm --rig free", "--rig is given 2 times (arm, free): give it once"},
        {"--rig crane", "--rig: unknown rig kind 'crane' (expected arm or free)"},
        {"--modle x.xml", "unknown option --modle (did you mean --model?)"}},
       "--model PATH"},
      {"pbnbv-camera",
       "",
       {{"--model", "--model needs a value"},
        {"--model a --model b", "--model is given 2 times (a, b): give it once"},
        {"--rig crane", "--rig: unknown rig kind 'crane'"},
        {"--rgi arm", "unknown option --rgi (did you mean --rig?)"}},
       "--rig arm|free"},
      {"pbnbv-registration",
       "",
       {{"--max-iterations", "--max-iterations needs a value"},
        {"--off --off", "--off is given 2 times: give it once"},
        {"--max-iterations 0", "--max-iterations: 0 is outside its range [1, 1000]"},
        {"--max-rmse 1", "--max-rmse: 1 is outside its range [1e-05, 0.1] m"},
        {"--icp-voxl 0.002", "unknown option --icp-voxl (did you mean --icp-voxel?)"}},
       "--model-voxel M"},
      {"pbnbv-mapping",
       "",
       {{"--resolution", "--resolution needs a value"},
        {"--resolution 0.03 --resolution 0.01", "--resolution is given 2 times (0.03, 0.01): give it once"},
        {"--resolution 0.5", "--resolution: 0.5 is outside its range [0.002, 0.2] m"},
        {"--volume-min 1,2", "--volume-min: '1,2' is not three numbers x,y,z"},
        {"--frontier-empty 18", "--frontier-empty: unknown frontier rule '18' (expected 6 or 26)"},
        {"--resolutoin 0.03", "unknown option --resolutoin (did you mean --resolution?)"}},
       "--volume-max x,y,z"},
      {"pbnbv-ellipsoids",
       "",
       {{"--tmax", "--tmax needs a value"},
        {"--tmax 5 --tmax 6", "--tmax is given 2 times (5, 6): give it once"},
        {"--tmax 500", "--tmax: 500 is outside its range [1, 200]"},
        {"--tmax 5.5", "--tmax: '5.5' is not a whole number"},
        {"--t-max 5", "unknown option --t-max (did you mean --tmax?)"}},
       "--tmax N"},
      {"pbnbv-scorer",
       "",
       {{"--rig", "--rig needs a value"},
        {"--rig free --rig free", "--rig is given 2 times (free, free): give it once"},
        {"--rig crane", "--rig: unknown rig kind 'crane'"},
        {"--rigs arm", "unknown option --rigs (did you mean --rig?)"},
        {"--out /tmp", "--out /tmp needs --scan ID: the figures in /tmp/plans are those of the one scan this scorer serves"},
        {"--scan s --out /nonexistent-pbnbv-folder",
         "--out /nonexistent-pbnbv-folder is not a folder (the scan's folder, made by the launcher)"}},
       "--model PATH"},
      {"pbnbv-coordinator",
       "",
       {{"", "--out is required"},
        {"--out", "--out needs a value"},
        {"--out a --out b", "--out is given 2 times (a, b): give it once"},
        {"--out a --setings s.json", "unknown option --setings (did you mean --settings?)"}},
       "--settings PATH"},
      {"pbnbv",
       "replay",
       {{"", "name the recorded scan's folder: pbnbv replay DIR"},
        {"d --planner best", "--planner: unknown planner 'best' (expected pbnbv, pbnbv-paper, raycast, random, ring or oracle)"},
        {"d --out", "--out needs a value"},
        {"d --ovewrite", "unknown option --ovewrite (did you mean --overwrite?)"}},
       "--planner"},
      {"pbnbv",
       "view",
       {{"--port", "--port needs a value"},
        {"--port 80", "--port: 80 is outside its range [1024, 65535]"},
        {"--port 9000 --port 9001", "--port is given 2 times (9000, 9001): give it once"},
        {"--prot 9000", "unknown option --prot (did you mean --port?)"}},
       "--cloud-voxel M"},
      {"pbnbv-replay-rig",
       "",
       {{"--recorded-scan x", "--log is required"},
        {"--log a --log b --recorded-scan x", "--log is given 2 times (a, b): give it once"},
        {"--log a", "--recorded-scan is required"},
        {"--log a --recorded-scan x --recorded-scn y", "unknown option --recorded-scn (did you mean --recorded-scan?)"}},
       "--recorded-scan ID"},
      {"pbnbv-twin",
       "",
       {{"--speed", "--speed needs a value"},
        {"--speed 2 --speed 3", "--speed is given 2 times (2, 3): give it once"},
        {"--speed 1000", "--speed: 1000 is outside its range [0.1, 100]"},
        {"--fx 0", "--fx: 0 is outside its range [1, 100000] px"},
        {"--rig crane", "--rig: unknown rig kind 'crane'"},
        {"--mesh-file x.stl", "unknown option --mesh-file (did you mean --mesh?)"},
        {"--fault slow", "--fault: unknown driver fault 'slow' (expected slow-status, no-seq-echo"}},
       "--hand-eye-error-mm MM"},
      {"pbnbv-ur-driver",
       "",
       {{"--rig-model r.xml", "--host is required"},
        {"--host h", "--rig-model is required"},
        {"--host h --rig-model r.xml --port 0", "--port: 0 is outside its range [1, 65535]"},
        {"--host h --rig-model r.xml --frequency 1000", "--frequency: 1000 is outside its range [10, 500] Hz"},
        {"--host h --rig-model r.xml --hots h", "unknown option --hots (did you mean --host?)"},
        {"--host 127.0.0.1 --rig-model /nonexistent-pbnbv-rig.xml", "/nonexistent-pbnbv-rig.xml"}},
       "--script-port"},
      {"pbnbv-twin",
       "",
       {{"--fault rtde-drop", "--fault rtde-drop is a UR controller's: it needs --rtde-port"},
        {"--rtde-port 30004 --ur-script-port 30004", "--rtde-port and --ur-script-port are both 30004"}},
       "--rtde-port"},
  };
}

std::string command_of(const Program& p, const std::string& args) {
  std::string c = bin_dir() + "/" + p.name;
  if (!p.command.empty()) c += " " + p.command;
  return c + (args.empty() ? "" : " " + args);
}

TEST(ProgramOptions, BadOptionsAreNamedAndExitTwo) {
  for (const Program& p : programs()) {
    for (const Case& c : p.bad) {
      const std::string command = command_of(p, c.args);
      const CommandResult r = run_command(command);
      EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.output;
      EXPECT_NE(r.output.find(c.message), std::string::npos) << command << "\n" << r.output;
    }
  }
}

TEST(ProgramOptions, HelpAndVersion) {
  for (const Program& p : programs()) {
    const std::string help = command_of(p, "--help");
    const CommandResult h = run_command(help);
    EXPECT_EQ(h.exit_code, 0) << help << "\n" << h.output;
    EXPECT_NE(h.output.find(p.help_names), std::string::npos) << help << "\n" << h.output;
    if (!p.command.empty()) continue;  // --version is the program's, not a command's
    const std::string version = bin_dir() + "/" + p.name + " --version";
    const CommandResult v = run_command(version);
    EXPECT_EQ(v.exit_code, 0) << version << "\n" << v.output;
    EXPECT_EQ(v.output, p.name + " " + PBNBV_TEST_VERSION + "\n") << version;
  }
  const CommandResult v = run_command(bin_dir() + "/pbnbv --version");
  EXPECT_EQ(v.output, std::string("pbnbv ") + PBNBV_TEST_VERSION + "\n");
}

}  // namespace
