// pbnbv-mapping: the mapping service.
//   in:  REGISTERED_CLOUD (which frame, and its registered camera pose; taken only when it answers
//        a CAPTURE_REQUEST heard: bus/asked_captures.hpp), DEPTH_FRAME (the rays;
//        DEPTH_FRAME_RESENT: the same frame sent again when it was lost), CAPTURE_REQUEST
//   out: VOXEL_MAP, HEARTBEAT; per view DIR/maps/view_NNN.ot (OctoMap, viewable in octovis:
//        Occupied and Empty only) and DIR/maps/view_NNN.states.ply (every cell with its state)
// Keeps the five-state voxel map of each scan (core VoxelMap: None, Empty, Occupied, Unknown,
// Frontier; the voxels of the bounding box B projected into each depth frame) and publishes, per
// view, the Occupied and Frontier voxel centres, the count of every state, B, the resolution and
// the update time.
// A view the registration rejected is not integrated (its pose is implausible).
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <tuple>

#include "bus/asked_captures.hpp"
#include "bus/bus.hpp"
#include "bus/recent_frames.hpp"
#include "bus/reply_cache.hpp"
#include "bus/state_file.hpp"
#include "bus/service.hpp"
#include "bus/convert.hpp"
#include "core/base/format.hpp"
#include "core/base/log.hpp"
#include "core/mapping/voxel_map.hpp"
#include "pbnbv/capture_request_t.hpp"
#include "core/perception/depth_filter.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/registered_cloud_t.hpp"
#include "pbnbv/voxel_set_t.hpp"

using namespace pbnbv;
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kFramesKept = 4;     // depth frames waiting for their registered cloud
constexpr double kFrameWaitS = 3.0;        // a view's depth frame this late is said in the log
constexpr std::size_t kAnswersKept = 16;   // maps kept to answer a repeated view again

class MappingService {
 public:
  MappingService(bus::Bus& bus, const VoxelMapParams& params, const Eigen::AlignedBox3d& working_volume, fs::path out,
                 bool depth_filter)
      : bus_(bus), params_(params), working_volume_(working_volume), out_(std::move(out)), depth_filter_(depth_filter),
        frames_(bus, kFramesKept) {
    restore();
    bus_.subscribe<capture_request_t>(channels::kCaptureRequest,
                                      [this](const capture_request_t& c) { asked_.heard(c.scan_id, c.request_id); });
    bus_.subscribe<registered_cloud_t>(channels::kRegisteredCloud, [this](const registered_cloud_t& r) { on_view(r); });
  }

  // A view whose depth frame has not come is not answered: the coordinator repeats the view's
  // capture request while its VOXEL_MAP is late, the camera service sends the frame again with
  // its answer (DEPTH_FRAME_RESENT), and the view is integrated then; when it never comes, the
  // coordinator's wait for VOXEL_MAP ends the view as failed, naming it. A view is never left
  // out of the map with an answer that says it was mapped.
  void tick() {
    if (!pending_) return;
    // A view registration did not merge is not integrated: it needs no frame; nor is one that
    // names no depth frame (a negative sequence number: there is none to wait for).
    if (!pending_->accepted || pending_->cloud.depth_frame_seq < 0 || frames_.find(pending_->cloud.depth_frame_seq)) {
      const registered_cloud_t r = std::move(*pending_);
      pending_.reset();
      integrate(r);
    } else if (!warned_ && bus::now_s() > pending_deadline_) {
      warned_ = true;
      log_warn("view " + std::to_string(pending_->iteration + 1) + ": DEPTH_FRAME " + std::to_string(pending_->cloud.depth_frame_seq) +
               " has not come in " + fixed(kFrameWaitS, 0) + " s; waiting for it to be sent again");
    }
  }

 private:
  void on_view(const registered_cloud_t& r) {
    // A capture that failed is no view to map: the coordinator goes on to the next view without
    // waiting for a map, and a failed cloud must not become the answer of its view (forged with a
    // guessed request id, it would be cached as the view's map and the real view answered from it).
    if (r.cloud.status != point_cloud_t::kOk) return;
    // Nor is a cloud that answers no capture request heard (forged with a guessed request id: it
    // would be integrated and answered as its view's map).
    asked_.require("REGISTERED_CLOUD", r.scan_id, r.request_id);
    bus_.set_scan(r.scan_id, r.iteration);
    if (const voxel_set_t* answer = answers_.find({r.scan_id, r.iteration, r.request_id})) {
      bus_.publish(channels::kVoxelMap, *answer);  // a repeat: answer again
      return;
    }
    if (pending_ && pending_->scan_id == r.scan_id && pending_->iteration == r.iteration &&
        pending_->request_id == r.request_id) {
      return;  // a repeat: still waiting
    }
    if (pending_ && pending_->scan_id == r.scan_id && r.iteration < pending_->iteration) {
      // Another capture of an earlier view, late: nobody waits for it any more (the coordinator
      // asks for the current view only), and settling the later view now would leave it out.
      log_info("view " + std::to_string(r.iteration + 1) + " (request " + std::to_string(r.request_id) + ") came while view " +
               std::to_string(pending_->iteration + 1) + " waits for its depth frame: not integrated");
      return;
    }
    if (pending_) {  // a newer view arrived: settle the older one now
      const registered_cloud_t older = std::move(*pending_);
      pending_.reset();
      integrate(older);
    }
    pending_ = r;
    pending_deadline_ = bus::now_s() + kFrameWaitS;
    warned_ = false;
    tick();
  }

  void integrate(const registered_cloud_t& r) {
    if (r.scan_id != scan_id_) {  // a new scan: a new map
      scan_id_ = r.scan_id;
      map_.emplace(params_);
      answers_.clear();
    }
    voxel_set_t out;
    out.scan_id = r.scan_id;
    out.iteration = r.iteration;
    out.request_id = r.request_id;
    out.updated = false;
    out.update_s = 0;
    const depth_frame_t* frame = frames_.find(r.cloud.depth_frame_seq);
    if (!r.accepted) {
      out.message = "not integrated: registration rejected the view (" + r.reason + ")";
    } else if (r.cloud.depth_frame_seq < 0) {
      out.message = "not integrated: the view names no depth frame (depth_frame_seq " +
                    std::to_string(r.cloud.depth_frame_seq) + ")";
    } else if (!frame) {
      out.message = "not integrated: DEPTH_FRAME " + std::to_string(r.cloud.depth_frame_seq) + " never arrived";
    } else {
      try {
        bus::DecodedFrame decoded = bus::decode_frame(*frame);
        // What the camera service removed from this frame before making its cloud, removed here too.
        if (depth_filter_) filter_depth(decoded.depth_m, decoded.intrinsics);
        DepthView view;
        view.depth_m = &decoded.depth_m;
        view.intrinsics = decoded.intrinsics;
        view.range = decoded.range;
        view.object_T_camera = bus::from_msg(r.cloud.object_T_camera, "REGISTERED_CLOUD cloud.object_T_camera");
        view.working_volume = working_volume_;
        const MapUpdateResult u = map_->integrate(view);
        out.updated = u.updated;
        out.message = u.message;
        out.update_s = u.time_s;
      } catch (const std::exception& e) {
        out.message = std::string("not integrated: ") + e.what();
      }
    }
    fill(out);
    if (!out_.empty() && !map_->empty()) {
      fs::create_directories(out_ / "maps");
      map_->write_octomap((out_ / "maps" / view_file(r.iteration, "ot")).string());
      map_->write_states_ply((out_ / "maps" / view_file(r.iteration, "states.ply")).string());
    }
    out.utime = bus::now_utime();
    // The state first, then the answer: after a crash between the two, the restarted service
    // answers the coordinator's repeated request from the saved answer. The other order could
    // lose the view: the answer out, the state not saved, the restarted map would lack a view
    // the coordinator counts as mapped. It also keeps the write off the cores while the
    // ellipsoid fitter works on the answer.
    save(out);
    bus_.publish(channels::kVoxelMap, out);
    answers_.put({r.scan_id, r.iteration, r.request_id}, out);
    std::ostringstream os;
    os << "view " << r.iteration << ": " << out.message << " (" << out.update_s * 1e3 << " ms; occupied "
       << out.num_occupied << ", frontier " << out.num_frontier << ", unknown " << out.num_unknown << ")";
    log_info(os.str());
  }

  // The state a restarted service continues from: DIR/state/mapping.map (the map) and
  // DIR/state/mapping.answer (the last VOXEL_MAP), written after every view.
  fs::path state_path(const char* name) const { return out_ / "state" / name; }

  void save(const voxel_set_t& answer) {
    if (out_.empty() || bus_.scope().empty()) return;  // only a service started for one scan
    fs::create_directories(out_ / "state");
    write_text_atomic(map_->serialise(), state_path("mapping.map").string());
    bus::save_message(answer, state_path("mapping.answer").string());
  }

  // Continues the map of the scan this service serves when the folder holds it (a restart).
  void restore() {
    if (out_.empty() || bus_.scope().empty()) return;
    const std::optional<voxel_set_t> last = bus::load_message<voxel_set_t>(state_path("mapping.answer").string());
    if (!last || last->scan_id != bus_.scope()) return;
    map_ = VoxelMap::restore(read_text(state_path("mapping.map").string()), params_, state_path("mapping.map").string());
    scan_id_ = last->scan_id;
    answers_.put({last->scan_id, last->iteration, last->request_id}, *last);
    log_info("continuing the map of scan " + scan_id_ + " after view " + std::to_string(last->iteration + 1) + " from " +
             state_path("mapping.map").string());
  }

  void fill(voxel_set_t& out) const {
    out.resolution_m = params_.resolution_m;
    const Eigen::AlignedBox3d b = map_->empty() ? Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()) : map_->bounds();
    for (int k = 0; k < 3; ++k) {
      out.bbox_min_m[k] = b.min()[k];
      out.bbox_max_m[k] = b.max()[k];
    }
    const VoxelCounts c = map_->counts();
    out.num_none = static_cast<int32_t>(c.none);
    out.num_empty = static_cast<int32_t>(c.empty);
    out.num_unknown = static_cast<int32_t>(c.unknown);
    auto centres = [&](VoxelState s, std::vector<std::vector<float>>& dst) {
      for (const auto& p : map_->centres(s)) dst.push_back({static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
      return static_cast<int32_t>(dst.size());
    };
    out.num_occupied = centres(VoxelState::kOccupied, out.occupied_centres_m);
    out.num_frontier = centres(VoxelState::kFrontier, out.frontier_centres_m);
    const VoxelGrid g = map_->grid();
    for (int k = 0; k < 3; ++k) out.dims[k] = g.dims[k];
    out.cells.resize(g.cells.size());
    for (std::size_t i = 0; i < g.cells.size(); ++i) out.cells[i] = static_cast<int8_t>(g.cells[i]);
    out.num_cells = static_cast<int32_t>(out.cells.size());
  }

  bus::Bus& bus_;
  VoxelMapParams params_;
  Eigen::AlignedBox3d working_volume_;
  fs::path out_;
  bool depth_filter_ = true;  // the camera service's filter, applied to the same frames
  std::string scan_id_;
  std::optional<VoxelMap> map_;
  bus::RecentFrames frames_;  // the frames waiting for their registered cloud
  std::optional<registered_cloud_t> pending_;
  double pending_deadline_ = 0;
  bool warned_ = false;  // the pending view's late frame was said in the log
  bus::ReplyCache<std::tuple<std::string, int32_t, int64_t>, voxel_set_t> answers_{kAnswersKept};
  bus::AskedCaptures asked_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbnbv-mapping: the five-state voxel map, updated with every registered cloud", "pbnbv-mapping"};
  cli::init(app);
  VoxelMapParams p;
  std::string out;
  std::optional<Eigen::Vector3d> volume_min, volume_max;
  cli::add(app, kMapResolution, &p.resolution_m);
  cli::add(app, kFrontierMargin, &p.gamma_m);
  cli::add(app, kFrontierEmpty, &p.frontier_empty);
  cli::add_text(app, "out", &out, "write DIR/maps/view_NNN.ot (OctoMap) and view_NNN.states.ply per view; empty: none", "DIR");
  cli::add_point(app, "volume-min", &volume_min, "working volume's lower corner, object frame, m [unlimited]");
  cli::add_point(app, "volume-max", &volume_max, "working volume's upper corner, object frame, m [unlimited]");
  bool no_depth_filter = false;
  cli::add_flag(app, "no-depth-filter", &no_depth_filter,
                "integrate the frames as they come (the camera service's --no-depth-filter: the same frames)");
  return bus::run_service("mapping", app, argc, argv, 10, [&](bus::Bus& bus) -> std::function<void()> {
    Eigen::AlignedBox3d volume;  // empty: unlimited
    if (volume_min || volume_max) {
      volume = Eigen::AlignedBox3d(volume_min.value_or(Eigen::Vector3d::Constant(-1e3)),
                                   volume_max.value_or(Eigen::Vector3d::Constant(1e3)));
      if (volume.isEmpty()) throw std::invalid_argument("--volume-min must be below --volume-max on every axis");
    }
    auto service = std::make_shared<MappingService>(bus, p, volume, fs::path(out), !no_depth_filter);
    log_info("ready: resolution " + std::to_string(p.resolution_m) + " m");
    return [service] { service->tick(); };
  });
}
