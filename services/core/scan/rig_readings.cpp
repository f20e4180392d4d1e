#include "core/scan/rig_readings.hpp"

namespace pbnbv {

const char* to_string(RigFault f) {
  switch (f) {
    case RigFault::kNone: return "none";
    case RigFault::kCommandRejected: return "command_rejected";
    case RigFault::kDriver: return "driver";
    case RigFault::kOutOfLimits: return "out_of_limits";
    case RigFault::kContact: return "contact";
  }
  return "unknown";
}

}  // namespace pbnbv
