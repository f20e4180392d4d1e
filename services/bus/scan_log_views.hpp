#pragma once
// The messages a scan's record says each view sent (core/scan's RecordedScan), for the audit of
// its log (log_audit.hpp). Header-only: for the programs that link both the bus and core/scan.
#include <vector>

#include "bus/log_audit.hpp"
#include "core/scan/scan_record.hpp"

namespace pbnbv::bus {

inline std::vector<ViewMessages> view_messages(const RecordedScan& scan) {
  std::vector<ViewMessages> out;
  for (const ViewRecord& v : scan.views) {
    ViewMessages m;
    m.view = v.view;
    m.captured = v.capture.has_value();
    if (v.capture) m.depth_frame_seq = v.capture->depth_frame_seq;
    m.registered = v.registration.has_value();
    m.mapped = v.map.has_value();
    out.push_back(m);
  }
  return out;
}

}  // namespace pbnbv::bus
