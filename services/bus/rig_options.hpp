#pragma once
// The rig a service works with, from its command line: --rig arm|free (models/rig_<rig>.xml) or
// --model PATH.
#include "core/base/args.hpp"
#include "core/rig/rig.hpp"

namespace pbnbv::bus {

inline RigModel rig_from_args(const Args& args) {
  const RigKind kind = parse_rig_kind(args.str("rig", "arm"));
  return load_rig(args.str("model", default_rig_path(kind)));
}

}  // namespace pbnbv::bus
