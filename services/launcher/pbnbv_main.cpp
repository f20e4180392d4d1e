// pbnbv: the command a user runs (pbnbv help: every command and option).
//   pbnbv scan [options]     twin-in-the-loop scan of an object
//   pbnbv bench [options]    every planner on every object in the twin
//   pbnbv ablate tmax|beta|initial-view|resolution [options]
//   pbnbv spy                lcm-spy with every pbnbv channel decoded
//   pbnbv view [DIR] [--port P]  the scan (live, or a finished folder) in 3-D in a browser (pbnbv-view)
//   pbnbv stop [options]     halt the rig and end a scan
//   pbnbv rig-host [options] the motion executor and camera service on the rig's computer
//   pbnbv rig-check [--rig-model FILE] [--deadline S] [--passive]   the drivers against the contract
//   pbnbv calibrate --rig-model FILE --sphere-radius R   hand-eye and turntable calibration
//   pbnbv stop [--scan ID]   halt the rig and end the scan
//   pbnbv replay DIR         run a recorded scan through the pipeline again and compare
//   pbnbv evaluate DIR|FILE [--reference MESH]   accuracy and F-score against a reference mesh
//   pbnbv mesh DIR           (re)build a finished scan's surface mesh
// The command line is launcher/command_line.hpp; running each command, launcher/commands.hpp.
#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <vector>

#include "core/base/install_paths.hpp"
#include "eval/bench_evaluation.hpp"
#include "launcher/command_line.hpp"
#include "launcher/commands.hpp"

using namespace pbnbv;
namespace fs = std::filesystem;

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "view") {  // pbnbv-view has its own command line
    const std::string view = (fs::path(services_dir()) / "pbnbv-view").string();
    std::vector<char*> args = {const_cast<char*>(view.c_str())};
    for (int i = 2; i < argc; ++i) args.push_back(argv[i]);
    args.push_back(nullptr);
    ::execv(view.c_str(), args.data());
    std::cerr << "pbnbv view: cannot run " << view << " (build it: ./scripts/setup)" << std::endl;
    return 2;
  }
  // pbnbv bench's evaluation of one object's scans, a task of its own (eval/bench_evaluation.hpp):
  // not a command for users, so not in the help.
  if (argc > 1 && std::string(argv[1]) == "bench-evaluate") {
    if (argc != 3) {
      std::cerr << "pbnbv bench-evaluate REQUEST: pbnbv bench runs it, with the request it wrote" << std::endl;
      return 2;
    }
    try {
      eval::run_evaluation_task(argv[2], std::cout);
      return 0;
    } catch (const std::exception& e) {
      std::cerr << "pbnbv bench-evaluate " << argv[2] << ": " << e.what() << std::endl;
      return 2;
    }
  }
  launcher::CommandLine line;
  if (const std::optional<int> code = line.parse(argc, argv, std::cout, std::cerr)) return *code;
  const fs::path self = fs::read_symlink("/proc/self/exe");
  const std::string command = argc > 1 ? argv[1] : "help";
  try {
    switch (line.command()) {
      case launcher::Command::kScan:
        return launcher::run_scan(line.scan(), services_dir());
      case launcher::Command::kBench:
        if (line.sweep().benches.size() > 1) return launcher::run_sweep(line.sweep(), self);
        return launcher::run_bench(line.bench(), self);
      case launcher::Command::kAblate:
        return launcher::run_ablate(line.ablate(), self);
      case launcher::Command::kSpy:
        return launcher::run_spy();
      case launcher::Command::kCalibrate:
        return launcher::run_calibrate(line.calibrate());
      case launcher::Command::kStop:
        return launcher::run_stop(line.stop());
      case launcher::Command::kImportUrdf:
        return launcher::run_import_urdf(line.import_urdf());
      case launcher::Command::kRigHost:
        return launcher::run_rig_host(line.rig_host(), services_dir());
      case launcher::Command::kRigCheck:
        return launcher::run_rig_check(line.rig_check());
      case launcher::Command::kReplay:
        return launcher::run_replay(line.replay(), services_dir());
      case launcher::Command::kEvaluate:
        return launcher::run_evaluate(line.evaluate(), std::cout);
      case launcher::Command::kMesh:
        return launcher::run_mesh(line.mesh());
      case launcher::Command::kHelp:
        std::cout << line.usage();
        return 0;
    }
  } catch (const std::exception& e) {
    std::cerr << "pbnbv " << command << ": " << e.what() << std::endl;
    return 2;
  }
  return 2;
}
