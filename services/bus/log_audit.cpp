#include "bus/log_audit.hpp"

#include <lcm/lcm-cpp.hpp>

#include <stdexcept>

#include "bus/channels.hpp"
#include "bus/rig_log.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/point_cloud_t.hpp"
#include "pbnbv/registered_cloud_t.hpp"
#include "pbnbv/voxel_set_t.hpp"

namespace pbnbv::bus {

LogContents read_scan_log(const std::string& path, const std::string& scan_id) {
  lcm::LogFile file(path, "r");
  if (!file.good()) throw std::runtime_error("cannot read the LCM log " + path);
  LogContents c;
  while (const lcm::LogEvent* e = file.readNextEvent()) {
    ++c.events;
    if (e->channel == channels::kDepthFrame || e->channel == channels::kDepthFrameResent) {
      depth_frame_t m;
      if (!decode_logged(*e, &m)) ++c.undecodable;
      else if (m.scan_id == scan_id || m.scan_id.empty()) c.depth_frames.insert(m.seq);
    } else if (e->channel == channels::kCloud) {
      point_cloud_t m;
      if (!decode_logged(*e, &m)) ++c.undecodable;
      else if (m.scan_id == scan_id) c.clouds.insert(m.iteration);
    } else if (e->channel == channels::kRegisteredCloud) {
      registered_cloud_t m;
      if (!decode_logged(*e, &m)) ++c.undecodable;
      else if (m.scan_id == scan_id) c.registered_clouds.insert(m.iteration);
    } else if (e->channel == channels::kVoxelMap) {
      voxel_set_t m;
      if (!decode_logged(*e, &m)) ++c.undecodable;
      else if (m.scan_id == scan_id) c.voxel_maps.insert(m.iteration);
    }
  }
  return c;
}

LogContents read_scan_logs(const std::vector<std::string>& paths, const std::string& scan_id) {
  LogContents all;
  for (const std::string& p : paths) {
    const LogContents c = read_scan_log(p, scan_id);
    all.events += c.events;
    all.undecodable += c.undecodable;
    all.depth_frames.insert(c.depth_frames.begin(), c.depth_frames.end());
    all.clouds.insert(c.clouds.begin(), c.clouds.end());
    all.registered_clouds.insert(c.registered_clouds.begin(), c.registered_clouds.end());
    all.voxel_maps.insert(c.voxel_maps.begin(), c.voxel_maps.end());
  }
  return all;
}

std::vector<std::string> missing_from_log(const LogContents& log, const std::vector<ViewMessages>& views) {
  std::vector<std::string> missing;
  for (const ViewMessages& v : views) {
    const int i = v.view;
    const std::string name = "view " + std::to_string(i + 1) + ": ";
    if (v.captured) {
      if (v.depth_frame_seq >= 0 && !log.depth_frames.count(v.depth_frame_seq)) {
        missing.push_back(name + "DEPTH_FRAME " + std::to_string(v.depth_frame_seq));
      }
      if (!log.clouds.count(i)) missing.push_back(name + "CLOUD");
    }
    if (v.registered && !log.registered_clouds.count(i)) missing.push_back(name + "REGISTERED_CLOUD");
    if (v.mapped && !log.voxel_maps.count(i)) missing.push_back(name + "VOXEL_MAP");
  }
  return missing;
}

}  // namespace pbnbv::bus
