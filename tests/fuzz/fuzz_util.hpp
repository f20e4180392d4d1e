#pragma once
// What the file-reading fuzz targets share: the input written to a file of the process's own
// folder, so each reader is fuzzed through the path a user gives it.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>

namespace pbnbv::fuzz {

// The process's scratch folder (under $TMPDIR or /tmp), made on first use.
inline const std::filesystem::path& scratch_dir() {
  static const std::filesystem::path dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    std::filesystem::path d = std::filesystem::path(tmp && *tmp ? tmp : "/tmp") /
                              ("pbnbv-fuzz-" + std::to_string(static_cast<long>(getpid())));
    std::filesystem::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(scratch_dir(), ec);
    });
    return d;
  }();
  return dir;
}

// Writes `bytes` to scratch_dir()/name and returns the path.
inline std::string write_input(std::string_view bytes, const std::string& name) {
  const std::filesystem::path p = scratch_dir() / name;
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return p.string();
}

inline std::string_view as_text(const uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// Splits the input at the first "\n\x00\n" into two files' bytes (the second empty when there is
// none): a target that reads two files from one input.
inline std::pair<std::string_view, std::string_view> split_two(std::string_view in) {
  static constexpr std::string_view kSeparator("\n\0\n", 3);
  const std::size_t at = in.find(kSeparator);
  if (at == std::string_view::npos) return {in, {}};
  return {in.substr(0, at), in.substr(at + kSeparator.size())};
}

}  // namespace pbnbv::fuzz
