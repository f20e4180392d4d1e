// Frame-to-model registration at scanning sizes: a ~30k-point frame against a ~100k-point model
// (counts after the 2 mm downsampling register_frame does), the frame 5 mm / 1 deg off.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <unordered_map>
#include <vector>

#include "core/geometry/point_cloud.hpp"
#include "core/geometry/mesh.hpp"
#include "core/io/mesh_file.hpp"
#include "core/perception/cloud_filter.hpp"
#include "core/perception/registration.hpp"
#include "core/base/units.hpp"

namespace {

using pbnbv::PointCloud;
using pbnbv::Pose;
using pbnbv::TriangleMesh;
using pbnbv::kPi;
using pbnbv::rad_to_deg;
using pbnbv::rotation_angle_rad;


void add_part(TriangleMesh& mesh, const TriangleMesh& part, const Eigen::Vector3d& at) {
  const int base = static_cast<int>(mesh.vertices.size());
  for (const auto& v : part.vertices) mesh.vertices.push_back(v + at);
  for (const auto& t : part.triangles) mesh.triangles.push_back(t + Eigen::Vector3i::Constant(base));
}

// Samples with face normals; visible = facing `view` and not behind a nearer sample (z-buffer
// of 1.5 mm cells); 0.3 mm Gaussian noise.
PointCloud view_of(const TriangleMesh& m, size_t n, Eigen::Vector3d view, uint64_t seed) {
  std::vector<double> cum;
  double total = 0;
  for (const auto& t : m.triangles) {
    total += 0.5 * (m.vertices[t[1]] - m.vertices[t[0]])
                       .cross(m.vertices[t[2]] - m.vertices[t[0]])
                       .norm();
    cum.push_back(total);
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 0.0003);
  view.normalize();
  const Eigen::Vector3d ux = view.unitOrthogonal(), uy = view.cross(ux);
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> s;
  for (size_t i = 0; i < n; ++i) {
    const size_t k = std::min<size_t>(
        std::lower_bound(cum.begin(), cum.end(), u(rng) * total) - cum.begin(), cum.size() - 1);
    const auto& t = m.triangles[k];
    const auto &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
    double x = u(rng), y = u(rng);
    if (x + y > 1) x = 1 - x, y = 1 - y;
    s.emplace_back(a + x * (b - a) + y * (c - a), (b - a).cross(c - a).normalized());
  }
  auto key = [&](const Eigen::Vector3d& p) {
    return (static_cast<int64_t>(std::floor(p.dot(ux) / 0.0015)) + (1 << 20)) * (int64_t{1} << 22) +
           (static_cast<int64_t>(std::floor(p.dot(uy) / 0.0015)) + (1 << 20));
  };
  std::unordered_map<int64_t, double> zmin;
  for (const auto& [p, nrm] : s) {
    auto [it, fresh] = zmin.emplace(key(p), p.dot(view));
    if (!fresh) it->second = std::min(it->second, p.dot(view));
  }
  PointCloud out;
  for (const auto& [p, nrm] : s) {
    if (nrm.dot(view) >= -0.05 || p.dot(view) > zmin[key(p)] + 0.002) continue;
    out.push_back((p + Eigen::Vector3d(g(rng), g(rng), g(rng))).cast<float>());
  }
  return out;
}

Eigen::Vector3d dir(double az_deg, double el_deg) {
  const double az = az_deg * kPi / 180, el = el_deg * kPi / 180;
  return -Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
}

struct Clouds {
  PointCloud model, frame;
  std::size_t model_ds = 0, frame_ds = 0;
  Pose perturbation = Pose::Identity();
};

// A non-symmetric object ~0.28 m across: several boxes and a ball. The model is eight views
// around it (~100k points after 2 mm downsampling), the frame one more view (~35k), moved
// 5 mm / 1 deg.
const Clouds& clouds() {
  static const Clouds c = [] {
    TriangleMesh m;
    const double k = 0.56;
    add_part(m, pbnbv::make_box(k * Eigen::Vector3d(0.50, 0.30, 0.10)), k * Eigen::Vector3d(0.0, 0.0, -0.10));
    add_part(m, pbnbv::make_box(k * Eigen::Vector3d(0.12, 0.30, 0.35)), k * Eigen::Vector3d(-0.19, 0.0, 0.125));
    add_part(m, pbnbv::make_box(k * Eigen::Vector3d(0.10, 0.08, 0.12)), k * Eigen::Vector3d(0.15, -0.08, 0.01));
    add_part(m, pbnbv::make_icosphere(k * 0.09, 4), k * Eigen::Vector3d(0.08, 0.06, 0.04));
    Clouds out;
    for (int v_i = 0; v_i < 8; ++v_i) {
      const PointCloud v = view_of(m, 400000, dir(45.0 * v_i, v_i % 2 ? 65 : 25), 10 + v_i);
      out.model.insert(out.model.end(), v.begin(), v.end());
    }
    out.frame = view_of(m, 400000, dir(20, 45), 99);
    Pose p = Pose::Identity();
    p.linear() = Eigen::AngleAxisd(kPi / 180, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    p.translation() = 0.005 * Eigen::Vector3d(0.6, -0.8, 0.0);
    out.frame = pbnbv::transform_cloud(out.frame, p);
    out.perturbation = p;
    out.model_ds = pbnbv::voxel_downsample(out.model, 0.002).size();
    out.frame_ds = pbnbv::voxel_downsample(out.frame, 0.002).size();
    return out;
  }();
  return c;
}

// The frames are off by 5 mm and 1 deg: a prior that allows it, so ICP's correction is taken.
pbnbv::RegistrationParams perturbed_prior() {
  pbnbv::RegistrationParams p;
  p.prior_translation_m = 0.005;
  p.prior_rotation_deg = 1.0;
  return p;
}

void BM_RegisterFrame(benchmark::State& state) {
  const Clouds& c = clouds();
  pbnbv::RegistrationResult r;
  for (auto _ : state) {
    r = pbnbv::register_frame(c.model, c.frame, perturbed_prior());
    benchmark::DoNotOptimize(r);
  }
  state.counters["model_pts_ds"] = static_cast<double>(c.model_ds);
  state.counters["frame_pts_ds"] = static_cast<double>(c.frame_ds);
  state.counters["model_pts_raw"] = static_cast<double>(c.model.size());
  state.counters["frame_pts_raw"] = static_cast<double>(c.frame.size());
  const Pose err = r.correction * c.perturbation;
  state.counters["refined"] = r.refined;  // the correction was taken (every view is merged)
  state.counters["err_mm"] = err.translation().norm() * 1e3;
  state.counters["err_deg"] = rad_to_deg(rotation_angle_rad(Eigen::Matrix3d::Identity(), err.linear()));
  state.counters["iterations"] = r.iterations;
  state.counters["overlap"] = r.overlap;
}
BENCHMARK(BM_RegisterFrame)->Unit(benchmark::kMillisecond)->MinTime(3.0);

// The counters of an alignment of a frame moved by `perturbation`: taken, how far off, iterations.
void report_alignment(benchmark::State& state, const pbnbv::RegistrationResult& r, const Pose& perturbation) {
  const Pose err = r.correction * perturbation;
  state.counters["refined"] = r.refined;
  state.counters["err_mm"] = err.translation().norm() * 1e3;
  state.counters["err_deg"] = rad_to_deg(rotation_angle_rad(Eigen::Matrix3d::Identity(), err.linear()));
  state.counters["iterations"] = r.iterations;
}

// The same frame registered to the model prepared beforehand (registration_model: downsampled,
// normals fitted), as the registration service does once a view is answered, while the rig moves:
// what is left on the frame's way. And the preparing, side by side.
void BM_RegisterFramePrepared(benchmark::State& state) {
  const Clouds& c = clouds();
  const pbnbv::RegistrationParams params = perturbed_prior();
  static const pbnbv::RegistrationModel model = pbnbv::registration_model(c.model, params);
  pbnbv::RegistrationResult r;
  for (auto _ : state) {
    r = pbnbv::register_frame(model, c.frame, params);
    benchmark::DoNotOptimize(r);
  }
  report_alignment(state, r, c.perturbation);
}
BENCHMARK(BM_RegisterFramePrepared)->Unit(benchmark::kMillisecond)->MinTime(3.0);

void BM_PrepareModel(benchmark::State& state) {
  const Clouds& c = clouds();
  const pbnbv::RegistrationParams params = perturbed_prior();
  for (auto _ : state) {
    pbnbv::RegistrationModel m = pbnbv::registration_model(c.model, params);
    benchmark::DoNotOptimize(m.points.data());
  }
}
BENCHMARK(BM_PrepareModel)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// The same with ICP's voxel at range(0) tenths of a millimetre, side by side (2 mm until stop 47, 3 mm since).
void BM_RegisterFrameVoxel(benchmark::State& state) {
  const Clouds& c = clouds();
  pbnbv::RegistrationParams params = perturbed_prior();
  params.voxel_m = state.range(0) * 1e-4;
  pbnbv::RegistrationResult r;
  for (auto _ : state) {
    r = pbnbv::register_frame(c.model, c.frame, params);
    benchmark::DoNotOptimize(r);
  }
  report_alignment(state, r, c.perturbation);
}
BENCHMARK(BM_RegisterFrameVoxel)->Arg(20)->Arg(30)->Arg(40)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// The same frame pre-downsampled to 2 mm by the caller (the downsampling is then nearly free).
void BM_RegisterFramePredownsampled(benchmark::State& state) {
  const Clouds& c = clouds();
  static const PointCloud model = pbnbv::voxel_downsample(c.model, 0.002);
  static const PointCloud frame = pbnbv::voxel_downsample(c.frame, 0.002);
  pbnbv::RegistrationResult r;
  for (auto _ : state) {
    r = pbnbv::register_frame(model, frame, perturbed_prior());
    benchmark::DoNotOptimize(r);
  }
  state.counters["refined"] = r.refined;  // the correction was taken (every view is merged)
}
BENCHMARK(BM_RegisterFramePredownsampled)->Unit(benchmark::kMillisecond)->MinTime(3.0);

// The Stanford bunny if the data has been fetched (or PBNBV_BUNNY_OBJ names it): model = four
// views, frame = one between, 5 mm / 1 deg off.
void BM_RegisterFrameBunny(benchmark::State& state) {
  const char* env = std::getenv("PBNBV_BUNNY_OBJ");
  const std::string path = env ? env : std::string(PBNBV_DATA_DIR) + "/meshes/bunny.obj";
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    state.SkipWithError(("no " + path).c_str());
    return;
  }
  TriangleMesh m = pbnbv::load_mesh(path);
  pbnbv::normalise_mesh(m, 0.3, pbnbv::UpAxis::kY);
  PointCloud model;
  for (int k = 0; k < 4; ++k) {
    const PointCloud v = view_of(m, 1500000, dir(90.0 * k, 30), 20 + k);
    model.insert(model.end(), v.begin(), v.end());
  }
  Pose p = Pose::Identity();
  p.linear() = Eigen::AngleAxisd(kPi / 180, Eigen::Vector3d(3, -1, 2).normalized()).toRotationMatrix();
  p.translation() = 0.005 * Eigen::Vector3d(0.0, 0.6, 0.8);
  const PointCloud frame = pbnbv::transform_cloud(view_of(m, 1500000, dir(45, 50), 30), p);
  pbnbv::RegistrationResult r;
  for (auto _ : state) {
    r = pbnbv::register_frame(model, frame, perturbed_prior());
    benchmark::DoNotOptimize(r);
  }
  const Pose err = r.correction * p;
  state.counters["model_pts_ds"] = static_cast<double>(pbnbv::voxel_downsample(model, 0.002).size());
  state.counters["frame_pts_ds"] = static_cast<double>(pbnbv::voxel_downsample(frame, 0.002).size());
  state.counters["refined"] = r.refined;  // the correction was taken (every view is merged)
  state.counters["err_mm"] = err.translation().norm() * 1e3;
  state.counters["err_deg"] = rad_to_deg(rotation_angle_rad(Eigen::Matrix3d::Identity(), err.linear()));
}
BENCHMARK(BM_RegisterFrameBunny)->Unit(benchmark::kMillisecond)->MinTime(3.0);

}  // namespace
