#pragma once
// The settings of `pbnbv rig-check` (and of the launcher's preflight before a scan on a real rig).
#include "core/base/setting.hpp"

namespace pbnbv::rigcheck {

inline constexpr Setting<double> kDriverDeadline{
    "deadline", 5.0, 0.5, 600.0, "s", "how long to wait for each driver's status, frame or move before failing"};

}  // namespace pbnbv::rigcheck
