#pragma once
// The rig a service works with, from its command line: --rig arm|free (models/rig_<rig>.xml) or
// --model PATH.
#include <string>

#include "cli/options.hpp"
#include "core/rig/rig.hpp"

namespace pbnbv::bus {

struct RigOptions {
  RigKind kind = kRig.value;
  std::string model_path;  // empty: the kind's model file
};

// Declares --rig and --model on `app`, bound to *o.
inline void add_rig_options(CLI::App& app, RigOptions* o) {
  cli::add(app, kRig, &o->kind);
  cli::add_text(app, "model", &o->model_path, "rig MJCF file instead of the --rig profile's (models/rig_<rig>.xml)",
                "PATH");
}

// The rig the options name.
inline RigModel load_rig(const RigOptions& o) {
  return pbnbv::load_rig(o.model_path.empty() ? default_rig_path(o.kind) : o.model_path);
}

}  // namespace pbnbv::bus
