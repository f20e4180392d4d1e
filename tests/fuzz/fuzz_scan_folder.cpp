// libFuzzer target: a scan folder as `pbnbv scan --resume` reads it. The input is settings.json
// and scan.json, split at the first "\n\0\n" (fuzz_util.hpp; no scan.json without one), written
// into a folder with the twin's object.stl (@MODELS@ in settings.json: the project's models/).
// read_resumable checks the folder; when it accepts it, the processes are built from the
// settings (their paths must stay inside the folder and the programs must be the installed ones:
// nothing from the folder is run or written elsewhere), and the coordinator's sequencer resumes
// from scan.json (ScanSequencer::resume), which may refuse it with std::exception naming the file.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/scan/scan_sequencer.hpp"
#include "fuzz_util.hpp"
#include "launcher/scan_processes.hpp"

namespace fs = std::filesystem;

namespace {

// A tetrahedron, binary STL: the twin's object of the folder.
void write_object(const fs::path& path) {
  std::ofstream f(path, std::ios::binary);
  const char header[80] = "pbnbv fuzz tetrahedron";
  f.write(header, 80);
  const uint32_t n = 4;
  f.write(reinterpret_cast<const char*>(&n), 4);
  const float v[4][3] = {{0, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}, {0, 0, 0.1f}};
  const int t[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (const auto& tri : t) {
    const float normal[3] = {0, 0, 0};
    f.write(reinterpret_cast<const char*>(normal), 12);
    for (int k = 0; k < 3; ++k) f.write(reinterpret_cast<const char*>(v[tri[k]]), 12);
    const uint16_t attr = 0;
    f.write(reinterpret_cast<const char*>(&attr), 2);
  }
}

bool inside(const fs::path& p, const fs::path& folder) {
  const fs::path rel = fs::absolute(p).lexically_normal().lexically_relative(folder);
  return !rel.empty() && *rel.begin() != "..";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const fs::path folder = pbnbv::fuzz::scratch_dir() / "scan";
  static const bool made = [&] {
    fs::create_directories(folder);
    write_object(folder / "object.stl");
    return true;
  }();
  (void)made;
  const auto [settings, scan] = pbnbv::fuzz::split_two(pbnbv::fuzz::as_text(data, size));
  // The seeds name the project's rig files as @MODELS@/<file>, wherever the checkout is.
  std::string text(settings);
  static const std::string kModels = "@MODELS@";
  for (std::size_t at = text.find(kModels); at != std::string::npos; at = text.find(kModels, at + 1)) {
    text.replace(at, kModels.size(), PBNBV_MODELS_DIR);
  }
  pbnbv::fuzz::write_input(text, "scan/settings.json");
  if (scan.empty()) {
    fs::remove(folder / "scan.json");
  } else {
    pbnbv::fuzz::write_input(scan, "scan/scan.json");
  }
  pbnbv::launcher::Resumable r;
  try {
    r = pbnbv::launcher::read_resumable(folder);
  } catch (const std::exception&) {  // refused, naming the folder and the file
    return 0;
  }
  const fs::path bin = "/opt/pbnbv-fuzz/bin";
  for (const auto& child : pbnbv::launcher::scan_processes(r.settings, r.launch, folder, bin)) {
    const fs::path program = child.argv.at(0);
    if (program.parent_path() != bin && program.filename() != "lcm-logger") {
      std::fprintf(stderr, "a resumed scan would run %s\n", program.c_str());
      std::abort();
    }
    for (size_t k = 1; k + 1 < child.argv.size(); ++k) {
      if (child.argv[k] == "--out" && !inside(child.argv[k + 1], folder) && fs::path(child.argv[k + 1]) != folder) {
        std::fprintf(stderr, "a resumed %s would write to %s\n", child.name.c_str(), child.argv[k + 1].c_str());
        std::abort();
      }
    }
    if (!child.log_path.empty() && !inside(child.log_path, folder)) {
      std::fprintf(stderr, "a resumed %s would log to %s\n", child.name.c_str(), child.log_path.c_str());
      std::abort();
    }
  }
  try {
    pbnbv::ScanSequencer sequencer(r.settings, folder);
    sequencer.resume(0.0);
  } catch (const std::exception&) {  // refused, naming scan.json and the view
  }
  return 0;
}
