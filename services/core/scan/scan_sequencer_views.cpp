// ScanSequencer's views as they are recorded: a view's map taken, a view recorded with its
// registration, and (map_pose rig) the view mapped before its registration answered, held until
// it does; and the views a scan knows before it has seen anything. The sequence itself:
// scan_sequencer.cpp.
#include <algorithm>
#include <cmath>

#include "core/base/format.hpp"
#include "core/base/units.hpp"
#include "core/geometry/views.hpp"
#include "core/scan/scan_sequencer.hpp"

namespace pbnbv {

std::vector<Pose> views_known_at_start(const ScanSettings& s) {
  const double radius = s.working_distance_m + (s.expected_extent_m() / 2.0).norm();
  const double elevation_rad = deg_to_rad(s.ring_elevation_deg);
  const double start_azimuth_rad = deg_to_rad(s.ring_start_azimuth_deg);
  if (s.planner == PlannerKind::kRing) {
    return ring_views(s.views, radius, elevation_rad, start_azimuth_rad, Eigen::Vector3d::Zero());
  }
  if (s.initial_view_m.allFinite()) return {look_at_z_up(s.initial_view_m, Eigen::Vector3d::Zero())};
  return ring_views(1, radius, elevation_rad, start_azimuth_rad, Eigen::Vector3d::Zero());
}

std::vector<Pose> first_view_options(const ScanSettings& s) {
  const Pose first = views_known_at_start(s).front();
  const Eigen::Vector3d eye = first.translation();
  const double radius = eye.norm();
  const double azimuth = std::atan2(eye.y(), eye.x());
  const double elevation = std::asin(std::clamp(eye.z() / radius, -1.0, 1.0));
  std::vector<Pose> options = {first};
  for (const double up_deg : {0.0, 20.0, -20.0}) {
    const double e = std::clamp(elevation + deg_to_rad(up_deg), deg_to_rad(-80.0), deg_to_rad(80.0));
    for (const double round_deg : {0.0, 45.0, -45.0, 90.0, -90.0, 135.0, -135.0, 180.0}) {
      if (up_deg == 0.0 && round_deg == 0.0) continue;  // the first view itself
      const double a = azimuth + deg_to_rad(round_deg);
      const Eigen::Vector3d p = radius * Eigen::Vector3d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
      options.push_back(look_at_z_up(p, Eigen::Vector3d::Zero()));
    }
  }
  return options;
}

void ScanSequencer::take_map(const VoxelMapSummary& m, double now_s) {
  done_.latest_map = iteration_;
  done_.latest_map_request = m.request_id;
  latest_map_summary_ = m;
  ellipsoids_.erase(ellipsoids_.begin(), ellipsoids_.lower_bound(done_.latest_map));
  view_.map = m;
  view_.map_round_trip_s = now_s - t_step_s_;
  if (m.updated) {
    done_.last_map = iteration_;
    // The registered pose; until the registration answers (map_pose rig), the rig's.
    done_.views_taken.push_back(registered_ ? registered_->cloud.object_T_camera : view_.capture->object_T_camera);
  } else {  // not mapped (e.g. registration rejected it): do not plan it again
    done_.excluded.push_back(moved_.reached_object_T_camera);
  }
}

void ScanSequencer::record_registered(ViewRecord& v, const RegisteredCloud& reg, double now_s) {
  v.registration = reg;
  record_.set_model_points(static_cast<std::size_t>(std::max(reg.model_points, 0)));
  ++done_.views_done;
  record_.add_view(v, done_.views_done, now_s - t_start_s_);
  const std::string verdict = !reg.accepted ? std::string("not merged")
                              : reg.flagged ? std::string("kinematic pose kept, flagged (alignment not trusted)")
                              : reg.refined ? "registered (" + fixed(reg.translation_m * 1e3, 2) + " mm, " +
                                                  fixed(reg.rotation_deg, 2) + " deg)"
                                            : std::string("kinematic pose kept");
  const VoxelMapSummary& m = *v.map;
  const double move_s = v.move ? v.move->move_s + v.move->settle_s : 0.0;
  std::string line = "done: " + std::to_string(v.capture_points) + " points, " +
                     std::to_string(record_.num_points()) + " in the model; " + verdict + ", " +
                     std::to_string(m.num_frontier) + " frontier voxels; move " + fixed(move_s, 2) + " s, capture " +
                     fixed(v.capture->capture_s, 2) + " s, register " + fixed(reg.register_s, 2) + " s, map " +
                     fixed(m.update_s * 1e3, 2) + " ms";
  if (v.plan) line += ", plan " + fixed(planner_step_ms(*v.plan), 2) + " ms";
  if (reg.new_surface) line += "; " + fixed(reg.new_surface->percent_of_model(), 2) + " % new surface";
  outputs_.push_back(ProgressLine{"[view " + std::to_string(v.view + 1) + "/" + std::to_string(s_.views) + "] " + line, true});
}

void ScanSequencer::defer_registration(double now_s) {
  Deferred d;
  d.view = view_;
  d.taken = done_.views_taken.size() - (view_.map->updated ? 1 : 0);
  d.capture_request = capture_request_;
  d.since_s = t_captured_s_;
  d.last_sent_s = awaited_.last_sent_s;
  d.sends = awaited_.sends;
  d.t_view_s = t_view_s_;
  deferred_ = std::move(d);
  progress("mapped; the registration refines it while the next view is planned");
  next_view(now_s);
}

void ScanSequencer::on_deferred(const RegisteredCloud& r, double now_s) {
  if (r.iteration != deferred_->view.view) {
    return refuse("REGISTERED_CLOUD of request " + std::to_string(r.request_id), "it is for view " + std::to_string(r.iteration + 1));
  }
  Deferred d = std::move(*deferred_);
  deferred_.reset();
  if (d.view.map->updated && d.taken < done_.views_taken.size()) done_.views_taken[d.taken] = r.cloud.object_T_camera;
  d.view.register_round_trip_s = now_s - d.since_s;
  d.view.view_total_s = now_s - d.t_view_s;
  record_registered(d.view, r, now_s);
  if (held_finish_) {  // the scan ends (the planner said stop, the budget is spent): as it said
    const HeldFinish h = *held_finish_;
    held_finish_.reset();
    return finish(h.state, h.message, now_s);
  }
  if (stopped_by_rule(d.view.view, now_s)) {  // what waited for the view is not done
    held_move_.reset();
    held_next_view_ = false;
    return;
  }
  if (phase_ != Phase::kAwaitingRegistration) return;
  // What waited for it goes on.
  if (held_move_) {
    const MoveResult m = *held_move_;
    held_move_.reset();
    phase_ = Phase::kMoving;
    return moved(m, now_s);  // the rig's wait since the move counts as compute (compute_wait_s)
  }
  if (held_next_view_) {
    held_next_view_ = false;
    return next_view(now_s);
  }
}

void ScanSequencer::await_registration(double now_s) {
  phase_ = Phase::kAwaitingRegistration;
  awaited_ = Awaited{};  // the deferred view's own deadline and re-sends (tick)
  const std::string what = "waiting for view " + std::to_string(deferred_->view.view + 1) + "'s registration";
  progress(what);
  set_status(ScanState::kIntegrating, what, now_s);
}

void ScanSequencer::flush_deferred(double now_s) {
  if (!deferred_) return;
  Deferred d = std::move(*deferred_);
  deferred_.reset();
  d.view.view_total_s = now_s - d.t_view_s;
  record_.add_view(d.view, done_.views_done, now_s - t_start_s_);
  held_move_.reset();
  held_finish_.reset();
  held_next_view_ = false;
}

}  // namespace pbnbv
