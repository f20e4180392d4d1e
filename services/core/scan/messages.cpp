#include "core/scan/messages.hpp"

namespace pbnbv {

const char* to_string(MoveStatus s) {
  switch (s) {
    case MoveStatus::kReached: return "reached";
    case MoveStatus::kUnreachable: return "unreachable";
    case MoveStatus::kTimedOut: return "timed_out";
    case MoveStatus::kRejected: return "rejected";
    case MoveStatus::kPlanned: return "planned";
    case MoveStatus::kBusy: return "busy";
    case MoveStatus::kRigSilent: return "rig_silent";
  }
  return "unknown";
}

const char* to_string(PlanOutcome o) {
  switch (o) {
    case PlanOutcome::kView: return "view";
    case PlanOutcome::kStop: return "stop";
    case PlanOutcome::kFailed: return "failed";
  }
  return "unknown";
}

}  // namespace pbnbv
