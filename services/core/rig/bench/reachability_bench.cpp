// Inverse kinematics and reachability check throughput (models/rig_arm.xml, rig_free.xml).
#include <benchmark/benchmark.h>

#include <cmath>

#include "core/rig/rig.hpp"
#include "core/geometry/views.hpp"
#include "core/base/units.hpp"

namespace {

using namespace pbnbv;


const RigModel& arm_rig() {
  static const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
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

// Analytic IK of one flange pose (all solutions, verified by FK).
void BM_ArmInverseKinematics(benchmark::State& state) {
  const RigModel& rig = arm_rig();
  Vector6d q;
  q << 0.3, -0.9, 1.2, 0.4, 0.8, 0.5;
  const Pose target = flange_in_world(rig, q);
  size_t n = 0;
  for (auto _ : state) {
    auto sols = inverse_kinematics(rig, target);
    n = sols.size();
    benchmark::DoNotOptimize(sols);
  }
  state.counters["solutions"] = static_cast<double>(n);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ArmInverseKinematics);

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
