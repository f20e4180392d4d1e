// pbnbv-registration: the registration service.
//   in:  CLOUD (a view placed by the rig's kinematic pose, with its normals), CAPTURE_REQUEST (a
//        CLOUD is taken only when it answers a capture request heard: bus/asked_captures.hpp),
//        DEPTH_FRAME and DEPTH_FRAME_RESENT (each view's depth image, for DIR/depth/),
//        MESH_REQUEST (the scan's end), MOVE_REQUEST (only when it was sent: the rig set moving
//        starts the work that needs no new frame)
//   out: REGISTERED_CLOUD, MESH_RESULT, HEARTBEAT; with --out DIR: DIR/frames/view_NNN.ply (every
//        view), DIR/cloud.ply (the model), DIR/depth/view_NNN.png and .json, DIR/mesh.ply and
//        mesh.obj (the surface of the merged views, core/surface/scan_mesh.hpp)
// Refines each view's pose against the accumulated model of its scan with point-to-plane ICP
// (core register_frame), starting from the kinematic pose and weighing ICP's correction against
// the kinematic pose's uncertainty (--pose-sigma-mm, --pose-sigma-deg); a view whose alignment
// cannot be trusted is merged at its kinematic pose and flagged, with the reason. The camera
// mount's error, the same in every view, is fitted to all views' clouds at once, each view's own
// small error alongside (core mount_from_views, DIR/hand_eye.json); once it is sure, views are
// registered from where it puts them, every view is placed again where it puts it, and at the
// scan's end the model is moved into the object frame. What needs no new frame (ICP's downsampled
// model with its normals, the k-d tree for the new surface) is done once a view is answered, on a
// worker while the rig moves to the next view.
// With --map-pose rig (the default) the next view is planned from the frame at the rig's pose while
// this service aligns it: the alignment and what follows it run at a lower priority
// (core/base/parallel.hpp lower_thread_priority), so that on a busy machine the plan has the cores
// first and the alignment takes what is left, most of it while the rig moves.
// It owns the model and what is made of it (core/surface/scan_model.hpp): each view's frame,
// the merged cloud and what each view added to it (new surface), said in the answer. A
// restarted service continues the model of its scan from DIR/cloud.ply; answers are idempotent
// by (scan_id, request_id). The mesh is made on a worker thread, so the service's heartbeat goes
// on while it fuses (seconds).
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <future>
#include <mutex>
#include <iostream>
#include <optional>
#include <sstream>
#include <tuple>

#include <filesystem>

#include "bus/asked_captures.hpp"
#include "bus/bus.hpp"
#include "bus/colour_codec.hpp"
#include "bus/recent_frames.hpp"
#include "bus/state_file.hpp"
#include "bus/reply_cache.hpp"
#include "bus/service.hpp"
#include "bus/convert_scan.hpp"
#include "core/perception/perception_options.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/base/log.hpp"
#include "core/perception/neighbours.hpp"
#include "core/perception/mount_estimate.hpp"
#include "core/perception/registration.hpp"
#include "core/io/json.hpp"
#include "core/base/parallel.hpp"
#include "core/base/units.hpp"
#include "core/mapping/map_options.hpp"
#include "core/scan/scan_options.hpp"
#include "core/surface/scan_model.hpp"
#include "core/surface/surface_options.hpp"
#include "pbnbv/capture_request_t.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/mesh_request_t.hpp"
#include "pbnbv/move_request_t.hpp"
#include "pbnbv/mesh_result_t.hpp"
#include "report/depth_png.hpp"
#include "pbnbv/point_cloud_t.hpp"
#include "pbnbv/registered_cloud_t.hpp"

using namespace pbnbv;

namespace {

constexpr std::size_t kAnswersKept = 4;
constexpr std::size_t kFramesKept = 4;
constexpr double kMountMinOverlap = 0.5;  // alignments that inform the mount's estimate
constexpr double kStartAfterS = 1.0;    // the work after an answer waits this long for the move at most
constexpr int kBackgroundNice = 10;     // the alignment's priority when the plan does not wait for it (nice)
constexpr int kMeshesPerScan = 3;       // different meshes made for one scan at most  // depth frames of the last views (a view's comes before its cloud)

class RegistrationService {
 public:
  RegistrationService(bus::Bus& bus, const RegistrationParams& params, double model_voxel_m, double new_surface_radius_m,
                      bool off, std::filesystem::path out, LengthUnit mesh_units, MapPose map_pose)
      : bus_(bus), params_(params), off_(off), background_(map_pose == MapPose::kRig), out_(std::move(out)), mesh_units_(mesh_units),
        model_(bus_.scope().empty() ? std::filesystem::path() : out_, model_voxel_m, new_surface_radius_m),
        frames_(bus, kFramesKept) {
    restore();
    bus_.subscribe<capture_request_t>(channels::kCaptureRequest,
                                      [this](const capture_request_t& c) { asked_.heard(c.scan_id, c.request_id); });
    bus_.subscribe<point_cloud_t>(channels::kCloud, [this](const point_cloud_t& c) { on_cloud(c); });
    bus_.subscribe<mesh_request_t>(channels::kMeshRequest, [this](const mesh_request_t& m) { on_mesh_request(m); });
    // The rig set moving: the work after the last answer starts (after_answer).
    bus_.subscribe<move_request_t>(channels::kMoveRequest, [this](const move_request_t& m) {
      if (m.scan_id == scan_id_) release_worker();
    });
  }

  // Answers the mesh request whose mesh the worker has finished.
  void tick() {
    if (!meshing_.valid() || meshing_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    const mesh_result_t out = answer_mesh(bus::to_msg(meshing_.get()));
    log_info(out.status == mesh_result_t::kOk ? "mesh: " + std::to_string(out.triangles) + " triangles (" +
                                                    std::to_string(out.seconds) + " s)"
                                              : "no mesh: " + out.message);
    if (out.status == mesh_result_t::kOk) last_mesh_ = std::make_pair(making_, out);
  }

 private:
  // A mesh costs seconds of CPU and rewrites DIR/mesh.*, so a request is taken only for the model
  // this service holds, a request for the mesh already made is answered with it (whatever its
  // request id), and at most kMeshesPerScan different meshes are made for one scan: a flood of
  // MESH_REQUESTs with new ids or view sets costs an answer each, not a mesh each.
  void on_mesh_request(const mesh_request_t& m) {
    if (const mesh_result_t* answer = meshes_.find({m.scan_id, m.request_id})) {
      bus_.publish(channels::kMeshResult, *answer);  // a repeat: answer again
      return;
    }
    const MeshRequest r = bus::from_msg(m, kViews.max);  // a malformed request throws: rejected by the bus
    const std::string what = "MESH_REQUEST " + std::to_string(r.request_id) + " of scan '" + r.scan_id + "'";
    if (r.scan_id != scan_id_) {
      throw std::invalid_argument(what + ": " + (scan_id_.empty() ? std::string("this service holds no model yet")
                                                                  : "this service holds the model of scan '" + scan_id_ + "'"));
    }
    const MeshKey key = mesh_key(r);
    if (last_mesh_ && last_mesh_->first == key) {  // the mesh already made: said again under this id
      mesh_result_t out = last_mesh_->second;
      out.request_id = r.request_id;
      log_info(what + " asks for the mesh made for request " + std::to_string(last_mesh_->second.request_id) +
               ": answered with it, not made again");
      answer_mesh(out);
      return;
    }
    if (meshing_.valid()) return;  // a repeat while the mesh is made (or another request: asked again later)
    if (meshes_made_ >= kMeshesPerScan) {
      MeshResult refused;
      refused.scan_id = r.scan_id;
      refused.request_id = r.request_id;
      refused.message = what + ": " + std::to_string(kMeshesPerScan) +
                        " different meshes of this scan made already, no more (a mesh takes seconds of CPU)";
      log_warn(refused.message);
      answer_mesh(bus::to_msg(refused));
      return;
    }
    bus_.set_scan(r.scan_id, -1);
    settle();  // the work after the last answer
    tie_model_to_object();
    ++meshes_made_;
    making_ = key;
    log_info("meshing " + std::to_string(r.views.size()) + " views");
    // The mesh reads only the frames' files, which no view changes after the scan's end (a CLOUD
    // that comes while it is made waits for it: on_cloud).
    meshing_ = std::async(std::launch::async, [this, r] {
      MeshResult out;
      out.scan_id = r.scan_id;
      out.request_id = r.request_id;
      try {
        out.mesh = model_.mesh(r.views, r.camera, r.point_spacing_m, mesh_units_);
        out.ok = true;
      } catch (const std::exception& e) {
        out.message = e.what();
      }
      return out;
    });
  }

  // At the scan's end, the model (cloud.ply, the frames and their poses, the depth images' poses)
  // is moved from the first view's kinematic frame to the object frame where the mount's
  // estimate puts it, once that estimate rests on 4 consistent views and is sure to a millimetre and 0.2 degrees
  // (else it stays).
  void tie_model_to_object() {
    if (off_ || !mount_.trusted(4)) return;
    place_again_by_the_estimate(5e-5, 0.005);
    const Pose target = mount_.object_T_model();
    const Pose delta = target * applied_.inverse();
    if (delta.translation().norm() < 1e-6 && Eigen::AngleAxisd(delta.linear()).angle() < 1e-6) return;
    try {
      model_.move_frame(delta);
      applied_ = target;
      save_mount();
      log_info(fmt::format("the model moved into the object frame by the mount's estimate: {:.3f} mm, ",
                           delta.translation().norm() * 1e3) +
               fmt::format("{:.4f} deg (hand_eye.json)", rad_to_deg(Eigen::AngleAxisd(delta.linear()).angle())));
    } catch (const std::exception& ex) {
      log_warn(std::string("the model stays in its frame: ") + ex.what());
    }
  }

  // Publishes a MESH_RESULT (stamped now) and keeps it to answer its request again.
  mesh_result_t answer_mesh(mesh_result_t out) {
    out.utime = bus::now_utime();
    bus_.publish(channels::kMeshResult, out);
    meshes_.put({out.scan_id, out.request_id}, out);
    return out;
  }

  // What a mesh is made of: the views, their camera and spacing.
  using MeshKey = std::tuple<std::vector<int>, int, int, double, double, double, double, double>;
  static MeshKey mesh_key(const MeshRequest& r) {
    const CameraIntrinsics& k = r.camera;
    return {r.views, k.width, k.height, k.fx, k.fy, k.cx, k.cy, r.point_spacing_m};
  }

  // A new scan's model: its meshes are counted afresh.
  void start_model(const std::string& scan_id) {
    scan_id_ = scan_id;
    model_.clear();
    mount_ = MountEstimator(params_.prior_translation_m, params_.prior_rotation_deg);
    applied_ = Pose::Identity();
    placed_views_.clear();
    mount_views_.clear();
    meshes_made_ = 0;
    last_mesh_.reset();
  }

  void on_cloud(const point_cloud_t& c) {
    asked_.require("CLOUD", c.scan_id, c.request_id);  // a cloud nobody asked for is not merged
    settle();
    bus_.set_scan(c.scan_id, c.iteration);
    if (meshing_.valid()) meshing_.wait();  // the frames stay as the mesh read them
    if (const registered_cloud_t* answer = answers_.find({c.scan_id, c.request_id})) {
      bus_.publish(channels::kRegisteredCloud, *answer);  // a repeat: answer again
      return;
    }
    const CaptureResult capture = bus::from_msg(c);  // a malformed cloud throws: rejected by the bus, nothing changed
    if (c.scan_id != scan_id_) start_model(c.scan_id);  // a new scan: a new model
    registered_cloud_t out;
    out.scan_id = c.scan_id;
    out.iteration = c.iteration;
    out.request_id = c.request_id;
    out.cloud = c;
    out.kinematic_object_T_camera = c.object_T_camera;
    out.correction = bus::to_msg(Pose::Identity());
    out.translation_m = out.rotation_deg = out.overlap = out.rmse_m = out.register_s = out.constraint = 0;
    out.refined = out.flagged = false;
    out.icp_translation_m = out.icp_rotation_deg = out.prior_sigmas = 0;
    out.iterations = 0;
    out.cloud.num_normals = 0;  // written to the frame's file, not sent on
    out.cloud.normals.clear();
    out.cloud.num_colours = 0;  // so are the colours
    out.cloud.colours.clear();
    out.normals = registered_cloud_t::kNormalsDepthImage;
    out.frame_points = out.model_points_before = 0;
    out.new_points = -1;
    out.new_surface_radius_m = out.accumulate_s = 0;
    if (c.status != point_cloud_t::kOk) {
      out.accepted = false;
      out.reason = "no cloud to register: " + c.message;
    } else {
      const PointCloud& frame = capture.points;
      const Pose kinematic = capture.object_T_camera;
      RegistrationResult r;
      if (off_) {  // for comparisons: every view kept where the kinematics put it
        r.accepted = true;
        r.reason = "registration off: kinematic pose kept";
      } else if (model_.points().empty() || !mount_.has_first()) {
        mount_.set_first(kinematic);  // the model's frame: this view's kinematic one
        mount_views_.clear();
        keep_for_mount(capture);
        r = register_frame(model_.points(), frame, params_, kinematic.translation());
      } else {
        // On a worker, the heartbeat going on meanwhile: ICP against a large model of a noisy
        // camera takes seconds, more on a loaded machine, and a silent service is taken for hung.
        auto job = std::async(std::launch::async, [&] {
          if (background_) lower_thread_priority(kBackgroundNice);  // the plan of the next view first
          keep_for_mount(capture);
          fit_mount_to_views();
          return register_predicted(c.iteration, frame, kinematic);
        });
        while (job.wait_for(std::chrono::milliseconds(250)) != std::future_status::ready) bus_.keep_alive();
        r = job.get();
      }
      out.accepted = r.accepted;
      out.refined = r.refined;
      out.flagged = r.flagged;
      out.icp_translation_m = r.icp_translation_m;
      out.icp_rotation_deg = r.icp_rotation_deg;
      out.prior_sigmas = r.prior_sigmas;
      out.constraint = r.constraint;
      out.reason = r.reason;
      out.correction = bus::to_msg(r.correction);
      out.translation_m = r.translation_m;
      out.rotation_deg = r.rotation_deg;
      out.overlap = r.overlap;
      out.rmse_m = r.rmse_m;
      out.iterations = r.iterations;
      out.register_s = r.time_s;
      PointCloud placed = frame;
      std::vector<Eigen::Vector3f> normals = capture.normals;
      Pose pose = kinematic;
      if (r.accepted) {
        placed = transform_cloud(frame, r.correction);
        const Eigen::Matrix3f turn = r.correction.linear().cast<float>();
        for (auto& n : normals) n = turn * n;
        pose = r.correction * kinematic;
        out.cloud.object_T_camera = bus::to_msg(pose);
        for (std::size_t i = 0; i < placed.size(); ++i) out.cloud.points_m[i] = {placed[i].x(), placed[i].y(), placed[i].z()};
      }
      if (!off_ && r.accepted) {
        // Each merged view's placing, in the first view's frame, for placing it again at the end.
        placed_views_.push_back({c.iteration, kinematic, applied_.inverse() * r.correction, r.refined || placed_views_.empty()});
      }
      save_mount();  // the estimate and the placings with this view (hand_eye.json, once per view)
      add_to_model(c, placed, std::move(normals), capture.colours, pose, r.accepted, out);
      std::ostringstream os;
      os << "view " << c.iteration << ": " << r.reason << " (" << r.time_s * 1e3 << " ms)";
      log_info(os.str());
    }
    out.model_points = static_cast<int32_t>(model_.points().size());
    out.utime = bus::now_utime();
    bus_.publish(channels::kRegisteredCloud, out);
    answers_.put({out.scan_id, out.request_id}, out);
    save(out);
    after_answer();
  }

  // After a view is answered, on a worker while the rig moves to the next view instead of on the
  // next frame's way: ICP's model (registration_model: the model downsampled, normals fitted over
  // all of it) and a k-d tree over the model for the next view's new surface. Taken while the model
  // has not changed since (on an uncalibrated rig the mount's fit places views again before the
  // next view registers: that view registers to the model given whole). Everything that touches
  // the model waits for it first (settle).
  struct PreparedModel {
    std::uint64_t revision = 0;  // ScanModel::revision() it was prepared from
    RegistrationModel model;
    std::optional<NeighbourIndex> index;  // over the model's points: the next view's new surface
  };
  // It starts when the rig is set moving to the next view (the scan's next MOVE_REQUEST heard), so
  // that the next view's plan (the map, the ellipsoids, the view scorer) has the CPU first, or
  // kStartAfterS after the answer at the latest (a lost MOVE_REQUEST, a scan that ends). With the
  // map at the rig's pose the plan does not wait for the answer: the work starts at once, at the
  // alignment's lower priority.
  void after_answer() {
    if (off_ || model_.points().empty()) return;
    settle();
    {
      std::lock_guard<std::mutex> lock(start_mutex_);
      start_ = background_;
    }
    preparing_ = std::async(std::launch::async, [this] {
      if (background_) lower_thread_priority(kBackgroundNice);
      {
        std::unique_lock<std::mutex> lock(start_mutex_);
        start_cv_.wait_for(lock, std::chrono::duration<double>(kStartAfterS), [this] { return start_; });
      }
      try {
        std::optional<PreparedModel> m = PreparedModel{model_.revision(), registration_model(model_.points(), params_), std::nullopt};
        m->index.emplace(model_.points());
        return m;
      } catch (const std::exception& e) {  // none: the next view registers to the model given whole
        log_warn("after the answer: " + std::string(e.what()));
        return std::optional<PreparedModel>();
      }
    });
  }
  void release_worker() {
    {
      std::lock_guard<std::mutex> lock(start_mutex_);
      start_ = true;
    }
    start_cv_.notify_all();
  }
  // Waits for the work after the last answer (starting it now if it waits for the move) and keeps
  // what it prepared.
  void settle() {
    if (!preparing_.valid()) return;
    release_worker();
    // The heartbeat goes on meanwhile (preparing takes a tenth of a second, more on a loaded machine).
    while (preparing_.wait_for(std::chrono::milliseconds(250)) != std::future_status::ready) bus_.keep_alive();
    prepared_ = preparing_.get();
  }
  // What was prepared, if the model is still as it was prepared from.
  const PreparedModel* current() const {
    return prepared_ && prepared_->revision == model_.revision() ? &*prepared_ : nullptr;
  }
  const RegistrationModel* prepared_model() const { return current() ? &current()->model : nullptr; }
  const NeighbourIndex* prepared_index() const {
    return current() && current()->index ? &*current()->index : nullptr;
  }

  // Registers a view from where the mount's estimate so far puts it (the kinematic pose when
  // nothing is known yet): the prior's mean moves there. ICP's proposal, against the kinematic
  // pose, goes into the estimate; the correction answered is against the kinematic pose.
  RegistrationResult register_predicted(int view, const PointCloud& frame, const Pose& kinematic) {
    // In the model's frame now: the first view's kinematic one, moved by applied_.
    // The estimate is used once it is sure (3 consistent views, 1 mm / 0.2 deg): an early one
    // resting on a view that slid would lead the next ones astray.
    const bool use = mount_.trusted(3);
    const Pose predicted = applied_ * (use ? mount_.predicted_correction(kinematic) : Pose::Identity());
    const PointCloud placed = transform_cloud(frame, predicted);
    const Eigen::Vector3d camera = (predicted * kinematic).translation();
    const RegistrationModel* prepared = prepared_model();
    RegistrationResult r = prepared ? register_frame(*prepared, placed, params_, camera)
                                    : register_frame(model_.points(), placed, params_, camera);
    const Pose total = r.correction * predicted;
    const double predicted_mm = predicted.translation().norm() * 1e3;
    r.correction = total;
    r.translation_m = total.translation().norm();
    r.rotation_deg = rad_to_deg(Eigen::AngleAxisd(total.linear()).angle());
    // Only well-overlapped alignments inform it (a view that sees little of the model may slide).
    if (r.icp && r.overlap >= kMountMinOverlap) {
      MountObservation o;
      o.view = view;
      o.kinematic = kinematic;
      o.proposal = *r.icp;
      o.proposal.correction = applied_.inverse() * r.icp->correction * predicted;
      o.proposal.centre = applied_.inverse() * r.icp->centre;
      o.proposal.covariance += per_view_covariance();
      mount_.add(o);
    }
    if (mount_.estimate().views > 0) {
      r.reason += (use ? fmt::format("; from the mount estimate's pose ({:.2f} mm from the kinematic one; mount ", predicted_mm)
                       : std::string("; mount estimate not used yet (")) +
                  fmt::format("{:.2f} mm, ", mount_.estimate().translation_m() * 1e3) +
                  fmt::format("{:.3f} deg off the rig file's over {} views, ", mount_.estimate().rotation_deg(),
                              mount_.estimate().views) +
                  fmt::format("{} left out", mount_.estimate().outliers) + ")";
    }
    return r;
  }

  // A view's points and normals (object frame by its kinematic pose) kept in its camera frame,
  // thinned to a few thousand, for fitting the mount to the views' agreement.
  void keep_for_mount(const CaptureResult& capture) {
    const PointCloud& frame = capture.points;
    const std::vector<Eigen::Vector3f>& normals = capture.normals;
    const Pose& kinematic = capture.object_T_camera;
    const int view = capture.iteration;
    if (normals.size() != frame.size()) return;
    constexpr std::size_t kKept = 4000;
    const std::size_t step = std::max<std::size_t>(1, frame.size() / kKept);
    MountView v;
    v.view = view;
    v.kinematic = kinematic;
    const Pose camera_T_object = kinematic.inverse();
    const Eigen::Matrix3f turn = camera_T_object.linear().cast<float>();
    for (std::size_t i = 0; i < frame.size(); i += step) {
      v.points.push_back((camera_T_object * frame[i].cast<double>()).cast<float>());
      v.normals.push_back(turn * normals[i]);
    }
    mount_views_.push_back(std::move(v));
  }

  // The mount fitted to the views' clouds at once (mount_from_views), from the last fit, once three
  // views are in: from then on it is the estimate (ICP's proposals say which views slid).
  void fit_mount_to_views() {
    // A mount known better than the fit resolves (0.1 mm and 0.01 deg from exact clouds:
    // mount_estimate_test), as the exact twin's, is not refitted.
    if (mount_views_.size() < 3 || (params_.prior_translation_m < 1e-4 && params_.prior_rotation_deg < 0.01)) return;
    const auto start = std::chrono::steady_clock::now();
    const MountEstimate e = mount_from_views(mount_views_, mount_.estimate().error, params_.prior_translation_m,
                                             params_.prior_rotation_deg);
    if (e.views < 3) return;
    mount_.set_from_views(e);
    log_info(fmt::format("the mount fitted to {} views' clouds: {:.2f} mm, {:.3f} deg off the rig file's ", e.views,
                         e.translation_m() * 1e3, e.rotation_deg()) +
             fmt::format("(sigma {:.2f} mm, {:.3f} deg; {:.0f} ms)", e.sigma_m * 1e3, e.sigma_deg,
                         std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count()));
    place_again_by_the_estimate(3e-4, 0.03);  // during the scan: what matters to the next alignments
  }

  // Views placed again where the mount's estimate puts them. Every view the clouds' fit paired
  // with another goes where that fit put it (the mount and the view's own error, fitted over all
  // views at once: replayed on the tune half's finished scans, d435 calibrated, 0.32 mm from the
  // truth at the object against 0.65 mm for ICP against the growing model, on the 11 objects where
  // no alignment slid). Of the others, those whose alignment was not taken (flagged, or not
  // pinned down by their overlap: placed at their kinematic pose, or where an earlier estimate put
  // them), those whose proposal the estimate left out as slid, and those placed more than 5 sigma
  // from where the mount puts them (an alignment that slid on too little overlap to inform the
  // estimate), sigma being the estimate's and a view's own (per_view_covariance) together, at the
  // view's points' centre.
  // Moves smaller than `min_move_m` (at the view's camera) and `min_move_deg` are left for later
  // (rewriting the model costs a read of every frame). cloud.ply is rebuilt once.
  void place_again_by_the_estimate(double min_move_m, double min_move_deg) {
    if (off_ || !mount_.trusted(3)) return;
    std::vector<int> merged;
    for (const PlacedView& v : placed_views_) merged.push_back(v.view);
    const std::vector<int>& slid = mount_.outlier_views();
    const MountEstimate& e = mount_.estimate();
    const TwistCovariance own = per_view_covariance();
    const double sigma_t = std::sqrt(own(3, 3) + e.sigma_m * e.sigma_m);
    const double sigma_r = std::sqrt(own(0, 0) + std::pow(deg_to_rad(e.sigma_deg), 2));
    std::vector<std::pair<int, Pose>> moves;
    std::vector<std::pair<PlacedView*, Pose>> placed;
    std::string said;
    for (PlacedView& v : placed_views_) {
      const std::optional<Pose> fitted = mount_.fitted_correction(v.view, v.kinematic);
      const Pose now = fitted ? *fitted : mount_.predicted_correction(v.kinematic);
      double sigmas = 0;
      if (v.refined && !fitted) {
        const auto seen = std::find_if(mount_views_.begin(), mount_views_.end(), [&](const MountView& m) { return m.view == v.view; });
        Eigen::Vector3d centre = v.kinematic.translation();
        if (seen != mount_views_.end() && !seen->points.empty()) {
          Eigen::Vector3d sum = Eigen::Vector3d::Zero();
          for (const auto& p : seen->points) sum += p.cast<double>();
          centre = v.correction * (v.kinematic * (sum / static_cast<double>(seen->points.size())));
        }
        const Twist d = twist_about(now * v.correction.inverse(), centre);
        sigmas = std::sqrt(d.head<3>().squaredNorm() / (sigma_r * sigma_r) + d.tail<3>().squaredNorm() / (sigma_t * sigma_t));
        const bool left_out = std::find(slid.begin(), slid.end(), v.view) != slid.end();
        if (v.view == placed_views_.front().view || (!left_out && sigmas <= 5.0)) continue;
      }
      const Pose q = applied_ * now * v.correction.inverse() * applied_.inverse();
      const double moved_m = (q * (applied_ * v.correction * v.kinematic).translation() -
                              (applied_ * v.correction * v.kinematic).translation()).norm();
      if (moved_m < min_move_m && Eigen::AngleAxisd(q.linear()).angle() < deg_to_rad(min_move_deg)) continue;
      moves.emplace_back(v.view, q);
      placed.emplace_back(&v, now);
      said += fmt::format("{}view {} {:.2f} mm", said.empty() ? "" : ", ", v.view + 1, moved_m * 1e3) +
              (fitted ? std::string() : v.refined ? fmt::format(" (its alignment {:.1f} sigma off)", sigmas) : std::string(" (mount only)"));
    }
    if (moves.empty()) return;
    try {
      model_.move_views(moves, merged);
      for (auto& [v, now] : placed) {
        v->correction = now;
        v->refined = false;  // placed by the estimate: placed again as it improves
      }
      log_info("placed again by the mount's estimate: " + said);
    } catch (const std::exception& ex) {
      log_warn("views not placed again: " + std::string(ex.what()));
    }
  }

  // What moves a view's pose besides the mount (joint encoders, turntable backlash): each view's
  // proposal is that uncertain beyond ICP's own covariance (a calibrated arm's size: 0.3 mm,
  // 0.03 degrees per axis).
  static TwistCovariance per_view_covariance() {
    Twist var;
    const double r = deg_to_rad(0.03), t = 0.3e-3;
    var << r * r, r * r, r * r, t * t, t * t, t * t;
    return var.asDiagonal();
  }

  // DIR/hand_eye.json: the mount's estimate (E: the camera sits at the rig file's flange_T_camera
  // times this), its sigma, the views it rests on, where the model lies in the object frame, and
  // the observations (a restarted service continues from them). Its views are counted from 1, as
  // scan.json's and the files' (view_001 is view 1); the service keeps them 0-based.
  void save_mount() const {
    if (out_.empty() || bus_.scope().empty() || !mount_.first()) return;
    const MountEstimate& e = mount_.estimate();
    nlohmann::json j;
    j["what"] = "the camera mount's error estimated across the scan's views: true flange_T_camera = the rig file's "
                "* error (docs/configuration.md, 'Cameras and rig errors')";
    j["views"] = e.views;
    j["outliers"] = e.outliers;
    j["error"] = to_json(e.error);
    j["error_mm"] = e.translation_m() * 1e3;
    j["error_deg"] = e.rotation_deg();
    j["sigma_mm"] = e.sigma_m * 1e3;
    j["sigma_deg"] = e.sigma_deg;
    j["fitted_to"] = mount_.from_views() ? "the views' clouds (each view against the others)" : "ICP's proposals";
    j["object_T_model"] = to_json(mount_.object_T_model());
    j["first_kinematic"] = to_json(*mount_.first());
    j["applied_object_T_model"] = to_json(applied_);  // what cloud.ply, frames/ and depth/ were moved by
    nlohmann::json obs = nlohmann::json::array();
    for (const MountObservation& o : mount_.observations()) {
      std::vector<double> cov(o.proposal.covariance.data(), o.proposal.covariance.data() + 36);
      obs.push_back({{"view", o.view + 1},
                     {"kinematic", to_json(o.kinematic)},
                     {"correction", to_json(o.proposal.correction)},
                     {"centre_m", to_json(o.proposal.centre)},
                     {"covariance", cov}});
    }
    j["observations"] = obs;
    nlohmann::json placed = nlohmann::json::array();
    for (const PlacedView& v : placed_views_) {
      placed.push_back({{"view", v.view + 1}, {"kinematic", to_json(v.kinematic)}, {"correction", to_json(v.correction)},
                        {"refined", v.refined}});
    }
    j["placed_views"] = placed;  // in the first view's frame
    write_json_atomic(j, (out_ / "hand_eye.json").string());
  }

  void restore_mount() {
    const std::filesystem::path path = out_ / "hand_eye.json";
    if (!std::filesystem::exists(path)) return;
    try {
      const nlohmann::json j = read_json(path.string());
      mount_.set_first(pose_from_json(j.at("first_kinematic"), path.string() + " first_kinematic"));
      if (j.contains("applied_object_T_model")) {
        applied_ = pose_from_json(j.at("applied_object_T_model"), path.string() + " applied_object_T_model");
      }
      for (const auto& o : j.at("observations")) {
        MountObservation m;
        // Counted from 1 in the file; 0 (or none): an observation of no view named.
        m.view = static_cast<int>(integer_from_json(o.contains("view") ? o.at("view") : nlohmann::json(0), 0, kViews.max,
                                                    path.string() + " observations view")) - 1;
        m.kinematic = pose_from_json(o.at("kinematic"), path.string() + " observation");
        m.proposal.correction = pose_from_json(o.at("correction"), path.string() + " observation");
        m.proposal.centre = vec3_from_json(o.at("centre_m"), path.string() + " observation");
        const std::vector<double> cov = o.at("covariance").get<std::vector<double>>();
        if (cov.size() != 36) throw std::invalid_argument(path.string() + ": a covariance of " + std::to_string(cov.size()) + " numbers, not 36");
        m.proposal.covariance = Eigen::Map<const TwistCovariance>(cov.data());
        if (!m.proposal.covariance.allFinite()) throw std::invalid_argument(path.string() + ": a covariance that is not finite");
        mount_.add(m);
      }
      for (const auto& v : j.value("placed_views", nlohmann::json::array())) {
        const int view = static_cast<int>(integer_from_json(v.at("view"), 1, kViews.max, path.string() + " placed_views view")) - 1;
        placed_views_.push_back({view, pose_from_json(v.at("kinematic"), path.string() + " placed view"),
                                 pose_from_json(v.at("correction"), path.string() + " placed view"),
                                 v.at("refined").get<bool>()});
      }
      // The views' clouds as their camera saw them, from their frames, and the fit to them again.
      for (const PlacedView& v : placed_views_) {
        MountView m;
        m.view = v.view;
        m.kinematic = v.kinematic;
        model_.view_in_camera_frame(v.view, m.points, m.normals);
        mount_views_.push_back(std::move(m));
      }
      fit_mount_to_views();
    } catch (const std::exception& e) {
      log_warn("the mount estimate is not continued (" + std::string(e.what()) + "): it starts again from the next view");
      mount_ = MountEstimator(params_.prior_translation_m, params_.prior_rotation_deg);
      applied_ = Pose::Identity();
      placed_views_.clear();
      mount_views_.clear();
    }
  }

  // The view into the model (and, with a folder, its frame, its depth image and cloud.ply); what
  // it added goes into the answer.
  void add_to_model(const point_cloud_t& c, const PointCloud& placed, std::vector<Eigen::Vector3f> normals,
                    const std::vector<Rgb>& colours, const Pose& pose, bool merge, registered_cloud_t& out) {
    const std::size_t before = model_.points().size();
    const ModelUpdate u = model_.add_view(c.iteration, placed, std::move(normals), pose, merge, colours, prepared_index());
    out.frame_file = u.frame_file;
    out.normals = u.normals_from_depth ? registered_cloud_t::kNormalsDepthImage : registered_cloud_t::kNormalsNeighbours;
    if (u.new_surface) {
      out.frame_points = u.new_surface->frame_points;
      out.new_points = u.new_surface->new_points;
      out.model_points_before = static_cast<int32_t>(before);
      out.new_surface_radius_m = u.new_surface->radius_m;
    }
    double seconds = u.seconds;
    const depth_frame_t* f = frames_.find(c.depth_frame_seq);
    if (f && !model_.folder().empty()) {
      const auto t0 = std::chrono::steady_clock::now();
      try {
        const bus::DecodedFrame d = bus::decode_frame(*f);
        std::optional<ScanModel::ColourFile> colour;
        // The JPEG as it came (raw R G B encoded): its camera is all that is read of it.
        if (std::optional<ColourImage> camera = bus::colour_camera(*f)) {
          colour.emplace();
          colour->jpeg = f->colour_encoding == depth_frame_t::kColourJpeg
                             ? f->colour
                             : bus::encode_jpeg(f->colour, camera->intrinsics.width, camera->intrinsics.height);
          colour->camera = std::move(*camera);
        }
        out.depth_file = model_.write_depth(c.iteration, DepthImage{&d.depth_m, d.intrinsics, d.range, f->seq}, pose, merge,
                                            write_depth_png, colour ? &*colour : nullptr);
      } catch (const std::invalid_argument& e) {
        log_warn("view " + std::to_string(c.iteration + 1) + ": DEPTH_FRAME " + std::to_string(f->seq) + " not written: " + e.what());
      }
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    out.accumulate_s = seconds;
  }

  // The state a restarted service continues from: DIR/cloud.ply (the model) and
  // DIR/state/registration.answer (the last REGISTERED_CLOUD), written after every view.
  std::filesystem::path state_path(const char* name) const { return out_ / "state" / name; }

  void save(const registered_cloud_t& answer) {
    if (out_.empty() || bus_.scope().empty()) return;  // only a service started for one scan
    std::filesystem::create_directories(out_ / "state");
    bus::save_message(answer, state_path("registration.answer").string());
  }

  // Continues the model of the scan this service serves when the folder holds it (a restart).
  void restore() {
    if (out_.empty() || bus_.scope().empty()) return;
    const auto last = bus::load_message<registered_cloud_t>(state_path("registration.answer").string());
    if (!last || last->scan_id != bus_.scope()) return;
    model_.restore();
    restore_mount();
    scan_id_ = last->scan_id;
    answers_.put({last->scan_id, last->request_id}, *last);
    log_info("continuing the model of scan " + scan_id_ + " (" + std::to_string(model_.points().size()) +
             " points) after view " + std::to_string(last->iteration) + " from " + (out_ / "cloud.ply").string());
  }

  bus::AskedCaptures asked_;
  bus::Bus& bus_;
  RegistrationParams params_;
  bool off_;
  bool background_;  // the map at the rig's pose: the plan does not wait for the alignment
  std::filesystem::path out_;
  LengthUnit mesh_units_;  // mesh.obj's
  std::string scan_id_;
  ScanModel model_;
  MountEstimator mount_{params_.prior_translation_m, params_.prior_rotation_deg};  // for scan_id_
  Pose applied_ = Pose::Identity();  // the model's frame: the first view's kinematic one moved by this
  struct PlacedView {
    int view;
    Pose kinematic;
    Pose correction;  // registered = correction * kinematic, in the first view's frame
    bool refined;     // by ICP (or the first view): kept as it is
  };
  std::vector<PlacedView> placed_views_;
  std::vector<MountView> mount_views_;  // the merged views in their camera frames, for the mount's fit
  bus::RecentFrames frames_;          // the last depth frames, for DIR/depth/
  std::mutex start_mutex_;            // after_answer's work waits for the move:
  std::condition_variable start_cv_;  // ... signalled here
  bool start_ = false;                // ... once it may start
  std::future<std::optional<PreparedModel>> preparing_;  // after_answer's work, running (declared after what it uses)
  std::optional<PreparedModel> prepared_;  // ... and what it prepared
  std::future<MeshResult> meshing_;   // the mesh being made
  MeshKey making_;                    // ... of this
  int meshes_made_ = 0;               // for scan_id_
  std::optional<std::pair<MeshKey, mesh_result_t>> last_mesh_;  // the last mesh made for scan_id_
  bus::ReplyCache<std::pair<std::string, int64_t>, mesh_result_t> meshes_{kAnswersKept};
  bus::ReplyCache<std::pair<std::string, int64_t>, registered_cloud_t> answers_{kAnswersKept};
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbnbv-registration: refines every captured view's pose by ICP against the model", "pbnbv-registration"};
  cli::init(app);
  // The registration's own settings (this program is their only user): defaults from
  // RegistrationParams, ranges here.
  RegistrationParams p;
  const RegistrationParams d;
  cli::add(app, kIcpVoxel, &p.voxel_m);
  cli::add(app, Setting<double>{"max-correspondence", d.max_correspondence_m, 0.001, 0.5, "m",
                                "ICP correspondence distance (coarse-to-fine from here)"},
           &p.max_correspondence_m);
  cli::add(app, Setting<int>{"max-iterations", d.max_iterations, 1, 1000, "", "ICP iterations at most"},
           &p.max_iterations);
  cli::add(app, Setting<double>{"min-overlap", d.min_overlap, 0.0, 1.0, "", "accept: at least this share of the view's points lies near the model after alignment"},
           &p.min_overlap);
  cli::add(app, Setting<double>{"max-rmse", d.max_rmse_m, 1e-5, 0.1, "m", "accept: RMS distance of the overlapping points at most this"},
           &p.max_rmse_m);
  cli::add(app, Setting<double>{"max-correction", d.max_translation_m, 1e-4, 1.0, "m",
                                "accept: the correction moves the camera at most this far"},
           &p.max_translation_m);
  cli::add(app, Setting<double>{"max-correction-deg", d.max_rotation_deg, 0.01, 45.0, "deg",
                                "accept: the correction turns the camera at most this much"},
           &p.max_rotation_deg);
  double pose_sigma_mm = d.prior_translation_m * 1e3;
  cli::add(app, kPoseSigmaMm, &pose_sigma_mm);
  cli::add(app, kPoseSigmaDeg, &p.prior_rotation_deg);
  double model_voxel_m = 0;
  cli::add(app, kCloudVoxel.renamed("model-voxel", "the model cloud's downsampling voxel (0: off)"), &model_voxel_m);
  double new_surface_radius_m = kStopRadius.value;
  cli::add(app, kStopRadius.renamed("new-surface-radius", "a view's point farther than this from the model is new surface"),
           &new_surface_radius_m);
  bool off = false;
  cli::add_flag(app, "off", &off, "pass every view through with its kinematic pose (no ICP)");
  MapPose map_pose = kMapPose.value;
  cli::add(app, kMapPose, &map_pose);
  LengthUnit mesh_units = kMeshUnits.value;
  cli::add(app, kMeshUnits, &mesh_units);
  std::string out;
  cli::add_text(app, "out", &out,
                "the scan's folder: with --scan, each view's frame (DIR/frames/), depth image (DIR/depth/) and the model "
                "(DIR/cloud.ply, continued after a restart) are written there", "DIR");
  return bus::run_service("registration", app, argc, argv, 20, [&](bus::Bus& bus) -> std::function<void()> {
    p.prior_translation_m = pose_sigma_mm * 1e-3;
    auto service = std::make_shared<RegistrationService>(bus, p, model_voxel_m, new_surface_radius_m, off, out, mesh_units, map_pose);
    log_info("ready");
    return [service] { service->tick(); };
  });
}
