#include "core/perception/cloud_filter.hpp"
#include "core/perception/registration.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <unordered_map>
#include <vector>

#include "core/geometry/point_cloud.hpp"
#include "core/base/pose.hpp"
#include "core/geometry/mesh.hpp"
#include "core/base/units.hpp"

namespace pbnbv {
namespace {

double deg(double rad) { return rad * 180.0 / kPi; }
double rad(double d) { return d * kPi / 180.0; }

// Appends `part`, rotated by `r` and moved to `at`, to `mesh`.
void add_part(TriangleMesh& mesh, const TriangleMesh& part, const Eigen::Vector3d& at,
              const Eigen::Matrix3d& r = Eigen::Matrix3d::Identity()) {
  const int base = static_cast<int>(mesh.vertices.size());
  for (const auto& v : part.vertices) mesh.vertices.push_back(r * v + at);
  for (const auto& t : part.triangles) mesh.triangles.push_back(t + Eigen::Vector3i::Constant(base));
}

// A non-symmetric object about 0.2 m across, centred near the origin: an L of two boxes, a
// sphere on the foot and a small box turned 30 deg about z. Every rigid motion changes it.
TriangleMesh make_scene() {
  TriangleMesh m;
  add_part(m, make_box({0.20, 0.12, 0.05}), {0.0, 0.0, -0.05});          // foot
  add_part(m, make_box({0.05, 0.12, 0.14}), {-0.075, 0.0, 0.045});       // upright
  add_part(m, make_icosphere(0.04, 4), {0.045, 0.015, 0.01});            // ball
  add_part(m, make_box({0.03, 0.04, 0.025}), {0.065, -0.04, -0.0125},
           Eigen::AngleAxisd(rad(30), Eigen::Vector3d::UnitZ()).toRotationMatrix());  // block
  return m;
}

struct Sample {
  Eigen::Vector3d p;
  Eigen::Vector3d n;
};

// Area-uniform surface samples with their face normals, deterministic for a seed.
std::vector<Sample> sample_with_normals(const TriangleMesh& m, size_t n, uint64_t seed) {
  std::vector<double> cum;
  double total = 0;
  for (const auto& t : m.triangles) {
    const auto &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
    total += 0.5 * (b - a).cross(c - a).norm();
    cum.push_back(total);
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Sample> out;
  out.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const size_t k = std::min<size_t>(
        std::lower_bound(cum.begin(), cum.end(), u(rng) * total) - cum.begin(), cum.size() - 1);
    const auto& t = m.triangles[k];
    const auto &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
    double s = u(rng), r = u(rng);
    if (s + r > 1) {
      s = 1 - s;
      r = 1 - r;
    }
    out.push_back({a + s * (b - a) + r * (c - a), (b - a).cross(c - a).normalized()});
  }
  return out;
}

// What a camera looking along `view` (orthographic) sees: front-facing samples that are not
// hidden by nearer ones (a z-buffer of 1.5 mm cells, 2 mm depth tolerance), with Gaussian noise.
PointCloud visible(const std::vector<Sample>& samples, Eigen::Vector3d view, double noise_m,
                   uint64_t seed) {
  view.normalize();
  const Eigen::Vector3d ux = view.unitOrthogonal();
  const Eigen::Vector3d uy = view.cross(ux);
  const double cell = 0.0015;
  auto key = [&](const Eigen::Vector3d& p) {
    const int64_t i = static_cast<int64_t>(std::floor(p.dot(ux) / cell));
    const int64_t j = static_cast<int64_t>(std::floor(p.dot(uy) / cell));
    return (i + (1 << 20)) * (int64_t{1} << 22) + (j + (1 << 20));
  };
  std::unordered_map<int64_t, double> zmin;
  for (const auto& s : samples) {
    const double z = s.p.dot(view);
    auto it = zmin.find(key(s.p));
    if (it == zmin.end()) {
      zmin.emplace(key(s.p), z);
    } else {
      it->second = std::min(it->second, z);
    }
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, noise_m);
  PointCloud out;
  for (const auto& s : samples) {
    if (s.n.dot(view) >= -0.05) continue;  // back-facing or grazing
    if (s.p.dot(view) > zmin[key(s.p)] + 0.002) continue;  // occluded
    out.push_back((s.p + Eigen::Vector3d(g(rng), g(rng), g(rng))).cast<float>());
  }
  return out;
}

// Direction a camera at azimuth/elevation (deg) around the object looks along.
Eigen::Vector3d view_dir(double az_deg, double el_deg) {
  const double az = rad(az_deg), el = rad(el_deg);
  return -Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
}

PointCloud concat(const PointCloud& a, const PointCloud& b) {
  PointCloud out = a;
  out.insert(out.end(), b.begin(), b.end());
  return out;
}

// Share of `frame` points with a `model` point within `d` (brute force over a voxel hash).
double true_overlap(const PointCloud& model, const PointCloud& frame, double d) {
  std::unordered_map<int64_t, std::vector<Eigen::Vector3f>> grid;
  auto k3 = [d](int64_t i, int64_t j, int64_t k) {
    return ((i + 100000) * 200000 + (j + 100000)) * 200000 + (k + 100000);
  };
  auto idx = [d](float v) { return static_cast<int64_t>(std::floor(v / d)); };
  for (const auto& p : model) grid[k3(idx(p.x()), idx(p.y()), idx(p.z()))].push_back(p);
  size_t n = 0;
  for (const auto& p : frame) {
    bool hit = false;
    for (int a = -1; a <= 1 && !hit; ++a)
      for (int b = -1; b <= 1 && !hit; ++b)
        for (int c = -1; c <= 1 && !hit; ++c) {
          auto it = grid.find(k3(idx(p.x()) + a, idx(p.y()) + b, idx(p.z()) + c));
          if (it == grid.end()) continue;
          for (const auto& q : it->second) {
            if ((q - p).squaredNorm() <= d * d) {
              hit = true;
              break;
            }
          }
        }
    n += hit;
  }
  return frame.empty() ? 0.0 : static_cast<double>(n) / static_cast<double>(frame.size());
}

// The scene seen from three sides: model = two views, frame = a third overlapping both.
struct Scene {
  PointCloud model;
  PointCloud frame;  // at its true place
};

const Scene& scene() {
  static const Scene s = [] {
    const auto samples = sample_with_normals(make_scene(), 400000, 7);
    Scene sc;
    sc.model = concat(visible(samples, view_dir(0, 35), 0.0003, 1),
                      visible(samples, view_dir(100, 20), 0.0003, 2));
    sc.frame = visible(samples, view_dir(225, 40), 0.0003, 3);
    return sc;
  }();
  return s;
}

Pose perturbation(double trans_m, double rot_deg, std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Vector3d dir = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
  const Eigen::Vector3d axis = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
  Pose p = Pose::Identity();
  p.linear() = Eigen::AngleAxisd(rad(rot_deg), axis).toRotationMatrix();
  p.translation() = trans_m * dir;
  return p;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

bool contains(const std::string& s, const std::string& needle) {
  return s.find(needle) != std::string::npos;
}

TEST(Registration, SceneHasPartialOverlap) {
  const Scene& s = scene();
  ASSERT_GT(s.frame.size(), 5000u);
  const double ov =
      true_overlap(voxel_downsample(s.model, 0.002), voxel_downsample(s.frame, 0.002), 0.003);
  RecordProperty("true_overlap", std::to_string(ov));
  std::printf("  frame %zu points, true overlap with the model %.2f\n", s.frame.size(), ov);
  EXPECT_GT(ov, 0.3);
  EXPECT_LT(ov, 0.7);
}

// Loose enough a prior for the perturbations below (5 mm, 1 deg): ICP's estimate decides.
RegistrationParams loose_prior() {
  RegistrationParams p;
  p.prior_translation_m = 0.005;
  p.prior_rotation_deg = 1.0;
  return p;
}

TEST(Registration, UnperturbedFrameIsAcceptedWithTinyCorrection) {
  const Scene& s = scene();
  const auto r = register_frame(s.model, s.frame, RegistrationParams{});
  EXPECT_TRUE(r.accepted) << r.reason;
  EXPECT_FALSE(r.flagged) << r.reason;
  EXPECT_TRUE(r.converged);
  EXPECT_LT(r.translation_m, 0.0005) << r.reason;
  EXPECT_LT(r.rotation_deg, 0.05) << r.reason;
  EXPECT_GT(r.overlap, 0.3);
  EXPECT_LT(r.rmse_m, 0.001);
  EXPECT_TRUE(contains(r.reason, "corrected ")) << r.reason;
  std::printf("  unperturbed: %s\n", r.reason.c_str());
}

// An exact kinematic pose stays exact when the rig says it is (a prior of 10 um and 0.002 deg):
// ICP's own error on the downsampled clouds (a few tenths of a millimetre) is not taken, on an
// object that pins the alignment down, whatever the camera's distance. With a prior of 5 mm,
// ICP's estimate is taken: the difference is what the prior is for.
TEST(Registration, AnExactKinematicPoseStaysExactWhenTheRigSaysItIs) {
  const Scene& s = scene();
  RegistrationParams exact;
  exact.prior_translation_m = 1e-5;
  exact.prior_rotation_deg = 0.002;
  for (const Eigen::Vector3d& camera : {Eigen::Vector3d(0.5, 0.2, 0.3), Eigen::Vector3d(-0.2, 0.6, 0.4)}) {
    const auto r = register_frame(s.model, s.frame, exact, camera);
    EXPECT_TRUE(r.accepted) << r.reason;
    EXPECT_FALSE(r.flagged) << r.reason;
    EXPECT_GT(r.constraint, exact.min_constraint) << "the scene pins the alignment down";
    EXPECT_LT(r.translation_m, 2e-5) << r.reason;
    EXPECT_LT(r.rotation_deg, 0.004) << r.reason;
    const auto loose = register_frame(s.model, s.frame, loose_prior(), camera);
    EXPECT_NEAR(loose.translation_m, loose.icp_translation_m, 0.2 * loose.icp_translation_m + 1e-6) << loose.reason;
    std::printf("  exact pose, prior 10 um: taken %.4f mm %.5f deg (ICP %.4f mm %.5f deg); prior 5 mm: taken %.4f mm\n",
                r.translation_m * 1e3, r.rotation_deg, r.icp_translation_m * 1e3, r.icp_rotation_deg,
                loose.translation_m * 1e3);
  }
}

// The model prepared beforehand (as the registration service does while the rig moves: normals
// fitted over the whole model, not only near the frame) registers a frame 5 mm / 1 deg off as the
// model given whole does: both within a millimetre and a tenth of a degree of the truth, and within
// 0.05 mm and 0.01 deg of each other (only the normals at the edge of the part near the frame
// differ); the prepared model is the model's finite points downsampled, one normal per point.
// Prepared without normals it registers exactly as the model given whole, to the bit. A model
// prepared for another voxel is refused, naming both.
TEST(Registration, APreparedModelRegistersAsTheWholeModel) {
  const Scene& s = scene();
  std::mt19937_64 rng(7);
  const Pose p = perturbation(0.005, 1.0, rng);
  const PointCloud frame = transform_cloud(s.frame, p);
  const RegistrationModel prepared = registration_model(s.model, loose_prior());
  EXPECT_EQ(prepared.finite, s.model.size());
  EXPECT_EQ(prepared.dropped, 0u);
  EXPECT_LT(prepared.points.size(), s.model.size());
  EXPECT_EQ(prepared.normals.normals.size(), prepared.points.size());
  EXPECT_EQ(prepared.normals.valid.size(), prepared.points.size());
  const auto whole = register_frame(s.model, frame, loose_prior());
  const auto r = register_frame(prepared, frame, loose_prior());
  EXPECT_TRUE(r.refined) << r.reason;
  EXPECT_TRUE(whole.refined) << whole.reason;
  for (const auto* x : {&r, &whole}) {
    const Pose err = x->correction * p;
    EXPECT_LT(err.translation().norm(), 0.001) << x->reason;
    EXPECT_LT(deg(rotation_angle_rad(Eigen::Matrix3d::Identity(), err.linear())), 0.1) << x->reason;
  }
  const Pose between = r.correction * whole.correction.inverse();
  EXPECT_LT(between.translation().norm(), 5e-5) << r.reason << " / " << whole.reason;
  EXPECT_LT(deg(rotation_angle_rad(Eigen::Matrix3d::Identity(), between.linear())), 0.01);
  const RegistrationModel bare = registration_model(s.model, loose_prior(), false);
  EXPECT_TRUE(bare.normals.valid.empty());
  EXPECT_TRUE(register_frame(bare, frame, loose_prior()).correction.isApprox(whole.correction, 1e-12));
  RegistrationParams other = loose_prior();
  other.voxel_m = 0.002;
  try {
    register_frame(prepared, frame, other);
    ADD_FAILURE() << "a model prepared for 3 mm registered at 2 mm";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "register_frame: the model was prepared for 3.0 mm voxels, not 2.0 mm");
  }
}

// A correction the rig's uncertainty does not allow (5 mm off where the rig claims 0.5 mm) is not
// taken: the kinematic pose is kept and the view flagged, ICP's proposal and its sigmas said.
TEST(Registration, ACorrectionBeyondThePriorIsNotTakenAndFlagged) {
  const Scene& s = scene();
  Pose p = Pose::Identity();
  p.translation() = Eigen::Vector3d(0.003, -0.003, 0.002);
  const auto r = register_frame(s.model, transform_cloud(s.frame, p), RegistrationParams{});
  EXPECT_TRUE(r.accepted) << r.reason;
  EXPECT_TRUE(r.flagged) << r.reason;
  EXPECT_FALSE(r.refined);
  EXPECT_TRUE(r.correction.isApprox(Pose::Identity()));
  EXPECT_NEAR(r.icp_translation_m, p.translation().norm(), 0.001) << r.reason;
  EXPECT_GT(r.prior_sigmas, 5.0) << r.reason;
  EXPECT_TRUE(contains(r.reason, "kinematic pose kept, flagged (ICP ")) << r.reason;
  EXPECT_TRUE(contains(r.reason, "sigma of the kinematic pose's sigma 0.50 mm, 0.100 deg, above 5.0)")) << r.reason;
}

TEST(Registration, RecoversFiveMillimetreOneDegreePerturbation) {
  const Scene& s = scene();
  std::mt19937_64 rng(2024);
  std::vector<double> te, re;
  for (int i = 0; i < 10; ++i) {
    const Pose p = perturbation(0.005, 1.0, rng);
    const auto r = register_frame(s.model, transform_cloud(s.frame, p), loose_prior());
    EXPECT_TRUE(r.accepted) << r.reason;
    EXPECT_TRUE(r.refined) << r.reason;
    const Pose err = r.correction * p;  // identity when the correction undoes p
    te.push_back(err.translation().norm());
    re.push_back(deg(rotation_angle_rad(Eigen::Matrix3d::Identity(), err.linear())));
    EXPECT_NEAR(r.translation_m, (r.correction.translation()).norm(), 1e-12);
    const Eigen::AngleAxisd aa(err.linear());
    std::printf("  trial %d: err %.3f mm %.4f deg axis %+.2f %+.2f %+.2f; %s, %d it, %.0f ms\n",
                i, te.back() * 1e3, re.back(), aa.axis().x(), aa.axis().y(), aa.axis().z(),
                r.reason.c_str(), r.iterations, r.time_s * 1e3);
  }
  const double tmed = median(te), rmed = median(re);
  const double tmax = *std::max_element(te.begin(), te.end());
  const double rmax = *std::max_element(re.begin(), re.end());
  std::printf("  translation error median %.3f mm max %.3f mm; rotation error median %.4f deg "
              "max %.4f deg\n",
              tmed * 1e3, tmax * 1e3, rmed, rmax);
  // Measured: ICP's 3 mm voxel (since stop 47) median 0.089 mm / 0.088 deg, worst 0.237 mm /
  // 0.224 deg; the 2 mm voxel before it 0.072 mm / 0.074 deg, worst 0.171 mm / 0.143 deg (the
  // scans' clouds are as accurate either way: docs/benchmark.md, "ICP at 3 mm").
  EXPECT_LE(tmed, 0.001);
  EXPECT_LE(rmed, 0.1);
  EXPECT_LE(tmax, 0.002);
  EXPECT_LE(rmax, 0.25);
}

TEST(Registration, OverlapIsTheShareOfFramePointsNearTheModel) {
  // The gate's overlap, checked by brute force on the same downsampled clouds.
  const Scene& s = scene();
  std::mt19937_64 rng(11);
  const Pose p = perturbation(0.005, 1.0, rng);
  const PointCloud frame = transform_cloud(s.frame, p);
  const auto r = register_frame(s.model, frame, loose_prior());
  ASSERT_TRUE(r.refined) << r.reason;
  const double voxel = RegistrationParams{}.voxel_m;
  const double want = true_overlap(voxel_downsample(s.model, voxel),
                                   transform_cloud(voxel_downsample(frame, voxel), r.correction),
                                   RegistrationParams{}.overlap_distance_m);
  EXPECT_NEAR(r.overlap, want, 0.002);
  // And with a looser distance the share grows.
  RegistrationParams loose = loose_prior();
  loose.overlap_distance_m = 0.006;
  const auto r2 = register_frame(s.model, frame, loose);
  EXPECT_GT(r2.overlap, r.overlap);
}

TEST(Registration, CorrectionAboveTheGateIsNotTakenButReported) {
  const Scene& s = scene();
  std::mt19937_64 rng(5);
  const Pose p = perturbation(0.008, 0.5, rng);
  RegistrationParams params = loose_prior();
  params.max_translation_m = 0.005;
  const auto r = register_frame(s.model, transform_cloud(s.frame, p), params);
  EXPECT_TRUE(r.accepted) << "merged at its kinematic pose";
  EXPECT_TRUE(r.flagged);
  EXPECT_TRUE(r.correction.isApprox(Pose::Identity()));
  EXPECT_TRUE(contains(r.reason, "kinematic pose kept, flagged (alignment not trusted: correction 0.00")) << r.reason;
  EXPECT_TRUE(contains(r.reason, "exceeds 0.005 m")) << r.reason;
  // The alignment itself was right; only the gate said no.
  EXPECT_NEAR(r.icp_translation_m, p.translation().norm(), 0.002);
  EXPECT_GT(r.overlap, 0.3);
}

TEST(Registration, TenCentimetresOffKeepsTheKinematicPoseFlagged) {
  const Scene& s = scene();
  for (const Eigen::Vector3d& off : {Eigen::Vector3d(0.10, 0, 0), Eigen::Vector3d(0, -0.1, 0),
                                    Eigen::Vector3d(0.06, 0.06, 0.05)}) {
    Pose p = Pose::Identity();
    p.translation() = off;
    const auto r = register_frame(s.model, transform_cloud(s.frame, p), RegistrationParams{});
    EXPECT_TRUE(r.accepted) << r.reason;
    EXPECT_TRUE(r.flagged) << r.reason;
    EXPECT_TRUE(r.correction.isApprox(Pose::Identity()));
    EXPECT_EQ(r.reason.rfind("kinematic pose kept, flagged (", 0), 0u) << r.reason;
    EXPECT_TRUE(contains(r.reason, "overlap") || contains(r.reason, "rmse") ||
                contains(r.reason, "correction") || contains(r.reason, "converge"))
        << r.reason;
    // ICP may even walk the 10 cm back, but a correction that large is never believed.
    EXPECT_TRUE(r.icp_translation_m > 0.03 || r.icp_rotation_deg > 3.0 || r.overlap < 0.3 ||
                !r.converged || r.rmse_m > 0.002 || r.prior_sigmas > 5.0)
        << r.reason;
    std::printf("  off %.2f m: %s\n", off.norm(), r.reason.c_str());
  }
}

// A view that sees nothing of the model (new surface only) is merged where the kinematics put it.
TEST(Registration, DisjointFrameIsMergedAtItsKinematicPose) {
  const Scene& s = scene();
  // A separate box 10 cm beyond the object: nothing of it is in the model.
  TriangleMesh other;
  add_part(other, make_box({0.06, 0.05, 0.04}), {0.25, 0.0, 0.0});
  const PointCloud frame =
      visible(sample_with_normals(other, 40000, 9), view_dir(190, 40), 0.0003, 4);
  const auto r = register_frame(s.model, frame, RegistrationParams{});
  EXPECT_TRUE(r.accepted);
  EXPECT_TRUE(r.flagged);
  EXPECT_TRUE(r.correction.isApprox(Pose::Identity()));
  EXPECT_TRUE(contains(r.reason, "kinematic pose kept, flagged (alignment not trusted: overlap 0.00 below 0.10")) << r.reason;
  EXPECT_EQ(r.overlap, 0.0);

  // Also a part within the correspondence distance: the model without the upright box, the
  // frame of the upright box seen from behind.
  TriangleMesh upright;
  add_part(upright, make_box({0.05, 0.12, 0.14}), {-0.075, 0.0, 0.045});
  TriangleMesh foot;
  add_part(foot, make_box({0.20, 0.12, 0.05}), {0.0, 0.0, -0.05});
  const PointCloud model2 =
      visible(sample_with_normals(foot, 100000, 11), view_dir(0, 35), 0.0003, 5);
  const PointCloud frame2 =
      visible(sample_with_normals(upright, 100000, 12), view_dir(180, 10), 0.0003, 6);
  const auto r2 = register_frame(model2, frame2, RegistrationParams{});
  EXPECT_TRUE(r2.accepted) << r2.reason;
  EXPECT_TRUE(r2.flagged) << r2.reason;
  EXPECT_TRUE(r2.correction.isApprox(Pose::Identity()));
  EXPECT_TRUE(contains(r2.reason, "alignment not trusted: overlap")) << r2.reason;
  EXPECT_LT(r2.overlap, 0.3);
}

TEST(Registration, EmptyModelDefinesTheModel) {
  const Scene& s = scene();
  const auto r = register_frame(PointCloud{}, s.frame, RegistrationParams{});
  EXPECT_TRUE(r.accepted);
  EXPECT_TRUE(r.correction.isApprox(Pose::Identity()));
  EXPECT_EQ(r.reason, "first frame: defines the model");
  // A model of only non-finite points is empty too.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const auto r2 = register_frame({Eigen::Vector3f(nan, 0, 0)}, s.frame, RegistrationParams{});
  EXPECT_TRUE(r2.accepted);
  EXPECT_TRUE(r2.correction.isApprox(Pose::Identity()));
}

TEST(Registration, TooFewPointsKeepsTheKinematicPoseWithTheCounts) {
  const Scene& s = scene();
  const PointCloud ten(s.frame.begin(), s.frame.begin() + 10);
  const auto r = register_frame(s.model, ten, RegistrationParams{});
  EXPECT_TRUE(r.accepted);
  EXPECT_TRUE(r.flagged);
  EXPECT_TRUE(contains(r.reason, "too few points")) << r.reason;
  EXPECT_TRUE(contains(r.reason, "frame 10,")) << r.reason;
  EXPECT_TRUE(contains(r.reason, "need 200")) << r.reason;
  EXPECT_TRUE(r.correction.isApprox(Pose::Identity()));

  // A tiny model is reported the same way.
  const auto r2 = register_frame(ten, s.frame, RegistrationParams{});
  EXPECT_TRUE(r2.accepted);
  EXPECT_TRUE(r2.flagged);
  EXPECT_TRUE(contains(r2.reason, "model 10 ")) << r2.reason;
  // An empty frame against a model: nothing to merge.
  const auto r3 = register_frame(s.model, {}, RegistrationParams{});
  EXPECT_FALSE(r3.accepted);
  EXPECT_EQ(r3.reason, "not merged (no finite point in the view)");
}

TEST(Registration, NonFinitePointsAreDropped) {
  const Scene& s = scene();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  std::mt19937_64 rng(3);
  const Pose p = perturbation(0.005, 1.0, rng);
  PointCloud frame = transform_cloud(s.frame, p);
  PointCloud model = s.model;
  for (size_t i = 0; i < frame.size(); i += 7) frame[i] = Eigen::Vector3f(nan, 0.0f, 1.0f);
  for (size_t i = 3; i < model.size(); i += 11) model[i] = Eigen::Vector3f(0.0f, inf, nan);
  RegistrationResult r;
  EXPECT_NO_THROW(r = register_frame(model, frame, loose_prior()));
  EXPECT_TRUE(r.refined) << r.reason;
  EXPECT_TRUE(contains(r.reason, "non-finite points dropped")) << r.reason;
  EXPECT_LT((r.correction * p).translation().norm(), 0.002);
  EXPECT_TRUE(r.correction.matrix().allFinite());

  // Nothing finite at all in the frame.
  const PointCloud all_nan(500, Eigen::Vector3f(nan, nan, nan));
  EXPECT_NO_THROW(r = register_frame(model, all_nan, RegistrationParams{}));
  EXPECT_FALSE(r.accepted);
  EXPECT_TRUE(contains(r.reason, "not merged (no finite point in the view")) << r.reason;

  // Absurd coordinates and degenerate (collinear) clouds do not throw either.
  PointCloud line;
  for (int i = 0; i < 1000; ++i) line.emplace_back(0.001f * i, 0.0f, 0.0f);
  EXPECT_NO_THROW(r = register_frame(line, line, RegistrationParams{}));
  PointCloud far = s.frame;
  far[0] = Eigen::Vector3f(1e30f, -1e30f, 1e30f);
  EXPECT_NO_THROW(r = register_frame(s.model, far, RegistrationParams{}));
}

TEST(Registration, TransformCloudAppliesThePoseExactly) {
  std::mt19937_64 rng(1);
  const Pose p = perturbation(0.3, 40.0, rng);
  std::uniform_real_distribution<float> u(-0.2f, 0.2f);
  PointCloud c;
  for (int i = 0; i < 1000; ++i) c.emplace_back(u(rng), u(rng), u(rng));
  const PointCloud t = transform_cloud(c, p);
  ASSERT_EQ(t.size(), c.size());
  for (size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector3d want = p.linear() * c[i].cast<double>() + p.translation();
    EXPECT_EQ(t[i], want.cast<float>()) << i;  // one rounding from the double result
  }
  // Identity is a no-op; a pose and its inverse round-trip to float precision.
  EXPECT_EQ(transform_cloud(c, Pose::Identity()), c);
  const PointCloud back = transform_cloud(t, p.inverse());
  for (size_t i = 0; i < c.size(); ++i) EXPECT_LT((back[i] - c[i]).norm(), 1e-6f);
  EXPECT_TRUE(transform_cloud({}, p).empty());
}

// A plane shifted within itself cannot be registered: the overlap leaves two translations and
// a rotation free, ICP would slide anywhere. The view keeps its kinematic pose (and is merged).
// The same shift of three perpendicular faces of a box is seen and undone.
TEST(Registration, GeometryThatDoesNotPinTheAlignmentKeepsTheKinematicPose) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  PointCloud plane_model, plane_frame;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), 0.0);
    plane_model.emplace_back(p.cast<float>());
    plane_frame.emplace_back((p + Eigen::Vector3d(0.004, -0.003, 0.0)).cast<float>());
  }
  RegistrationParams params;
  const RegistrationResult flat = register_frame(plane_model, plane_frame, params);
  EXPECT_TRUE(flat.accepted) << flat.reason;
  EXPECT_FALSE(flat.refined) << flat.reason;
  EXPECT_LT(flat.constraint, params.min_constraint);
  EXPECT_TRUE(flat.correction.isApprox(Pose::Identity())) << flat.reason;
  EXPECT_NE(flat.reason.find("kinematic pose kept"), std::string::npos) << flat.reason;

  // Three faces of a box meeting at a corner, the frame moved by (4, -3, 2) mm.
  PointCloud corner_model, corner_frame;
  const Eigen::Vector3d shift(0.004, -0.003, 0.002);
  for (int i = 0; i < 30000; ++i) {
    Eigen::Vector3d p(u(rng) + 0.1, u(rng) + 0.1, u(rng) + 0.1);  // in [0, 0.2]^3
    p[i % 3] = 0.0;                                              // on one of the three faces
    corner_model.emplace_back(p.cast<float>());
    corner_frame.emplace_back((p + shift).cast<float>());
  }
  const RegistrationResult box = register_frame(corner_model, corner_frame, loose_prior());
  EXPECT_TRUE(box.accepted) << box.reason;
  EXPECT_TRUE(box.refined) << box.reason;
  EXPECT_GT(box.constraint, params.min_constraint);
  EXPECT_LT((box.correction.translation() + shift).norm(), 5e-4) << box.reason;
}

}  // namespace
}  // namespace pbnbv
