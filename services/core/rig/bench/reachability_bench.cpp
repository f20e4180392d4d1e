// Inverse kinematics and reachability check throughput (models/rig_arm.xml, rig_ur5e.xml,
// rig_free.xml): the analytic IK of the KUKA and the parallel-axes one of the UR5e, each beside
// the general IK forced on the same arm.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>

#include "core/rig/rig.hpp"
#include "core/geometry/views.hpp"
#include "core/base/parallel.hpp"
#include "core/base/units.hpp"

namespace {

using namespace pbnbv;


const RigModel& arm_rig() {
  static const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  return rig;
}

const RigModel& ur5e_rig() {
  static const RigModel rig = load_rig(model_file_path("rig_ur5e.xml"));
  return rig;
}

// `rig` with the general IK forced (for comparison with its closed form).
RigModel general(const RigModel& rig) {
  RigModel r = rig;
  r.ik = IkMethod::kGeneral;
  return r;
}
const RigModel& arm_rig_general() {
  static const RigModel rig = general(arm_rig());
  return rig;
}
const RigModel& ur5e_rig_general() {
  static const RigModel rig = general(ur5e_rig());
  return rig;
}

const RigModel& free_rig() {
  static const RigModel rig = load_rig(default_rig_path(RigKind::kFree));
  return rig;
}

Eigen::AlignedBox3d cube() {
  return Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-0.15), Eigen::Vector3d::Constant(0.15));
}

std::vector<Pose> hemisphere() {
  const double r = 0.6 + 0.5 * std::sqrt(3.0) * 0.3;
  return sphere_band_views(800, 24, r, Eigen::Vector3d::Zero(), 0, kPi / 2);
}

// What a scan of a large object asks (the bear's fourth plan on the UR5e): its map's box,
// 0.72 x 0.42 x 0.84 m, and the 800 candidates on a sphere of 1.19 m around it, of which the
// arm reaches about 80 %: the unreachable ones cost the most.
Eigen::AlignedBox3d large_box() {
  return Eigen::AlignedBox3d(Eigen::Vector3d(-0.36, -0.21, -0.39), Eigen::Vector3d(0.36, 0.21, 0.45));
}
std::vector<Pose> far_hemisphere() {
  return sphere_band_views(800, 24, 1.19, Eigen::Vector3d(0, 0, 0.03), 0, kPi / 2);
}

// Closed-form IK of one flange pose (all solutions, verified by FK): the KUKA's spherical wrist,
// the UR5e's parallel axes.
void BM_ArmInverseKinematics(benchmark::State& state, const RigModel* rig) {
  Vector6d q;
  q << 0.3, -0.9, 1.2, 0.4, 0.8, 0.5;
  const Pose target = flange_in_world(*rig, q);
  size_t n = 0;
  for (auto _ : state) {
    auto sols = inverse_kinematics(*rig, target);
    n = sols.size();
    benchmark::DoNotOptimize(sols);
  }
  state.counters["solutions"] = static_cast<double>(n);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_ArmInverseKinematics, kuka_analytic, &arm_rig());
BENCHMARK_CAPTURE(BM_ArmInverseKinematics, ur5e_parallel_axes, &ur5e_rig());

// All solutions of one flange pose (full search: reference, home, 32 spread seeds).
void BM_GeneralInverseKinematics(benchmark::State& state, const RigModel* rig) {
  Vector6d q;
  q << 0.3, -0.9, 1.2, 0.4, 0.8, 0.5;
  const Pose target = flange_in_world(*rig, q);
  size_t n = 0;
  for (auto _ : state) {
    auto sols = inverse_kinematics(*rig, target);
    n = sols.size();
    benchmark::DoNotOptimize(sols);
  }
  state.counters["solutions"] = static_cast<double>(n);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_GeneralInverseKinematics, kuka, &arm_rig_general());
BENCHMARK_CAPTURE(BM_GeneralInverseKinematics, ur5e, &ur5e_rig_general());

// One converged solve from a seed 0.1 rad away (what the reachability check does per candidate
// when the neighbouring candidate's solution seeds it).
void BM_GeneralIkFromNearSeed(benchmark::State& state, const RigModel* rig) {
  Vector6d q;
  q << 0.3, -0.9, 1.2, 0.4, 0.8, 0.5;
  const Pose target = flange_in_world(*rig, q);
  const Vector6d seed = q + Vector6d::Constant(0.1);
  Vector6d sol;
  for (auto _ : state) {
    benchmark::DoNotOptimize(general_ik_from_seed(*rig, target, seed, &sol));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_GeneralIkFromNearSeed, kuka, &arm_rig_general());
BENCHMARK_CAPTURE(BM_GeneralIkFromNearSeed, ur5e, &ur5e_rig_general());

void BM_ArmForwardKinematics(benchmark::State& state) {
  const RigModel& rig = arm_rig();
  Vector6d q;
  q << 0.3, -0.9, 1.2, 0.4, 0.8, 0.5;
  for (auto _ : state) {
    benchmark::DoNotOptimize(camera_in_world(rig, q));
    q[0] += 1e-9;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ArmForwardKinematics);

// The planner's candidate set: 800 hemisphere views, each split into turntable angle + arm
// configuration with IK, limits, collision and line-of-sight checks.
void BM_ArmSolveBatchHemisphere(benchmark::State& state) {
  const RigModel& rig = arm_rig();
  ReachabilityChecker checker(rig);
  const std::vector<Pose> views = hemisphere();
  int reachable = 0;
  for (auto _ : state) {
    const auto sols = checker.solve_batch(views, rig.q_home, 0.0, cube(), 0.15);
    reachable = 0;
    for (const auto& s : sols) reachable += s.reachable;
    benchmark::DoNotOptimize(reachable);
  }
  state.counters["reachable"] = reachable;
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(views.size()));
}
BENCHMARK(BM_ArmSolveBatchHemisphere)->Unit(benchmark::kMillisecond);

// The view scorer's reachability step: the 800 hemisphere candidates shared out over
// range(0) workers (parallel_for in chunks of 16, one checker per worker, as in
// services/scorer), side by side for each arm with its closed-form IK and with the general IK
// forced. Checkers are built once, as the scorer keeps them.
void reachability_800(benchmark::State& state, const RigModel* rig, const std::vector<Pose>& views,
                      const Eigen::AlignedBox3d& box, TurntableChoice choice = TurntableChoice::kPreferred) {
  const int workers = static_cast<int>(state.range(0));
  std::vector<std::unique_ptr<ReachabilityChecker>> checkers;
  for (int w = 0; w < workers; ++w) checkers.push_back(std::make_unique<ReachabilityChecker>(*rig, choice));
  std::vector<uint8_t> reachable(views.size(), 0);
  for (auto _ : state) {
    parallel_for(views.size(), [&](std::size_t begin, std::size_t end, int w) {
      const std::vector<Pose> part(views.begin() + begin, views.begin() + end);
      const auto sols = checkers[w]->solve_batch(part, rig->q_home, 0.0, box, -box.min().z());
      for (std::size_t i = 0; i < sols.size(); ++i) reachable[begin + i] = sols[i].reachable ? 1 : 0;
    }, 16, workers);
    benchmark::DoNotOptimize(reachable);
  }
  int n = 0;
  for (uint8_t r : reachable) n += r;
  state.counters["reachable"] = n;
  state.counters["workers"] = workers;
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(views.size()));
}
void BM_Reachability800(benchmark::State& state, const RigModel* rig) {
  reachability_800(state, rig, hemisphere(), cube());
}
// The same for the large object's candidates (about a fifth unreachable).
void BM_Reachability800Large(benchmark::State& state, const RigModel* rig) {
  reachability_800(state, rig, far_hemisphere(), large_box());
}
// The same 800 hemisphere candidates with each turntable rule (TurntableChoice), one worker: the
// preferred azimuth (plain), the least turn, and the quickest move (the motion-aware default),
// which goes on past the least turn where the arm is the slower part of the move.
void BM_Reachability800Rule(benchmark::State& state, const RigModel* rig, TurntableChoice choice) {
  reachability_800(state, rig, hemisphere(), cube(), choice);
}
BENCHMARK_CAPTURE(BM_Reachability800Rule, kuka_preferred, &arm_rig(), TurntableChoice::kPreferred)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Reachability800Rule, kuka_least_turn, &arm_rig(), TurntableChoice::kLeastTurn)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Reachability800Rule, kuka_quickest, &arm_rig(), TurntableChoice::kQuickest)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Reachability800Rule, ur5e_preferred, &ur5e_rig(), TurntableChoice::kPreferred)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Reachability800Rule, ur5e_least_turn, &ur5e_rig(), TurntableChoice::kLeastTurn)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Reachability800Rule, ur5e_quickest, &ur5e_rig(), TurntableChoice::kQuickest)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_CAPTURE(BM_Reachability800Large, kuka_analytic, &arm_rig())->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Reachability800Large, ur5e_parallel_axes, &ur5e_rig())->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Reachability800Large, ur5e_general, &ur5e_rig_general())->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Reachability800, kuka_analytic, &arm_rig())->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Reachability800, kuka_general, &arm_rig_general())->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Reachability800, ur5e_parallel_axes, &ur5e_rig())->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Reachability800, ur5e_general, &ur5e_rig_general())->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_FreeSolveBatchHemisphere(benchmark::State& state) {
  const RigModel& rig = free_rig();
  ReachabilityChecker checker(rig);
  const std::vector<Pose> views = hemisphere();
  for (auto _ : state) {
    benchmark::DoNotOptimize(checker.solve_batch(views, rig.q_home, 0.0, cube(), 0.0));
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(views.size()));
}
BENCHMARK(BM_FreeSolveBatchHemisphere)->Unit(benchmark::kMillisecond);

}  // namespace
