#pragma once
// Where a program finds its run-time files (rig models, fetched meshes, the message jar): in the
// source and build trees it was built from, or, once installed (`cmake --install build --prefix
// P`: programs in P/bin), in P/share/pbnbv beside them.
#include <string>

namespace pbnbv {

// P/share/pbnbv/<name> when the running program is P/bin/<program> and that file or folder
// exists; else "".
std::string installed_share_path(const std::string& name);

// A folder of run-time files: the environment variable `env_var` when set and not empty, else
// the installed share/pbnbv/<name>, else `built_in` (the tree's path compiled into the program).
std::string resource_dir(const char* env_var, const std::string& name, const std::string& built_in);

}  // namespace pbnbv
