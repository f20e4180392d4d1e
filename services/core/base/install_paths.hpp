#pragma once
// Where a program finds its run-time files (rig models, fetched meshes, the message jar): in the
// source and build trees it was built from, or, once installed (`cmake --install build --prefix
// P`: pbnbv in P/bin, its services in P/libexec/pbnbv), in P/share/pbnbv.
#include <string>

namespace pbnbv {

// P when the running program is P/bin/<program> or P/libexec/pbnbv/<program>; else "" (a build
// tree).
std::string install_prefix();

// P/share/pbnbv/<name> when the running program is installed under P and that file or folder
// exists; else "".
std::string installed_share_path(const std::string& name);

// Where pbnbv's services (pbnbv-twin, pbnbv-camera, ...) are: P/libexec/pbnbv once installed
// there, else the running program's own folder (the build tree's bin/).
std::string services_dir();

// A folder of run-time files: the environment variable `env_var` when set and not empty, else
// the installed share/pbnbv/<name>, else `built_in` (the tree's path compiled into the program).
std::string resource_dir(const char* env_var, const std::string& name, const std::string& built_in);

}  // namespace pbnbv
