#include "eval/coverage.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/geometry/visibility.hpp"

namespace pbnbv {
namespace {

using Points = std::vector<Eigen::Vector3d>;

constexpr double kR = 0.15;  // sphere radius / box half-edge used throughout (a 0.3 m object)

// Throws std::invalid_argument whose message contains `needle`.
void expect_invalid(const std::function<void()>& fn, const std::string& needle) {
  try {
    fn();
    ADD_FAILURE() << "no exception thrown";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
        << "message '" << e.what() << "' lacks '" << needle << "'";
  }
}

Points select(const Points& pts, const std::function<bool(const Eigen::Vector3d&)>& keep) {
  Points out;
  for (const auto& p : pts) {
    if (keep(p)) out.push_back(p);
  }
  return out;
}

// Exhaustive reference: sample i covered when some cloud point is within r.
std::vector<uint8_t> brute_force(const Points& samples, const Points& cloud, double r) {
  std::vector<uint8_t> out(samples.size(), 0);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    for (const auto& p : cloud) {
      if ((p - samples[i]).squaredNorm() <= r * r) {
        out[i] = 1;
        break;
      }
    }
  }
  return out;
}

const TriangleMesh& sphere() {
  static const TriangleMesh m = make_icosphere(kR, 4);
  return m;
}
// 200k points on the sphere, a different seed from the evaluator's samples (seed 1).
const Points& dense_sphere_cloud() {
  static const Points c = sample_surface(sphere(), 200000, 7);
  return c;
}

// ---- hand-made samples -------------------------------------------------------------------
// The evaluator's samples are the surface samples the oracle and the observable surface use
// (sample_surface_with_normals with the same count and seed), bit for bit.
TEST(Coverage, SamplesAreTheSurfaceSamplesOfTheSameSeed) {
  for (const TriangleMesh& mesh : {make_box(Eigen::Vector3d(0.3, 0.2, 0.1)), make_icosphere(kR, 3)}) {
    for (std::uint64_t seed : {1u, 42u}) {
      CoverageParams cp;
      cp.num_samples = 5000;
      cp.seed = seed;
      EXPECT_EQ(CoverageEvaluator(mesh, cp).samples(), sample_surface_with_normals(mesh, 5000, seed).points);
    }
  }
}

TEST(Coverage, GivenSamplesRadiusIsInclusive) {
  CoverageEvaluator ev({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {10, 10, 10}}, 0.005);
  EXPECT_EQ(ev.samples().size(), 4u);
  EXPECT_DOUBLE_EQ(ev.radius_m(), 0.005);
  EXPECT_DOUBLE_EQ(ev.add({{0.0049, 0, 0}}), 25.0);   // 4.9 mm from sample 0
  EXPECT_DOUBLE_EQ(ev.add({{1, 0.0051, 0}}), 25.0);   // 5.1 mm from sample 1: not covered
  EXPECT_DOUBLE_EQ(ev.add({{1, 0, 0.005}}), 50.0);    // exactly 5 mm: covered
  EXPECT_DOUBLE_EQ(ev.add({{100, 100, 100}, {5, 5, 5}}), 50.0);  // far from everything
  EXPECT_EQ(ev.covered(), (std::vector<uint8_t>{1, 1, 0, 0}));
  EXPECT_EQ(ev.num_covered(), 2u);
  EXPECT_DOUBLE_EQ(ev.coverage_percent(), 50.0);
}

TEST(Coverage, NonFinitePointsAreSkippedAndCounted) {
  CoverageEvaluator ev({{0, 0, 0}, {1, 0, 0}}, 0.01);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_DOUBLE_EQ(ev.add({{nan, 0, 0}, {0, inf, 0}, {1, 0, 0}}), 50.0);
  EXPECT_EQ(ev.rejected_points(), 2u);
  EXPECT_EQ(ev.covered(), (std::vector<uint8_t>{0, 1}));
}

TEST(Coverage, FloatCloudSameAsDouble) {
  CoverageEvaluator a(sphere()), b(sphere());
  const Points half = select(dense_sphere_cloud(), [](const Eigen::Vector3d& p) { return p.x() > 0; });
  PointCloud f;
  for (const auto& p : half) f.push_back(p.cast<float>());
  a.add(half);
  b.add_cloud(f);
  // Float rounding (~1e-8 m) may flip a sample sitting exactly on the radius; none should here.
  EXPECT_EQ(a.covered(), b.covered());
}

// Random samples and clouds against the exhaustive reference, for radii from much smaller to much
// larger than the sample spacing, and with a grid so sparse that its cells must be enlarged.
TEST(Coverage, MatchesBruteForce) {
  std::mt19937_64 rng(3);
  for (const double spread : {1.0, 1000.0}) {
    std::uniform_real_distribution<double> u(-0.5 * spread, 0.5 * spread);
    Points samples(1500);
    for (auto& s : samples) s = {u(rng), u(rng), u(rng)};
    for (const double r : {0.001, 0.02, 0.3, 2.0}) {
      std::normal_distribution<double> g(0.0, r);
      Points cloud;
      for (int k = 0; k < 3000; ++k) {
        cloud.push_back(samples[static_cast<std::size_t>(k) % samples.size()] +
                        Eigen::Vector3d(g(rng), g(rng), g(rng)));
        cloud.push_back({u(rng), u(rng), u(rng)});
      }
      CoverageEvaluator ev(samples, r);
      ev.add(cloud);
      const auto ref = brute_force(samples, cloud, r);
      EXPECT_EQ(ev.covered(), ref) << "spread " << spread << " radius " << r;
      std::size_t n = 0;
      for (auto c : ref) n += c;
      EXPECT_EQ(ev.num_covered(), n);
      EXPECT_GT(n, 0u);
    }
  }
}

// ---- on meshes ---------------------------------------------------------------------------
TEST(Coverage, DefaultSamplesAreTheFixedSeedSurfaceSamples) {
  CoverageEvaluator ev(sphere());
  EXPECT_EQ(ev.samples(), sample_surface(sphere(), 10000, 1));
  EXPECT_DOUBLE_EQ(ev.radius_m(), 0.005);
  EXPECT_DOUBLE_EQ(ev.coverage_percent(), 0.0);
}

TEST(Coverage, DenseCloudCoversEverything) {
  CoverageEvaluator ev(sphere());
  EXPECT_GE(ev.add(dense_sphere_cloud()), 99.9);
  EXPECT_GE(coverage_percent(sphere(), dense_sphere_cloud()), 99.9);
  const TriangleMesh box = make_box(Eigen::Vector3d::Constant(2 * kR));
  EXPECT_GE(coverage_percent(box, sample_surface(box, 200000, 7)), 99.9);
}

TEST(Coverage, UpperHalfOfSphere) {
  // z > 0 covers the upper half plus a 5 mm band below the equator: by Archimedes the area
  // fraction with z > -r is (R + r) / 2R = 51.7%.
  const Points upper = select(dense_sphere_cloud(), [](const Eigen::Vector3d& p) { return p.z() > 0; });
  const double expected = 100.0 * (kR + 0.005) / (2 * kR);
  EXPECT_NEAR(coverage_percent(sphere(), upper), expected, 1.5);
  EXPECT_NEAR(coverage_percent(sphere(), upper), 50.0, 2.0);
}

TEST(Coverage, TopFaceOfBox) {
  // The top face is 1/6 of the area; the 5 mm strips along its edges on the four side faces add
  // 4 * 0.005 * 0.3 / (6 * 0.09) = 1.1%: 17.8% in all.
  const TriangleMesh box = make_box(Eigen::Vector3d::Constant(2 * kR));
  const Points top = select(sample_surface(box, 200000, 7),
                            [](const Eigen::Vector3d& p) { return std::abs(p.z() - kR) < 1e-9; });
  const double expected = 100.0 * (1.0 / 6.0 + 4 * 0.005 * 0.3 / (6 * 0.09));
  EXPECT_NEAR(expected, 17.78, 0.01);
  EXPECT_NEAR(coverage_percent(box, top), expected, 1.5);
}

TEST(Coverage, EmptyAndOffsetClouds) {
  EXPECT_DOUBLE_EQ(coverage_percent(sphere(), {}), 0.0);
  auto scaled = [](double offset_m) {
    Points out;
    for (const auto& p : dense_sphere_cloud()) out.push_back(p * (kR + offset_m) / kR);
    return out;
  };
  EXPECT_DOUBLE_EQ(coverage_percent(sphere(), scaled(0.010)), 0.0);   // 1 cm outside
  EXPECT_GE(coverage_percent(sphere(), scaled(0.004)), 99.9);        // 4 mm outside
  EXPECT_GE(coverage_percent(sphere(), scaled(-0.004)), 99.9);       // 4 mm inside
}

TEST(Coverage, AddAccumulates) {
  const Points& all = dense_sphere_cloud();
  const Points upper = select(all, [](const Eigen::Vector3d& p) { return p.z() > 0; });
  const Points lower = select(all, [](const Eigen::Vector3d& p) { return p.z() <= 0; });
  CoverageEvaluator whole(sphere()), halves(sphere());
  const double w = whole.add(all);
  const double first = halves.add(upper);
  EXPECT_GT(first, 45.0);
  EXPECT_LT(first, 55.0);
  EXPECT_DOUBLE_EQ(halves.add(lower), w);
  EXPECT_EQ(halves.covered(), whole.covered());
  EXPECT_DOUBLE_EQ(halves.add(upper), w);  // adding a view again changes nothing

  halves.reset();
  EXPECT_DOUBLE_EQ(halves.coverage_percent(), 0.0);
  EXPECT_EQ(halves.num_covered(), 0u);
  EXPECT_DOUBLE_EQ(halves.add(upper), first);  // grid counters restored too
  EXPECT_DOUBLE_EQ(halves.add(lower), w);
}

TEST(Coverage, Mask) {
  CoverageEvaluator ev(sphere());
  ev.add(select(dense_sphere_cloud(), [](const Eigen::Vector3d& p) { return p.z() > 0; }));
  const Points& s = ev.samples();
  std::vector<uint8_t> upper(s.size()), far_below(s.size()), all(s.size(), 1), none(s.size(), 0);
  for (std::size_t i = 0; i < s.size(); ++i) {
    upper[i] = s[i].z() > 0 ? 1 : 0;
    far_below[i] = s[i].z() < -0.01 ? 2 : 0;  // any non-zero value selects
  }
  EXPECT_DOUBLE_EQ(ev.coverage_percent(upper), 100.0);
  EXPECT_DOUBLE_EQ(ev.coverage_percent(far_below), 0.0);
  EXPECT_DOUBLE_EQ(ev.coverage_percent(all), ev.coverage_percent());
  EXPECT_DOUBLE_EQ(ev.coverage_percent(none), 0.0);
  // Hand-checkable: samples 0 and 3 covered, 1 and 2 not.
  CoverageEvaluator small({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}}, 0.1);
  small.add({{0, 0, 0}, {3, 0, 0}});
  EXPECT_DOUBLE_EQ(small.coverage_percent({1, 1, 0, 0}), 50.0);
  EXPECT_DOUBLE_EQ(small.coverage_percent({0, 1, 1, 0}), 0.0);
  EXPECT_DOUBLE_EQ(small.coverage_percent({1, 0, 0, 1}), 100.0);
  expect_invalid([&] { small.coverage_percent(std::vector<uint8_t>(3, 1)); }, "mask");
}

TEST(Coverage, BadParametersThrowNamingThem) {
  CoverageParams p;
  p.num_samples = 0;
  expect_invalid([&] { CoverageEvaluator ev(sphere(), p); }, "num_samples");
  for (const double r : {0.0, -0.005, std::numeric_limits<double>::quiet_NaN(),
                         std::numeric_limits<double>::infinity()}) {
    CoverageParams q;
    q.radius_m = r;
    expect_invalid([&] { CoverageEvaluator ev(sphere(), q); }, "radius_m");
    expect_invalid([&] { CoverageEvaluator ev(Points{{0, 0, 0}}, r); }, "radius_m");
    expect_invalid([&] { coverage_percent(sphere(), {}, q); }, "radius_m");
  }
  expect_invalid([] { CoverageEvaluator ev(Points{}, 0.005); }, "surface_points");
  expect_invalid(
      [] {
        CoverageEvaluator ev(Points{{0, 0, 0}, {0, std::nan(""), 0}}, 0.005);
      },
      "sample 1");
  expect_invalid([] { CoverageEvaluator ev(TriangleMesh{}); }, "no triangles");
}

}  // namespace
}  // namespace pbnbv
