#include "core/scan/scan_sequencer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "core/base/format.hpp"
#include "core/io/json.hpp"

namespace fs = std::filesystem;

namespace pbnbv {

namespace {

// An object-frame box from the settings' corners; equal corners mean "no box".
Eigen::AlignedBox3d box_or_none(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m) {
  if (min_m == max_m) return Eigen::AlignedBox3d();
  return Eigen::AlignedBox3d(min_m, max_m);
}

}  // namespace

ScanSequencer::ScanSequencer(ScanSettings settings, fs::path out, ScanTimeouts timeouts)
    : s_(std::move(settings)), t_(timeouts), record_(std::move(out), s_) {
  const std::vector<Pose> start = views_known_at_start(s_);
  if (s_.planner == PlannerKind::kRing) {
    ring_ = start;
    record_.set_ring_plan(s_.working_distance_m + (s_.expected_extent_m() / 2.0).norm(), s_.ring_elevation_deg);
  } else {
    first_view_ = start.front();
    record_.set_next_best_view_plan(std::string(name_of(s_.planner)), first_view_);
  }
}

CaptureRequest ScanSequencer::capture_request(int iteration, int64_t request_id, int64_t not_before_utime) const {
  CaptureRequest r;
  r.scan_id = s_.scan_id;
  r.iteration = iteration;
  r.request_id = request_id;
  r.not_before_utime = not_before_utime;
  r.object_z_m = s_.object_z_m;
  r.crop = box_or_none(s_.crop_min_m, s_.crop_max_m);
  r.ground_clearance_m = s_.ground_clearance_m;
  r.voxel_m = s_.voxel_m;
  r.timeout_s = s_.capture_timeout_s;
  return r;
}

namespace {

// Request ids a scan may use: first_request_id() draws below 2^62, and a resumed scan goes on
// from the largest recorded, so every id of a scan stays far below what int64 holds.
constexpr int64_t kMaxRequestId = int64_t{1} << 62;

}  // namespace

void ScanSequencer::resume(double now_s) {
  record_.continue_from_folder(s_.scan_id);  // read into its types, every field checked
  const RecordedScan& recorded = record_.record();
  const std::string file = record_.scan_json_path().string();
  int64_t max_id = 0;
  for (const ViewRecord& v : recorded.views) {
    // Each entry's view below the scan's view count: a folder that says otherwise was not
    // written by a scan of these settings.
    const int i = v.view;
    if (i >= s_.views) {
      throw std::invalid_argument(file + ": view " + std::to_string(i + 1) + " is beyond the scan's " + std::to_string(s_.views) + " views");
    }
    for (const FailedMove& f : v.failed_moves) done_.excluded.push_back(f.object_T_camera);
    Pose reached = Pose::Identity();
    if (v.move && v.move->status == MoveStatus::kReached) {
      reached = v.move->reached_object_T_camera;
      done_.joints_rad = v.move->joint_position_rad;
      done_.turntable_rad = v.move->turntable_angle_rad;
    }
    if (v.plan && std::isfinite(v.plan->plan.first_quality) && !std::isfinite(done_.first_quality)) {
      done_.first_quality = v.plan->plan.first_quality;
    }
    if (v.capture) {
      max_id = std::max(max_id, v.capture->request_id);
      capture_request_ = capture_request(i, v.capture->request_id, 0);  // the last one stays
      if (!v.capture->ok) done_.excluded.push_back(reached);
    }
    if (v.map) {
      done_.latest_map = i;
      done_.latest_map_request = capture_request_.request_id;
      ++done_.views_done;
      if (v.map->updated && v.registration) {
        done_.last_map = i;
        done_.views_taken.push_back(v.registration->cloud.object_T_camera);
      } else {
        done_.excluded.push_back(reached);
      }
    }
    next_view_after_ready_ = i + 1;
  }
  const ScanStatusRecord& status = recorded.status;
  // Past every id recorded, with room for those the interrupted view sent but did not record.
  done_.next_request_id = std::max<int64_t>(status.next_request_id, max_id + 1) + 1000;
  record_.set_next_request_id(done_.next_request_id);
  const double elapsed_s = status.elapsed_s;
  if (!std::isfinite(elapsed_s) || elapsed_s < 0 || elapsed_s > 1e9) {
    throw std::invalid_argument(file + ": status elapsed_s = " + std::to_string(elapsed_s) + " is not a duration (0..1e9 s)");
  }
  t_start_s_ = now_s - elapsed_s;
  if (status.state == "done") {
    phase_ = Phase::kFinished;
    state_ = ScanState::kDone;
    summary_ = "scan already complete: " + status.message + " -> " + file;
    return;
  }
  phase_ = Phase::kWaitingReady;
  set_status(ScanState::kStarting, "resuming after view " + std::to_string(next_view_after_ready_) + ": waiting for the rig and services",
             now_s);
  check_ready(now_s);
}

void ScanSequencer::replay(std::vector<std::vector<Pose>> attempts, const std::string& recorded) {
  for (std::size_t i = 0; i < attempts.size(); ++i) {
    if (attempts[i].empty()) {
      throw std::invalid_argument(recorded + ": view " + std::to_string(i + 1) + " has no pose it moved to: cannot replay it");
    }
  }
  if (attempts.empty()) throw std::invalid_argument(recorded + " records no view: nothing to replay");
  s_.views = static_cast<int>(attempts.size());
  replay_ = std::move(attempts);
  record_.set_replay_of(recorded, s_.views);
}

void ScanSequencer::start(double now_s) {
  done_.next_request_id = first_request_id();
  record_.set_next_request_id(done_.next_request_id);
  t_start_s_ = now_s;
  phase_ = Phase::kWaitingReady;
  set_status(ScanState::kStarting, "waiting for the rig and services", now_s);
  check_ready(now_s);
}

void ScanSequencer::handle(const ScanEvent& event, double now_s) {
  if (phase_ == Phase::kFinished) return;
  std::visit([&](const auto& e) { on(e, now_s); }, event);
}

void ScanSequencer::tick(double now_s) {
  switch (phase_) {
    case Phase::kIdle:
    case Phase::kFinished:
      return;
    case Phase::kWaitingReady:
      check_ready(now_s);
      break;
    case Phase::kPlanning:
      if (awaited_.expired(now_s)) return finish(ScanState::kFailed, waited("the view scorer", "VIEW_PLAN", "the plan request"), now_s);
      break;
    case Phase::kMoving:
      if (awaited_.expired(now_s)) {
        view_.move_unanswered = true;
        return fail_view(waited("the motion executor", "MOVE_RESULT", "the move request"), now_s);
      }
      break;
    case Phase::kCapturing:
      if (awaited_.expired(now_s)) {
        view_.capture_unanswered = true;
        return fail_view(waited("the camera service", "CLOUD", "the capture request"), now_s);
      }
      break;
    case Phase::kRegistering:
      if (awaited_.expired(now_s)) return fail_view(waited("the registration service", "REGISTERED_CLOUD", "the capture request"), now_s);
      break;
    case Phase::kMapping:
      if (awaited_.expired(now_s)) return fail_view(waited("the mapping service", "VOXEL_MAP", "the capture request"), now_s);
      break;
    case Phase::kAwaitingRegistration:  // the deferred view's deadline, below
      break;
    case Phase::kMeshing:
      if (awaited_.expired(now_s)) {
        return meshed(std::nullopt,
                      "the registration service sent no MESH_RESULT in " + fixed(awaited_.deadline_s - awaited_.since_s, 0) +
                          " s (the mesh request sent " + std::to_string(awaited_.sends) + " times)",
                      now_s);
      }
      break;
  }
  if (phase_ == Phase::kFinished) return;
  if (deferred_) {
    if (now_s - deferred_->since_s >= t_.answer_s) {
      const int sends = deferred_->sends;
      return finish(ScanState::kFailed,
                    "the registration service sent no REGISTERED_CLOUD for view " + std::to_string(deferred_->view.view + 1) +
                        " in " + fixed(t_.answer_s, 0) + " s (the capture request sent " + std::to_string(sends) +
                        (sends == 1 ? " time)" : " times)"),
                    now_s);
    }
    if (now_s - deferred_->last_sent_s >= t_.capture_resend_s) {  // lost on the way: asked for again
      outputs_.push_back(deferred_->capture_request);
      deferred_->last_sent_s = now_s;
      ++deferred_->sends;
    }
  }
  if (awaited_.resend_due(now_s)) {
    outputs_.push_back(*awaited_.request);
    // A late plan may wait for a VOXEL_MAP or ELLIPSOIDS that was lost, or that a restarted
    // ellipsoid fitter or view scorer never saw: the last view's capture request, sent again,
    // makes the camera, the registration and the mapping service repeat their answers (from
    // their caches) and the fitter fit that map again.
    if (phase_ == Phase::kPlanning && !capture_request_.scan_id.empty()) outputs_.push_back(capture_request_);
    awaited_.last_sent_s = now_s;
    ++awaited_.sends;
  }
  if (now_s - last_status_s_ >= t_.status_period_s) publish_status(now_s);
}

void ScanSequencer::stop(double now_s, const std::string& why) {
  if (phase_ != Phase::kFinished) finish(ScanState::kStopped, why, now_s);
}

void ScanSequencer::abort(double now_s, const std::string& why) {
  if (phase_ != Phase::kFinished) finish(ScanState::kFailed, why, now_s);
}

std::vector<ScanOutput> ScanSequencer::take_outputs() {
  std::vector<ScanOutput> out;
  out.swap(outputs_);
  return out;
}

int ScanSequencer::exit_code() const {
  switch (state_) {
    case ScanState::kDone: return 0;
    case ScanState::kStopped: return 130;
    default: return 1;
  }
}

// ---- Events ----------------------------------------------------------------------------------

void ScanSequencer::on(const Heard& h, double now_s) {
  seen_.insert(h.what);
  if (phase_ == Phase::kWaitingReady) check_ready(now_s);
}

void ScanSequencer::on(const ViewPlan& p, double now_s) {
  if (p.scan_id != s_.scan_id || phase_ != Phase::kPlanning || p.request_id != awaited_.request_id) return;
  const std::string what = "VIEW_PLAN of request " + std::to_string(p.request_id);
  if (p.iteration != iteration_) return refuse(what, "it plans view " + std::to_string(p.iteration + 1));
  if (p.planner != s_.planner) return refuse(what, "its planner is " + std::string(name_of(p.planner)));
  if (p.outcome == PlanOutcome::kView) {
    if (!is_rigid(p.object_T_camera)) return refuse(what, "its view is not a rigid transform");
    if (!std::isfinite(p.view_quality)) return refuse(what, "its view_quality is not finite");
    if (p.alternatives.size() > static_cast<std::size_t>(s_.alternatives) ||
        p.alternative_quality.size() != p.alternatives.size()) {
      return refuse(what, std::to_string(p.alternatives.size()) + " alternatives with " +
                              std::to_string(p.alternative_quality.size()) + " qualities (at most " +
                              std::to_string(s_.alternatives) + " asked for)");
    }
    for (const Pose& a : p.alternatives) {
      if (!is_rigid(a)) return refuse(what, "an alternative is not a rigid transform");
    }
  }
  for (const int n : {p.num_candidates, p.num_unreachable, p.num_excluded, p.num_scored}) {
    if (n < 0 || n > s_.candidates) {
      return refuse(what, "a candidate count " + std::to_string(n) + " is outside 0.." + std::to_string(s_.candidates));
    }
  }
  planned(p, now_s);
}

void ScanSequencer::on(const MoveResult& r, double now_s) {
  if (r.scan_id != s_.scan_id || phase_ != Phase::kMoving || r.request_id != awaited_.request_id) return;
  const std::string what = "MOVE_RESULT of request " + std::to_string(r.request_id);
  if (r.iteration != iteration_) return refuse(what, "it is for view " + std::to_string(r.iteration + 1));
  if (r.status == MoveStatus::kReached && !is_rigid(r.reached_object_T_camera)) {
    return refuse(what, "the reached pose is not a rigid transform");
  }
  if (r.status == MoveStatus::kBusy) {  // still finishing an earlier move: ask again now
    outputs_.push_back(*awaited_.request);
    awaited_.last_sent_s = now_s;
    ++awaited_.sends;
    return;
  }
  if (r.status == MoveStatus::kRigSilent) {
    // The rig's drivers are silent (a driver restarting, a cable): the scan pauses with the rig
    // still and asks again at every re-send, for up to t_.rig_silent_s, then fails naming them.
    if (!paused_) {
      paused_ = true;
      progress("paused: " + r.reason);
      set_status(ScanState::kMoving, "paused: " + r.reason, now_s);
      awaited_.deadline_s = std::max(awaited_.deadline_s, now_s + t_.rig_silent_s);
    }
    return;
  }
  if (paused_) {
    paused_ = false;
    progress("resumed: the rig is back");
  }
  moved(r, now_s);
}

void ScanSequencer::on(const CaptureResult& c, double now_s) {
  if (c.scan_id != s_.scan_id || phase_ != Phase::kCapturing || c.request_id != capture_id_) return;
  if (c.iteration != iteration_) {
    return refuse("CLOUD of request " + std::to_string(c.request_id), "it is for view " + std::to_string(c.iteration + 1));
  }
  captured(c, now_s);
}

void ScanSequencer::on(const RegisteredCloud& r, double now_s) {
  if (r.scan_id != s_.scan_id) return;
  if (deferred_ && r.request_id == deferred_->capture_request.request_id) return on_deferred(r, now_s);
  // The registration may answer the cloud before the sequence has taken the cloud itself, and
  // (map_pose rig) before or after the map.
  if (r.request_id != capture_id_) return;
  if (phase_ != Phase::kCapturing && phase_ != Phase::kRegistering && phase_ != Phase::kMapping) return;
  if (r.iteration != iteration_) {
    return refuse("REGISTERED_CLOUD of request " + std::to_string(r.request_id),
                  "it is for view " + std::to_string(r.iteration + 1));
  }
  if (registered_) return;  // a repeat
  registered_ = r;
  if (phase_ == Phase::kRegistering) registered(now_s);
  else if (phase_ == Phase::kMapping) view_.register_round_trip_s = now_s - t_captured_s_;
}

void ScanSequencer::on(const VoxelMapSummary& m, double now_s) {
  // A map of another request for this view (a forged cloud the mapping service took, an earlier
  // capture) is not this view's map.
  if (m.scan_id != s_.scan_id || m.iteration != iteration_ || m.request_id != capture_id_) return;
  if (phase_ != Phase::kCapturing && phase_ != Phase::kRegistering && phase_ != Phase::kMapping) return;
  map_ = m;
  if (phase_ == Phase::kMapping) mapped(now_s);
}

void ScanSequencer::on(const MeshResult& m, double now_s) {
  if (m.scan_id != s_.scan_id || phase_ != Phase::kMeshing || m.request_id != awaited_.request_id) return;
  if (!m.ok) return meshed(std::nullopt, m.message, now_s);
  const std::size_t merged = std::get<MeshRequest>(*awaited_.request).views.size();
  if (m.mesh.frames > merged) {
    return refuse("MESH_RESULT of request " + std::to_string(m.request_id),
                  "it fused " + std::to_string(m.mesh.frames) + " frames of " + std::to_string(merged) + " asked for");
  }
  meshed(m.mesh, "", now_s);
}

void ScanSequencer::on(const EllipsoidSetSummary& e, double /*now_s*/) {
  // Sets of maps not yet made (a view after the current one) are not kept: nothing asks for them.
  if (e.scan_id != s_.scan_id || e.iteration < done_.latest_map || e.iteration > iteration_) return;
  // Fitted to the map of the request the view's was (the current view's, or the newest map's).
  const int64_t map_request = e.iteration == iteration_ ? capture_id_ : done_.latest_map_request;
  if (e.request_id != map_request) return;
  ellipsoids_[e.iteration] = e;
}

// ---- The sequence ----------------------------------------------------------------------------

void ScanSequencer::check_ready(double now_s) {
  std::set<std::string> need = {"ARM_STATUS", "heartbeat of motion", "heartbeat of camera",
                                "heartbeat of registration", "heartbeat of mapping"};
  if (s_.rig == RigKind::kArm) need.insert("TURNTABLE_STATUS");
  if (uses_view_scorer(s_.planner)) need.insert("heartbeat of scorer");
  if (uses_ellipsoids(s_.planner)) need.insert("heartbeat of ellipsoids");
  std::string missing;
  for (const auto& n : need) {
    if (!seen_.count(n)) missing += (missing.empty() ? "" : ", ") + n;
  }
  if (missing.empty()) {
    if (next_view_after_ready_ >= s_.views) {  // a resumed scan that had every view
      iteration_ = s_.views - 1;
      return next_view(now_s);
    }
    return begin_view(next_view_after_ready_, now_s);
  }
  if (now_s - t_start_s_ > s_.startup_timeout_s) {
    finish(ScanState::kFailed, "not ready after " + fixed(s_.startup_timeout_s, 2) + " s: no " + missing, now_s);
  }
}

void ScanSequencer::begin_view(int i, double now_s) {
  iteration_ = i;
  view_ = ViewRecord{};
  view_.view = i;
  t_view_s_ = now_s;
  options_.clear();
  option_ = 0;
  capture_id_ = -1;
  registered_.reset();
  map_.reset();
  if (s_.planner == PlannerKind::kRing) {
    options_ = replay_ ? (*replay_)[i] : std::vector<Pose>{ring_[i]};
    return begin_move(now_s);
  }
  if (i == 0) {
    options_ = replay_ ? (*replay_)[0] : first_view_options(s_);
    view_.initial_view = true;
    return begin_move(now_s);
  }
  progress("planning");
  set_status(ScanState::kPlanning, "planning " + view_name(), now_s);
  begin_plan(now_s);
}

void ScanSequencer::begin_plan(double now_s) {
  phase_ = Phase::kPlanning;
  PlanRequest r;
  r.scan_id = s_.scan_id;
  r.iteration = iteration_;
  r.planner = s_.planner;
  r.seed = s_.seed + iteration_;
  r.map_iteration = done_.latest_map;  // the newest map: the view scorer keeps only that one
  r.map_request_id = done_.latest_map_request;
  r.views_done = done_.views_taken;
  r.excluded = done_.excluded;
  r.num_candidates = s_.candidates;
  r.num_parallels = s_.parallels;
  r.num_sectors = partition_sectors(s_.planner, s_.rig == RigKind::kFree, s_.sectors);
  r.area = s_.area;
  r.working_distance_m = s_.working_distance_m;
  r.num_alternatives = s_.alternatives;
  r.stop_fraction = s_.stop_fraction;
  r.when_done = s_.when_done;
  r.first_quality = done_.first_quality;
  r.camera = s_.camera;
  r.depth_range = s_.depth_range;
  r.check_reachability = s_.rig == RigKind::kArm;
  r.joint_position_rad = done_.joints_rad;
  r.turntable_angle_rad = done_.turntable_rad;
  r.object_z_m = s_.object_z_m;
  r.keepout = box_or_none(s_.keepout_min_m, s_.keepout_max_m);
  r.turntable_choice = turntable_choice(s_);
  r.seconds_per_point = r.turntable_choice != TurntableChoice::kPreferred && s_.rig == RigKind::kArm ? s_.seconds_per_point : 0.0;
  if (done_.last_map < 0) {  // nothing to plan from: no request
    ViewPlan none;
    none.scan_id = s_.scan_id;
    none.iteration = iteration_;
    none.planner = s_.planner;
    none.outcome = PlanOutcome::kFailed;
    none.reason = "no view has been mapped yet";
    return planned(none, now_s);
  }
  r.request_id = next_request_id();
  send(r, r.request_id, t_.resend_s, now_s + t_.plan_s, now_s);
}

void ScanSequencer::planned(const ViewPlan& p, double now_s) {
  PlanRecord plan;
  plan.plan = p;
  plan.map_of_view = done_.latest_map;
  if (latest_map_summary_ && latest_map_summary_->iteration == done_.latest_map) {
    plan.map_update_s = latest_map_summary_->update_s;
  }
  if (auto e = ellipsoids_.find(done_.latest_map); e != ellipsoids_.end()) plan.ellipsoids = e->second;
  if (replay_) {  // the recorded view, whatever the plan
    const std::string decision = p.outcome == PlanOutcome::kView ? "a view" : std::string(to_string(p.outcome)) + ": " + p.reason;
    if (p.outcome == PlanOutcome::kView && !std::isfinite(done_.first_quality)) done_.first_quality = p.first_quality;
    options_ = (*replay_)[iteration_];
    progress("planned " + decision + "; replaying the recorded view");
    view_.plan = std::move(plan);
    return begin_move(now_s);
  }
  if (p.outcome != PlanOutcome::kView) {
    const bool stop = p.outcome == PlanOutcome::kStop;
    // The view whose registration is awaited (map_pose rig) counts: the scan ends once it is recorded.
    stop_ = ScanStop{p.reason, done_.views_done + (deferred_ ? 1 : 0), stop ? "planner" : "planner failed", {}};
    record_.set_stop(*stop_);
    record_.set_planning_stopped(plan);
    if (stop) return finish(ScanState::kDone, "scan complete: " + p.reason, now_s);
    return finish(ScanState::kFailed, "no plan for " + view_name() + ": " + p.reason, now_s);
  }
  if (!std::isfinite(done_.first_quality)) done_.first_quality = p.first_quality;
  options_ = {p.object_T_camera};
  options_.insert(options_.end(), p.alternatives.begin(), p.alternatives.end());
  std::string quality;  // what the plan ranked by (a gap-filling view of any planner: degrees)
  switch (p.ranking) {
    case Ranking::kF: quality = "F " + fixed(p.view_quality, 2) + " px, "; break;
    case Ranking::kUnobservedVoxels: quality = "gain " + fixed(p.view_quality, 2) + " voxels, "; break;
    case Ranking::kTrueSamples: quality = fixed(p.view_quality, 0) + " new true surface samples, "; break;
    case Ranking::kGapAngle: quality = "gap-filling, " + fixed(p.view_quality, 1) + " deg from the nearest view, "; break;
    case Ranking::kCombined: quality = "combined " + fixed(p.view_quality, 2) + " of 3, "; break;
    case Ranking::kRandom: break;
  }
  progress("planned: " + quality + std::to_string(p.num_scored) + " candidates scored");
  view_.plan = std::move(plan);
  begin_move(now_s);
}

void ScanSequencer::begin_move(double now_s) {
  phase_ = Phase::kMoving;
  progress("moving");
  set_status(ScanState::kMoving, "moving to " + view_name(), now_s);
  t_step_s_ = now_s;
  option_ = 0;
  send_move(now_s);
}

void ScanSequencer::send_move(double now_s) {
  MoveRequest r;
  r.scan_id = s_.scan_id;
  r.iteration = iteration_;
  r.request_id = next_request_id();
  r.object_T_camera = options_[option_];
  r.object_z_m = s_.object_z_m;
  r.keepout = box_or_none(s_.keepout_min_m, s_.keepout_max_m);
  r.speed_scale = s_.speed_scale;
  r.timeout_s = s_.move_timeout_s;
  r.plan_only = false;
  r.turntable_choice = turntable_choice(s_);
  send(r, r.request_id, t_.resend_s, now_s + s_.move_timeout_s + t_.move_extra_s, now_s);
}

void ScanSequencer::moved(const MoveResult& r, double now_s) {
  if (deferred_) {  // what follows a move records or captures: the view before first
    held_move_ = r;
    return await_registration(now_s);
  }
  if (r.contacts > 0) {
    progress(fmt::format("warning: the rig reported {} contact{} during the move (request {}): {}", r.contacts,
                         r.contacts == 1 ? "" : "s", r.request_id, r.contact),
             true);
  }
  if (r.status == MoveStatus::kReached) {
    view_.option = static_cast<int>(option_);
    view_.requested_object_T_camera = options_[option_];
  } else {
    view_.failed_moves.push_back(
        {static_cast<int>(option_), options_[option_], r.status, r.reason, r.request_id, r.contacts, r.contact});
    done_.excluded.push_back(options_[option_]);
    if (r.status == MoveStatus::kUnreachable && option_ + 1 < options_.size()) {  // the next alternative
      ++option_;
      return send_move(now_s);
    }
  }
  view_.move = r;
  view_.move_round_trip_s = now_s - t_step_s_;
  // Rig time: this move's motion and settling; the previous view waited until its command.
  const MoveRigTime rig = move_rig_time(r);
  const bool reached = r.status == MoveStatus::kReached;  // then a capture follows; else none (0)
  view_.rig_time = RigTime{rig.motion_s, rig.settle_s, reached ? RigTime::kUnset : 0.0, RigTime::kUnset};
  if (rig_wait_) end_rig_wait(compute_wait_s(rig_wait_->since_s, now_s, r));
  if (!reached) {
    progress(std::string(to_string(r.status)) + ": " + r.reason, true);
    begin_rig_wait(now_s);  // nothing to capture: the rig waits from here
    record_.add_view(view_, done_.views_done, now_s - t_start_s_);
    return next_view(now_s);
  }
  moved_ = r;
  t_settled_s_ = now_s;
  done_.joints_rad = r.joint_position_rad;
  done_.turntable_rad = r.turntable_angle_rad;
  begin_capture(r.settled_utime, now_s);
}

void ScanSequencer::begin_capture(int64_t not_before_utime, double now_s) {
  phase_ = Phase::kCapturing;
  progress("capturing");
  set_status(ScanState::kCapturing, "capturing " + view_name(), now_s);
  t_step_s_ = now_s;
  const CaptureRequest r = capture_request(iteration_, next_request_id(), not_before_utime);
  capture_id_ = r.request_id;
  capture_request_ = r;
  // The camera service re-triggers the camera itself and answers within the capture timeout;
  // the request is re-sent (the same id: answered again, never captured twice) in case the
  // request or its answer is lost.
  send(r, r.request_id, t_.capture_resend_s, now_s + 2 * s_.capture_timeout_s + t_.capture_extra_s, now_s);
}

void ScanSequencer::captured(const CaptureResult& c, double now_s) {
  view_.capture = c;
  view_.capture_points = c.points.size();
  view_.capture->points = PointCloud();  // counted; the registration service keeps the points
  view_.capture->normals.clear();
  view_.capture_round_trip_s = now_s - t_step_s_;
  if (view_.rig_time) view_.rig_time->capture_s = capture_wait_s(t_settled_s_, now_s, c);
  begin_rig_wait(now_s - c.process_s);  // from the frame's arrival at the camera service
  if (!c.ok) {
    progress("capture failed: " + c.message, true);
    done_.excluded.push_back(moved_.reached_object_T_camera);
    record_.add_view(view_, done_.views_done, now_s - t_start_s_);
    return next_view(now_s);
  }
  t_captured_s_ = now_s;
  if (s_.map_pose == MapPose::kRig) {  // the map first: the next view is planned from it
    if (registered_) view_.register_round_trip_s = 0;
    set_status(ScanState::kIntegrating, "mapping " + view_name(), now_s);
    return begin_map(now_s);
  }
  begin_register(now_s);
}

void ScanSequencer::begin_register(double now_s) {
  phase_ = Phase::kRegistering;
  set_status(ScanState::kIntegrating, "registering and mapping " + view_name(), now_s);
  progress("registering");
  t_step_s_ = now_s;
  wait_for_answer(now_s + t_.answer_s, now_s);
  if (registered_) registered(now_s);
}

void ScanSequencer::registered(double now_s) {
  view_.registration = registered_;
  view_.register_round_trip_s = now_s - t_step_s_;
  begin_map(now_s);
}

void ScanSequencer::begin_map(double now_s) {
  phase_ = Phase::kMapping;
  progress("mapping");
  t_step_s_ = now_s;
  wait_for_answer(now_s + t_.answer_s, now_s);
  if (map_) mapped(now_s);
}

void ScanSequencer::mapped(double now_s) {
  take_map(*map_, now_s);
  if (!registered_) return defer_registration(now_s);
  view_.view_total_s = now_s - t_view_s_;
  record_registered(view_, *registered_, now_s);
  if (stopped_by_rule(iteration_, now_s)) return;
  next_view(now_s);
}

bool ScanSequencer::stopped_by_rule(int view, double now_s) {
  if (replay_ || view + 1 >= s_.views) return false;
  std::optional<ScanStop> stop = rule_stop(s_, record_.record().views, done_.views_done);
  if (!stop) return false;
  stop_ = std::move(stop);
  record_.set_stop(*stop_);
  finish(ScanState::kDone, "scan complete: " + stop_->reason, now_s);
  return true;
}

void ScanSequencer::next_view(double now_s) {
  if (iteration_ + 1 < s_.views) return begin_view(iteration_ + 1, now_s);
  if (deferred_) {  // the last view's registration first
    held_next_view_ = true;
    return await_registration(now_s);
  }
  if (done_.views_done == 0) return finish(ScanState::kFailed, "no view produced a cloud", now_s);
  if (replay_) {
    stop_ = ScanStop{"the recording's " + std::to_string(s_.views) + " views replayed", done_.views_done, "replay", {}};
    record_.set_stop(*stop_);
    return finish(ScanState::kDone, "replay complete: " + stop_->reason, now_s);
  }
  stop_ = ScanStop{"view budget reached (--views " + std::to_string(s_.views) + ")", done_.views_done, "budget", {}};
  record_.set_stop(*stop_);
  finish(ScanState::kDone, "scan complete: " + stop_->reason, now_s);
}

void ScanSequencer::fail_view(const std::string& message, double now_s) {
  flush_deferred(now_s);  // recorded in order
  record_.add_view(view_, done_.views_done, now_s - t_start_s_);
  finish(ScanState::kFailed, message, now_s);
}

void ScanSequencer::finish(ScanState state, const std::string& message, double now_s) {
  if (deferred_) {
    if (state == ScanState::kDone) {  // done once the last view is recorded
      held_finish_ = HeldFinish{state, message};
      return await_registration(now_s);
    }
    flush_deferred(now_s);
  }
  if (rig_wait_) end_rig_wait(now_s - rig_wait_->since_s);  // the scan no longer uses the rig
  // A scan that is done gets its surface mesh first (a resumed scan and an external rig's too:
  // they end here).
  if (state == ScanState::kDone && phase_ != Phase::kMeshing) return begin_mesh(message, now_s);
  conclude(state, message, now_s);
}

void ScanSequencer::begin_mesh(const std::string& message, double now_s) {
  phase_ = Phase::kMeshing;
  done_message_ = message;
  MeshRequest r;
  r.scan_id = s_.scan_id;
  r.request_id = next_request_id();
  for (const ViewRecord& v : record_.record().views) {
    if (v.registration && v.registration->accepted && !v.registration->frame_file.empty()) r.views.push_back(v.view);
  }
  if (r.views.empty()) return meshed(std::nullopt, "no view was merged into the model: nothing to mesh", now_s);
  r.camera = s_.camera;
  r.point_spacing_m = s_.voxel_m;
  set_status(ScanState::kIntegrating, "meshing the scan (" + std::to_string(r.views.size()) + " views)", now_s);
  outputs_.push_back(ProgressLine{"meshing " + std::to_string(r.views.size()) + " views", false});
  send(r, r.request_id, t_.resend_s, now_s + t_.mesh_s, now_s);
}

void ScanSequencer::meshed(const std::optional<MeshSummary>& m, const std::string& why_not, double now_s) {
  if (m) {
    record_.set_mesh(*m);
    outputs_.push_back(ProgressLine{"mesh.ply: " + std::to_string(m->triangles) + " triangles, " +
                                        (m->watertight ? std::string("watertight") : std::to_string(m->boundary_loops) + " holes") +
                                        ", " + fixed(m->seconds, 2) + " s",
                                    true});
  } else {
    record_.set_no_mesh(why_not);
    outputs_.push_back(ProgressLine{"no mesh: " + why_not, true});
  }
  conclude(ScanState::kDone, done_message_, now_s);
}

void ScanSequencer::conclude(ScanState state, const std::string& message, double now_s) {
  phase_ = Phase::kFinished;
  awaited_ = Awaited{};
  set_status(state, message, now_s);
  const char* name = state == ScanState::kDone ? "done" : state == ScanState::kStopped ? "stopped" : "failed";
  record_.write(name, message, done_.views_done, now_s - t_start_s_);
  const std::string rig_text = rig_time_summary(sum_rig_time(record_.record().views));
  summary_ = (state == ScanState::kDone ? "" : "scan ") + message + ": " + std::to_string(done_.views_done) + " of " +
             std::to_string(s_.views) + " views, " + std::to_string(record_.num_points()) + " points, " +
             fixed(now_s - t_start_s_, 2) + " s" + rig_text + " -> " + record_.scan_json_path().string();
}

void ScanSequencer::begin_rig_wait(double since_s) { rig_wait_ = RigWait{record_.record().views.size(), since_s}; }

void ScanSequencer::end_rig_wait(double compute_s) {
  record_.set_compute_wait(rig_wait_->index, compute_s);
  rig_wait_.reset();
}

// ---- Output ----------------------------------------------------------------------------------

void ScanSequencer::send(const ScanOutput& request, int64_t request_id, double resend_s, double deadline_s, double now_s) {
  awaited_ = Awaited{request, request_id, now_s, now_s, resend_s, deadline_s, 1};
  outputs_.push_back(request);
}

void ScanSequencer::wait_for_answer(double deadline_s, double now_s) {
  // REGISTERED_CLOUD and VOXEL_MAP follow from the view's CLOUD: when one is late, the capture
  // request is sent again; the camera answers it again from its cache, the registration and the
  // mapping service answer the repeated CLOUD and REGISTERED_CLOUD from theirs, so a message lost
  // anywhere on that path is sent again.
  const int sent = awaited_.request_id == capture_id_ ? awaited_.sends : 0;  // counted on from the capture
  awaited_ = Awaited{capture_request_, capture_id_, now_s, now_s, t_.capture_resend_s, deadline_s, sent};
}

std::string ScanSequencer::waited(const std::string& from, const std::string& what, const std::string& request) const {
  return from + " sent no " + what + " for " + view_name() + " in " + fixed(awaited_.deadline_s - awaited_.since_s, 0) +
         " s (" + request + " sent " + std::to_string(awaited_.sends) + (awaited_.sends == 1 ? " time)" : " times)");
}

int64_t first_request_id() {
  std::random_device entropy;
  std::uniform_int_distribution<int64_t> pick(int64_t{1} << 32, kMaxRequestId - 1);
  return pick(entropy);
}

void ScanSequencer::refuse(const std::string& what, const std::string& why) {
  constexpr int kLogged = 20;
  ++done_.answers_refused;
  record_.set_answers_refused(done_.answers_refused);
  if (done_.answers_refused <= kLogged) {
    progress("refused a " + what + ": " + why + " (" + std::to_string(done_.answers_refused) + " refused so far" +
             (done_.answers_refused == kLogged ? "; the next ones are counted in scan.json, not logged)" : ")"));
  }
}

void ScanSequencer::progress(const std::string& what, bool ends_view) {
  outputs_.push_back(ProgressLine{"[view " + std::to_string(iteration_ + 1) + "/" + std::to_string(s_.views) + "] " + what, ends_view});
}

void ScanSequencer::set_status(ScanState state, const std::string& message, double now_s) {
  state_ = state;
  message_ = message;
  publish_status(now_s);
}

void ScanSequencer::publish_status(double now_s) {
  ScanStatus m;
  m.scan_id = s_.scan_id;
  m.iteration = iteration_;
  m.num_views_planned = s_.views;
  m.num_views_done = done_.views_done;
  m.state = state_;
  m.message = message_;
  m.elapsed_s = now_s - t_start_s_;
  m.num_points = static_cast<int>(record_.num_points());
  outputs_.push_back(m);
  last_status_s_ = now_s;
}

}  // namespace pbnbv
