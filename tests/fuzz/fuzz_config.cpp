// libFuzzer target: a settings file (--config FILE, TOML `name = value` lines) of `pbnbv scan` and
// of `pbnbv bench`, through the whole command line's checks (CommandLine::parse: every value
// checked as if given on the command line, the settings validated). The first byte picks the
// command; the rest is the file. A file is either accepted or refused with exit code 2 and a
// message; nothing else.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "fuzz_util.hpp"
#include "launcher/command_line.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::string path = pbnbv::fuzz::write_input(pbnbv::fuzz::as_text(data + 1, size - 1), "settings.toml");
  const std::string out = (pbnbv::fuzz::scratch_dir() / "out").string();
  const char* const argv[] = {"pbnbv", data[0] % 2 == 0 ? "scan" : "bench", "--config", path.c_str(), "--out", out.c_str()};
  pbnbv::launcher::CommandLine line;
  std::ostringstream o, e;
  const std::optional<int> code = line.parse(6, argv, o, e);
  if (code && *code != 2) {
    std::fprintf(stderr, "a settings file made `pbnbv` exit %d\n", *code);
    std::abort();
  }
  if (code && e.str().empty()) {
    std::fprintf(stderr, "a settings file was refused without a message\n");
    std::abort();
  }
  return 0;
}
