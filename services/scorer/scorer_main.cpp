// pbnbv-scorer: the view scorer (PB-NBV's next-best-view choice, and the benchmark's baselines).
//   in:  PLAN_REQUEST, VOXEL_MAP, ELLIPSOIDS
//   out: VIEW_PLAN, HEARTBEAT; with --out DIR (and --scan), a picture of each plan of that scan:
//        DIR/plans/view_NNN.png and .svg, NNN the request's view (iteration + 1). No path comes
//        from the bus: a request names its view, bounded (0..999), never a file.
// Answers each PLAN_REQUEST from the VOXEL_MAP (bounding box B) and ELLIPSOIDS of the request's
// map_iteration: candidates on the sphere around B, the rig's reachability check (arm rig: the
// same check as the motion executor's, on the same rig model), F of every candidate by ellipsoid
// projection, global partitioning, termination (core plan_pbnbv). The request's planner may also
// be a baseline on the same candidates and map: "raycast" (ray-casting information gain over the
// VOXEL_MAP's cells, core plan_raycast) or "random" (core plan_random); those need no ELLIPSOIDS.
// "oracle" (core plan_oracle, the benchmark's yardstick) chooses by the object's true surface:
// only when started with --truth-mesh (the launcher passes it for a twin scan with --planner oracle).
// The request carries the scan's
// history, so the scorer keeps no scan state: restarted, it answers the next request the same.
// Reachability runs as soon as B is known, while the ellipsoid fitter is still working.
#include <chrono>
#include <cmath>
#include <deque>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "bus/bus.hpp"
#include "bus/convert.hpp"
#include "bus/convert_planning.hpp"
#include "bus/reply_cache.hpp"
#include "bus/rig_options.hpp"
#include "bus/service.hpp"
#include "core/base/format.hpp"
#include "core/base/log.hpp"
#include "core/base/parallel.hpp"
#include "core/io/mesh_file.hpp"
#include "core/planning/planner.hpp"
#include "core/scan/scan_options.hpp"
#include "report/plan_figure.hpp"
#include "core/rig/rig.hpp"
#include "pbnbv/ellipsoid_set_t.hpp"
#include "pbnbv/plan_request_t.hpp"
#include "pbnbv/view_plan_t.hpp"
#include "pbnbv/voxel_set_t.hpp"

using namespace pbnbv;

namespace {

constexpr double kInputWaitS = 60.0;   // give up on a map / ellipsoids that never come
constexpr std::size_t kAnswersKept = 64;
constexpr std::size_t kCandidatesPerWorker = 16;  // reachability: below this another worker does not pay

// The object's true surface, for the oracle.
struct Truth {
  TriangleMesh mesh;
  SurfaceSamples samples;
};

// Where the plan figure of view `iteration` (0-based) of the scan in `out` goes: plans/view_NNN.png.
std::filesystem::path plan_figure_file(const std::filesystem::path& out, int iteration) {
  return out / "plans" / view_file(iteration, "png");
}

class ScorerService {
 public:
  // `figures_out`: the scan's folder, where plans/ receives a figure per plan ("": none).
  ScorerService(bus::Bus& bus, const RigModel& rig, std::optional<Truth> truth, std::filesystem::path figures_out)
      : bus_(bus), rig_(rig), truth_(std::move(truth)), figures_out_(std::move(figures_out)) {
    bus_.subscribe<voxel_set_t>(channels::kVoxelMap, [this](const voxel_set_t& m) { maps_.offer(m); });
    bus_.subscribe<ellipsoid_set_t>(channels::kEllipsoids, [this](const ellipsoid_set_t& e) { ellipsoids_.offer(e); });
    bus_.subscribe<plan_request_t>(channels::kPlanRequest, [this](const plan_request_t& r) { on_request(r); });
  }

  void tick() {
    if (!pending_) return;
    const plan_request_t& r = pending_->request;
    const voxel_set_t* map = maps_.find(r.scan_id, r.map_iteration, r.map_request_id);
    const bool needs_ellipsoids = uses_ellipsoids(pending_->planner);
    const ellipsoid_set_t* ell = needs_ellipsoids ? ellipsoids_.find(r.scan_id, r.map_iteration, r.map_request_id) : nullptr;
    if (map && !pending_->move_time_s && r.check_reachability) {
      try {
        pending_->move_time_s = reachability(r, *map);
      } catch (const std::exception& e) {  // from any worker of the check: this request fails
        fail(std::string("reachability check failed: ") + e.what());
        return;
      }
    }
    if (map && (ell || !needs_ellipsoids)) {
      answer(*map, ell);
    } else if (bus::now_s() > pending_->deadline_s) {
      std::string missing = map ? "" : "VOXEL_MAP";
      if (needs_ellipsoids && !ell) missing += std::string(missing.empty() ? "" : " or ") + "ELLIPSOIDS";
      fail("no " + missing + " for view " + std::to_string(r.map_iteration) + " within " + std::to_string(static_cast<int>(kInputWaitS)) + " s");
    }
  }

 private:
  struct Pending {
    plan_request_t request;
    PlannerKind planner = PlannerKind::kPbnbv;  // request.planner, parsed
    PlanInput input;
    double received_s = 0;
    double deadline_s = 0;
    // Per candidate, the rig's time to reach it from the request's rig state (core/rig move_s),
    // NaN where it is unreachable; none before the check (or without one: the free rig).
    std::optional<std::vector<double>> move_time_s;
    double reachability_s = 0;
    RaycastParams raycast;  // planner "raycast"
    VisibilityParams visibility;  // planner "oracle"
  };

  void on_request(const plan_request_t& r) {
    bus_.set_scan(r.scan_id, r.iteration);
    const auto key = std::make_pair(r.scan_id, r.request_id);
    if (const view_plan_t* answer = answers_.find(key)) {
      bus_.publish(channels::kViewPlan, *answer);  // a repeat: answer again
      return;
    }
    if (pending_ && pending_->request.scan_id == r.scan_id && pending_->request.request_id == r.request_id) return;
    std::optional<PlannerKind> planner;
    try {
      planner = bus::planner_from_msg(r.planner, "PLAN_REQUEST planner");
    } catch (const std::invalid_argument& e) {
      view_plan_t out = bus::empty_answer(r);
      out.outcome = view_plan_t::kFailed;
      out.reason = std::string(e.what()) + ": pbnbv-scorer serves pbnbv, pbnbv-paper, raycast, random and oracle";
      publish(out);
      return;
    }
    if (uses_truth(*planner) && !truth_) {
      view_plan_t out = bus::empty_answer(r);
      out.outcome = view_plan_t::kFailed;
      out.reason = "planner 'oracle' needs the object's true mesh: this pbnbv-scorer was started without --truth-mesh "
                   "(twin scans only)";
      publish(out);
      return;
    }
    Pending p;
    p.request = r;
    p.planner = *planner;
    try {
      // The view to plan names the figure's file: bounded as the scan's view budget is.
      bus::require_range(r.iteration, 0, kViews.max - 1, "PLAN_REQUEST iteration");
      p.input = bus::plan_input_from_msg(r);
      if (r.check_reachability) {
        bus::to_vector6(std::vector<double>(r.joint_position_rad, r.joint_position_rad + 6), "PLAN_REQUEST joint_position_rad");
        bus::require_range(r.turntable_angle_rad, -1e3, 1e3, "PLAN_REQUEST turntable_angle_rad");
        bus::require_range(r.object_z_m, -10, 10, "PLAN_REQUEST object_z_m");
      }
      p.raycast.camera = p.visibility.camera = p.input.camera;
      p.raycast.range = p.visibility.range = p.input.depth_range;
    } catch (const std::exception& e) {
      view_plan_t out = bus::empty_answer(r);
      out.outcome = view_plan_t::kFailed;
      out.reason = std::string("bad request: ") + e.what();
      publish(out);
      throw;  // counted and logged as a rejected message
    }
    if (pending_) fail("superseded by request " + std::to_string(r.request_id));
    p.received_s = bus::now_s();
    p.deadline_s = p.received_s + kInputWaitS;
    pending_ = std::move(p);
    tick();
  }

  // The reachability of every candidate for B of this map, on the workers of core/base/parallel.hpp
  // (one MuJoCo checker each: a checker is not thread-safe).
  // Returns each candidate's move time, NaN where it is unreachable.
  std::vector<double> reachability(const plan_request_t& r, const voxel_set_t& map) {
    const auto t0 = std::chrono::steady_clock::now();
    const Eigen::AlignedBox3d box = bus::bbox_of(map);
    const std::vector<Pose> cands = candidate_views(box, pending_->input.candidates);
    // A request asked again (its answer lost), or planned again from the same rig state after a
    // view could not be taken: the same candidates from the same state, the same answer.
    const std::string key = bus::reachability_key(r, box);
    if (key == reach_key_) {
      pending_->reachability_s = 0;
      return reach_cache_;
    }
    reach_solutions_.assign(cands.size(), RigState{});
    paths_.clear();
    Vector6d q;
    for (int k = 0; k < 6; ++k) q[k] = r.joint_position_rad[k];
    const Eigen::AlignedBox3d keepout(Eigen::Map<const Eigen::Vector3d>(r.keepout_min_m),
                                      Eigen::Map<const Eigen::Vector3d>(r.keepout_max_m));
    // Each candidate is solved on its own (same current state), so the answer does not depend on
    // how the candidates are shared out. One byte per candidate: workers never write the same
    // byte (a std::vector<bool> packs eight candidates into one).
    const int workers = worker_count(cands.size(), kCandidatesPerWorker);
    while (checkers_.size() < static_cast<std::size_t>(workers)) checkers_.push_back(std::make_unique<ReachabilityChecker>(rig_));
    std::vector<double> times(cands.size(), std::numeric_limits<double>::quiet_NaN());
    const RigState from{q, r.turntable_angle_rad};
    const TurntableChoice choice = bus::turntable_choice_from_msg(r.turntable_choice, "PLAN_REQUEST turntable_choice");
    parallel_for(cands.size(), [&](std::size_t begin, std::size_t end, int w) {
      const std::vector<Pose> part(cands.begin() + begin, cands.begin() + end);
      checkers_[w]->set_turntable_choice(choice);
      const std::vector<ViewSolution> s = checkers_[w]->solve_batch(part, q, r.turntable_angle_rad, keepout, r.object_z_m);
      for (std::size_t i = 0; i < s.size(); ++i) {
        if (!s[i].reachable) continue;
        reach_solutions_[begin + i] = {s[i].q, s[i].turntable_rad};
        times[begin + i] = move_s(rig_, from, reach_solutions_[begin + i]);
      }
    }, kCandidatesPerWorker, workers);
    pending_->reachability_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    reach_key_ = key;
    reach_cache_ = times;
    reach_from_ = from;
    reach_keepout_ = keepout;
    reach_object_z_m_ = r.object_z_m;
    return times;
  }

  // Candidate i's path from where the rig stood at the last reachability check (its solution
  // there): its direct move's time when that move is clear along its whole path, else the time of
  // a detour via home (the motion executor plans the quickest clear detour when it moves: via home
  // is what it takes most often, and checking every detour here would cost a plan 10 times the
  // direct check). Kept until the next check.
  CandidatePath candidate_path(int i) {
    if (const auto it = paths_.find(i); it != paths_.end()) return it->second;
    const RigState& to = reach_solutions_.at(static_cast<std::size_t>(i));
    const std::string hit = checkers_.front()->path_collision(reach_from_, to, reach_keepout_, reach_object_z_m_);
    if (hit.empty()) return paths_[i] = CandidatePath{true, move_s(rig_, reach_from_, to), "direct"};
    return paths_[i] = CandidatePath{true, path_s(rig_, reach_from_, {{rig_.q_home, to.turntable_rad}, to}),
                                     "a detour: the direct move hits " + hit};
  }

  void answer(const voxel_set_t& map, const ellipsoid_set_t* ell) {
    Pending p = std::move(*pending_);
    pending_.reset();
    const plan_request_t& r = p.request;
    const double wait_s = bus::now_s() - p.received_s;
    view_plan_t out = bus::empty_answer(r);
    PlanResult result;
    std::optional<VoxelGrid> grid;  // ours (pbnbv): the combined ranking's rays go through the map
    try {
      p.input.bbox = bus::bbox_of(map);
      for (std::size_t i = 0; ell && i < ell->ellipsoids.size(); ++i) {
        p.input.ellipsoids.push_back(bus::from_msg(ell->ellipsoids[i], "ELLIPSOIDS ellipsoids[" + std::to_string(i) + "]"));
      }
      if (p.move_time_s) {
        std::vector<bool> cached(p.move_time_s->size());
        for (std::size_t i = 0; i < cached.size(); ++i) cached[i] = !std::isnan((*p.move_time_s)[i]);
        p.input.reachable = [cached](const std::vector<Pose>& c) {
          if (c.size() != cached.size()) throw std::logic_error("candidate set changed after the reachability check");
          return cached;
        };
      }
      const double t0 = bus::now_s();
      // The heartbeat between chunks of a long plan (ray casting at fine resolutions, the
      // oracle on a large mesh), so the launcher does not take the scorer for hung.
      p.input.progress = [this] { bus_.keep_alive(); };
      if (p.planner == PlannerKind::kRaycast) {
        result = plan_raycast(p.input, bus::grid_from_msg(map), p.raycast);
      } else if (p.planner == PlannerKind::kRandom) {
        result = plan_random(p.input, static_cast<uint64_t>(r.seed));
      } else if (p.planner == PlannerKind::kOracle) {
        result = plan_oracle(p.input, truth_->mesh, truth_->samples, p.visibility);
      } else {
        if (combined_ranking(p.planner)) {
          p.input.grid = &grid.emplace(bus::grid_from_msg(map));
          // Motion-aware (the scan's --motion): the rig's time to each candidate weighs against it.
          if (r.seconds_per_point > 0 && p.move_time_s) {
            p.input.move_time_s = *p.move_time_s;
            p.input.path = [this](int i) { return candidate_path(i); };  // a detour's time, asked for the best
          }
        }
        result = plan_pbnbv(p.input);
      }
      bus::fill_answer(out, result);
      out.reachability_s = p.reachability_s;
      out.wait_s = wait_s;
      out.plan_s = bus::now_s() - t0 + p.reachability_s;
    } catch (const std::exception& e) {
      out.outcome = view_plan_t::kFailed;
      out.reason = e.what();
    }
    publish(out);
    // Only for the scan this scorer serves (the bus drops other scans' requests before this; checked
    // again here because it decides where a file is written).
    if (!figures_out_.empty() && r.scan_id == bus_.scope() && !result.candidates.empty()) {
      try {
        std::ostringstream title;
        title << name_of(p.planner) << ": view " << r.iteration + 1 << " - planned from the map of view " << r.map_iteration + 1;
        if (ell) title << " - T occupied " << ell->occupied_components << ", T frontier " << ell->frontier_components;
        PlanFigure figure = plan_figure(p.input, result, title.str());
        if (p.planner == PlannerKind::kRaycast) figure.quality_label = "unobserved voxels each scored candidate's rays reach";
        if (p.planner == PlannerKind::kRandom) figure.quality_label = "random choice (no score)";
        if (p.planner == PlannerKind::kOracle) figure.quality_label = "true surface samples each candidate sees that no view taken saw";
        const std::filesystem::path file = plan_figure_file(figures_out_, r.iteration);
        std::filesystem::create_directories(file.parent_path());
        write_plan_figure(figure, file.string());
      } catch (const std::exception& e) {
        bus_.note_error(std::string("figure not written: ") + e.what());
      }
    }
  }

  void fail(const std::string& why) {
    view_plan_t out = bus::empty_answer(pending_->request);
    pending_.reset();
    out.outcome = view_plan_t::kFailed;
    out.reason = why;
    publish(out);
  }

  void publish(view_plan_t& out) {
    out.utime = bus::now_utime();
    bus_.publish(channels::kViewPlan, out);
    answers_.put({out.scan_id, out.request_id}, out);
    std::ostringstream os;
    os << "view " << out.iteration << " (request " << out.request_id << "): "
       << (out.outcome == view_plan_t::kView ? "" : out.outcome == view_plan_t::kStop ? "stop: " : "failed: ") << out.reason;
    if (out.outcome == view_plan_t::kView) {
      os << "; " << out.num_unreachable << " of " << out.num_candidates << " unreachable; reachability "
         << out.reachability_s * 1e3 << " ms, scoring " << out.scoring_s * 1e3 << " ms";
    }
    (out.outcome == view_plan_t::kFailed ? log_warn : log_info)(os.str());
  }

  bus::Bus& bus_;
  RigModel rig_;
  std::optional<Truth> truth_;  // --truth-mesh: the oracle's
  std::filesystem::path figures_out_;  // --out: plans/ of this scan's folder ("": no figures)
  std::vector<std::unique_ptr<ReachabilityChecker>> checkers_;  // one per worker, made on first use
  bus::RecentPerScan<voxel_set_t> maps_;
  bus::RecentPerScan<ellipsoid_set_t> ellipsoids_;
  std::optional<Pending> pending_;
  std::string reach_key_;                 // the candidate set of the last reachability check
  std::vector<double> reach_cache_;        // its answer: each candidate's move time, NaN unreachable
  std::vector<RigState> reach_solutions_;  // and each reachable candidate's rig state there
  RigState reach_from_;                    // where the rig stood
  Eigen::AlignedBox3d reach_keepout_;
  double reach_object_z_m_ = 0;
  std::map<int, CandidatePath> paths_;     // the paths asked for since (candidate_path)
  bus::ReplyCache<std::pair<std::string, int64_t>, view_plan_t> answers_{kAnswersKept};
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbnbv-scorer: answers each PLAN_REQUEST with the next view (PB-NBV or a baseline) and its "
               "alternatives, checking the rig can reach them",
               "pbnbv-scorer"};
  cli::init(app);
  bus::RigOptions rig_options;
  bus::add_rig_options(app, &rig_options);
  std::string truth_mesh;
  cli::add_text(app, "truth-mesh", &truth_mesh,
                "the object's true mesh in the object frame (a twin scan's object.stl), for --planner oracle only: "
                "the benchmark's yardstick, never a real scan",
                "PATH");
  std::string out;
  cli::add_text(app, "out", &out,
                "the scan's folder: a figure of each plan of the scan --scan names goes to DIR/plans/view_NNN.png "
                "(and .svg); none without it",
                "DIR");
  int truth_samples = kOracleSamples.value;
  cli::add(app, kOracleSamples, &truth_samples);
  // Checked once the command line is read (run_service adds --scan), before the bus starts.
  app.callback([&] {
    if (out.empty()) return;
    if (app.get_option("--scan")->count() == 0) {
      throw std::invalid_argument("--out " + out + " needs --scan ID: the figures in " + out +
                                  "/plans are those of the one scan this scorer serves");
    }
    if (!std::filesystem::is_directory(out)) {
      throw std::invalid_argument("--out " + out + " is not a folder (the scan's folder, made by the launcher)");
    }
  });
  return bus::run_service("scorer", app, argc, argv, 5, [&](bus::Bus& bus) -> std::function<void()> {
    const RigModel rig = bus::load_rig(rig_options);
    std::optional<Truth> truth;
    if (!truth_mesh.empty()) {
      truth.emplace();
      truth->mesh = load_mesh(truth_mesh);
      truth->samples = sample_surface_with_normals(truth->mesh, static_cast<std::size_t>(truth_samples), kOracleSeed);
      log_info("true mesh " + truth_mesh + ": " + std::to_string(truth->mesh.triangles.size()) + " triangles, " +
               std::to_string(truth->samples.points.size()) + " surface samples (the oracle's)");
    }
    auto service = std::make_shared<ScorerService>(bus, rig, std::move(truth), out);
    log_info("ready");
    return [service] { service->tick(); };
  });
}
