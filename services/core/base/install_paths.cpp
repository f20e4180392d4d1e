#include "core/base/install_paths.hpp"

#include <cstdlib>
#include <filesystem>
#include <system_error>

namespace fs = std::filesystem;

namespace pbnbv {

namespace {
fs::path running_program() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe;
}
}  // namespace

std::string install_prefix() {
  const fs::path dir = running_program().parent_path();
  if (dir.filename() == "bin") return dir.parent_path().string();
  if (dir.filename() == "pbnbv" && dir.parent_path().filename() == "libexec") return dir.parent_path().parent_path().string();
  return "";
}

std::string installed_share_path(const std::string& name) {
  const std::string prefix = install_prefix();
  if (prefix.empty()) return "";
  std::error_code ec;
  const fs::path p = fs::path(prefix) / "share" / "pbnbv" / name;
  return fs::exists(p, ec) ? p.string() : "";
}

std::string services_dir() {
  const std::string prefix = install_prefix();
  std::error_code ec;
  if (!prefix.empty() && fs::is_directory(fs::path(prefix) / "libexec" / "pbnbv", ec)) {
    return (fs::path(prefix) / "libexec" / "pbnbv").string();
  }
  return running_program().parent_path().string();
}

std::string resource_dir(const char* env_var, const std::string& name, const std::string& built_in) {
  if (const char* env = std::getenv(env_var); env && *env) return env;
  const std::string installed = installed_share_path(name);
  return installed.empty() ? built_in : installed;
}

}  // namespace pbnbv
