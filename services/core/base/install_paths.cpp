#include "core/base/install_paths.hpp"

#include <cstdlib>
#include <filesystem>
#include <system_error>

namespace fs = std::filesystem;

namespace pbnbv {

std::string installed_share_path(const std::string& name) {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec || exe.parent_path().filename() != "bin") return "";
  const fs::path p = exe.parent_path().parent_path() / "share" / "pbnbv" / name;
  return fs::exists(p, ec) ? p.string() : "";
}

std::string resource_dir(const char* env_var, const std::string& name, const std::string& built_in) {
  if (const char* env = std::getenv(env_var); env && *env) return env;
  const std::string installed = installed_share_path(name);
  return installed.empty() ? built_in : installed;
}

}  // namespace pbnbv
