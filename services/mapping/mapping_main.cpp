// pbnbv-mapping: the mapping service.
//   in:  --map-pose rig (the default): CLOUD (which frame, and the rig's camera pose), with
//        REGISTERED_CLOUD for the correction the registration found (below);
//        --map-pose registered: REGISTERED_CLOUD (which frame, and its registered camera pose);
//        each taken only when it answers a CAPTURE_REQUEST heard (bus/asked_captures.hpp);
//        DEPTH_FRAME (the rays; DEPTH_FRAME_RESENT: the same frame sent again when it was lost),
//        CAPTURE_REQUEST
//   out: VOXEL_MAP, HEARTBEAT; per view DIR/maps/view_NNN.ot (OctoMap, viewable in octovis:
//        Occupied and Empty only) and DIR/maps/view_NNN.states.ply (every cell with its state)
// Keeps the five-state voxel map of each scan (core VoxelMap: None, Empty, Occupied, Unknown,
// Frontier; the voxels of the bounding box B projected into each depth frame) and publishes, per
// view, the Occupied and Frontier voxel centres, the count of every state, B, the resolution and
// the update time.
// The pose a view is integrated at (--map-pose):
// - rig: the camera's kinematic pose (CLOUD's object_T_camera) times the camera-frame correction the
//   registration found for the newest view it answered (kinematic^-1 * registered, from REGISTERED_CLOUD;
//   after a restart read from DIR/state/registration.answer). The map answers before the registration
//   has refined the view, so the next view is planned while it does. A mount that is off moves every
//   view alike in the camera's frame, so the last correction carries to the next view; what is left
//   is well under the 30 mm voxel. A cloud with no point is not integrated.
// - registered: the registration's pose; a view the registration rejected is not integrated.
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
#include "core/mapping/map_options.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/point_cloud_t.hpp"
#include "pbnbv/registered_cloud_t.hpp"
#include "pbnbv/voxel_set_t.hpp"

using namespace pbnbv;
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kFramesKept = 4;     // depth frames waiting for their registered cloud
constexpr double kFrameWaitS = 3.0;        // a view's depth frame this late is said in the log
constexpr std::size_t kAnswersKept = 16;   // maps kept to answer a repeated view again

// A view to integrate, from CLOUD (--map-pose rig) or REGISTERED_CLOUD (registered).
struct ViewToMap {
  std::string scan_id;
  int32_t iteration = 0;
  int64_t request_id = 0;
  int64_t depth_frame_seq = -1;
  pose_t object_T_camera;  // the pose it is integrated at
  std::string not_integrated;  // why it is not (empty: it is)
};

class MappingService {
 public:
  MappingService(bus::Bus& bus, const VoxelMapParams& params, const Eigen::AlignedBox3d& working_volume, fs::path out,
                 bool depth_filter, MapPose map_pose)
      : bus_(bus), params_(params), working_volume_(working_volume), out_(std::move(out)), depth_filter_(depth_filter),
        map_pose_(map_pose), frames_(bus, kFramesKept) {
    restore();
    bus_.subscribe<capture_request_t>(channels::kCaptureRequest,
                                      [this](const capture_request_t& c) { asked_.heard(c.scan_id, c.request_id); });
    bus_.subscribe<registered_cloud_t>(channels::kRegisteredCloud, [this](const registered_cloud_t& r) { on_registered(r); });
    if (map_pose_ == MapPose::kRig) {
      bus_.subscribe<point_cloud_t>(channels::kCloud, [this](const point_cloud_t& c) { on_cloud(c); });
    }
  }

  // A view whose depth frame has not come is not answered: the coordinator repeats the view's
  // capture request while its VOXEL_MAP is late, the camera service sends the frame again with
  // its answer (DEPTH_FRAME_RESENT), and the view is integrated then; when it never comes, the
  // coordinator's wait for VOXEL_MAP ends the view as failed, naming it. A view is never left
  // out of the map with an answer that says it was mapped.
  void tick() {
    if (!pending_) return;
    // A view that is not integrated needs no frame; nor does one that names no depth frame (a
    // negative sequence number: there is none to wait for).
    if (!pending_->not_integrated.empty() || pending_->depth_frame_seq < 0 || frames_.find(pending_->depth_frame_seq)) {
      const ViewToMap r = std::move(*pending_);
      pending_.reset();
      integrate(r);
    } else if (!warned_ && bus::now_s() > pending_deadline_) {
      warned_ = true;
      log_warn("view " + std::to_string(pending_->iteration + 1) + ": DEPTH_FRAME " + std::to_string(pending_->depth_frame_seq) +
               " has not come in " + fixed(kFrameWaitS, 0) + " s; waiting for it to be sent again");
    }
  }

 private:
  void on_registered(const registered_cloud_t& r) {
    // A capture that failed is no view to map: the coordinator goes on to the next view without
    // waiting for a map, and a failed cloud must not become the answer of its view (forged with a
    // guessed request id, it would be cached as the view's map and the real view answered from it).
    if (r.cloud.status != point_cloud_t::kOk) return;
    // Nor is a cloud that answers no capture request heard (forged with a guessed request id: it
    // would be integrated and answered as its view's map).
    asked_.require("REGISTERED_CLOUD", r.scan_id, r.request_id);
    if (map_pose_ == MapPose::kRig) return take_correction(r);
    ViewToMap v;
    v.scan_id = r.scan_id;
    v.iteration = r.iteration;
    v.request_id = r.request_id;
    v.depth_frame_seq = r.cloud.depth_frame_seq;
    v.object_T_camera = r.cloud.object_T_camera;
    if (!r.accepted) v.not_integrated = "registration rejected the view (" + r.reason + ")";
    on_view(v);
  }

  // --map-pose rig: the view at the rig's pose times the registration's last correction.
  void on_cloud(const point_cloud_t& c) {
    if (c.status != point_cloud_t::kOk) return;  // as above
    asked_.require("CLOUD", c.scan_id, c.request_id);
    ViewToMap v;
    v.scan_id = c.scan_id;
    v.iteration = c.iteration;
    v.request_id = c.request_id;
    v.depth_frame_seq = c.depth_frame_seq;
    const Pose kinematic = bus::from_msg(c.object_T_camera, "CLOUD object_T_camera");
    const Pose correction = correction_ && correction_->first == c.scan_id ? correction_->second : Pose::Identity();
    v.object_T_camera = bus::to_msg(Pose(kinematic * correction));
    if (c.num_points == 0) v.not_integrated = "the view has no point";
    on_view(v);
  }

  // The camera-frame correction of the newest view the registration answered (kinematic^-1 *
  // registered): the next view's rig pose is corrected by it.
  void take_correction(const registered_cloud_t& r) {
    if (!r.accepted) return;
    const Pose kinematic = bus::from_msg(r.kinematic_object_T_camera, "REGISTERED_CLOUD kinematic_object_T_camera");
    const Pose registered = bus::from_msg(r.cloud.object_T_camera, "REGISTERED_CLOUD cloud.object_T_camera");
    if (correction_ && correction_->first == r.scan_id && r.iteration < correction_iteration_) return;  // an older view's
    correction_ = {r.scan_id, Pose(kinematic.inverse() * registered)};
    correction_iteration_ = r.iteration;
  }

  void on_view(const ViewToMap& r) {
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
      const ViewToMap older = std::move(*pending_);
      pending_.reset();
      integrate(older);
    }
    pending_ = r;
    pending_deadline_ = bus::now_s() + kFrameWaitS;
    warned_ = false;
    tick();
  }

  void integrate(const ViewToMap& r) {
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
    const depth_frame_t* frame = frames_.find(r.depth_frame_seq);
    if (!r.not_integrated.empty()) {
      out.message = "not integrated: " + r.not_integrated;
    } else if (r.depth_frame_seq < 0) {
      out.message = "not integrated: the view names no depth frame (depth_frame_seq " + std::to_string(r.depth_frame_seq) + ")";
    } else if (!frame) {
      out.message = "not integrated: DEPTH_FRAME " + std::to_string(r.depth_frame_seq) + " never arrived";
    } else {
      try {
        bus::DecodedFrame decoded = bus::decode_frame(*frame);
        // What the camera service removed from this frame before making its cloud, removed here too.
        if (depth_filter_) filter_depth(decoded.depth_m, decoded.intrinsics);
        DepthView view;
        view.depth_m = &decoded.depth_m;
        view.intrinsics = decoded.intrinsics;
        view.range = decoded.range;
        view.object_T_camera = bus::from_msg(r.object_T_camera, "the view's object_T_camera");
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
    // The registration's last answer: the correction the next view's rig pose takes.
    if (map_pose_ == MapPose::kRig) {
      try {
        const auto reg = bus::load_message<registered_cloud_t>(state_path("registration.answer").string());
        if (reg && reg->scan_id == scan_id_ && reg->cloud.status == point_cloud_t::kOk) take_correction(*reg);
      } catch (const std::exception& e) {
        log_warn("no correction from " + state_path("registration.answer").string() + ": " + e.what());
      }
    }
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
  MapPose map_pose_ = MapPose::kRig;
  std::string scan_id_;
  std::optional<VoxelMap> map_;
  bus::RecentFrames frames_;  // the frames waiting for their registered cloud
  std::optional<std::pair<std::string, Pose>> correction_;  // (scan, kinematic^-1 * registered)
  int32_t correction_iteration_ = -1;
  std::optional<ViewToMap> pending_;
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
  MapPose map_pose = kMapPose.value;
  cli::add(app, kMapPose, &map_pose);
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
    auto service = std::make_shared<MappingService>(bus, p, volume, fs::path(out), !no_depth_filter, map_pose);
    log_info("ready: resolution " + std::to_string(p.resolution_m) + " m");
    return [service] { service->tick(); };
  });
}
