#include "core/geometry/visibility.hpp"
#include "core/base/units.hpp"

#include "core/base/parallel.hpp"
#include "core/geometry/mesh_tree.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace pbnbv {

namespace {

constexpr const char* kName = "visible_from_any";
constexpr const char* kCtx = "visible_from_any: ";

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument(kCtx + what); }

std::string index_name(const char* array, std::size_t i) {
  return std::string(array) + "[" + std::to_string(i) + "]";
}

// A view prepared for the per-sample tests.
struct ViewFrame {
  Eigen::Matrix3d camera_R_object;  // rotation part of camera_T_object
  Eigen::Vector3d centre;           // camera centre in the object frame
};

}  // namespace

SurfaceSamples sample_surface_with_normals(const TriangleMesh& mesh, std::size_t n,
                                           std::uint64_t seed) {
  SurfaceSamples out;
  if (n == 0) return out;
  check_triangle_indices(mesh, "sample_surface_with_normals");
  out.points = sample_surface(mesh, n, seed, &out.normals);
  return out;
}

namespace {

void check_arguments(const TriangleMesh& mesh, const std::vector<Eigen::Vector3d>& samples,
                     const std::vector<Eigen::Vector3d>& normals, const std::vector<Pose>& views,
                     const VisibilityParams& p) {
  // --- Arguments -------------------------------------------------------------------------------
  if (!normals.empty() && normals.size() != samples.size()) {
    fail("normals has " + std::to_string(normals.size()) + " entries, samples has " +
         std::to_string(samples.size()) + " (need 0 or the same number)");
  }
  if (mesh.triangles.empty() || mesh.vertices.empty()) fail("mesh has no triangles");
  check_triangle_indices(mesh, kName);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (!samples[i].allFinite()) fail(index_name("samples", i) + " is not finite");
  }
  for (std::size_t i = 0; i < normals.size(); ++i) {
    if (!normals[i].allFinite()) fail(index_name("normals", i) + " is not finite");
  }
  for (std::size_t i = 0; i < views.size(); ++i) {
    if (!views[i].matrix().allFinite()) fail(index_name("views", i) + " is not finite");
  }
  try {
    p.camera.validate();
  } catch (const std::invalid_argument& e) {
    fail(std::string("p.camera: ") + e.what());
  }
  try {
    p.range.validate();
  } catch (const std::invalid_argument& e) {
    fail(std::string("p.range: ") + e.what());
  }
  if (!(std::isfinite(p.surface_offset_m) && p.surface_offset_m >= 0.0)) {
    fail("p.surface_offset_m = " + std::to_string(p.surface_offset_m) +
         " must be a finite number >= 0");
  }
  if (!(p.max_incidence_deg >= 0.0 && p.max_incidence_deg <= 90.0)) {
    fail("p.max_incidence_deg = " + std::to_string(p.max_incidence_deg) + " must be in [0, 90]");
  }
  if (p.threads < 0) fail("p.threads = " + std::to_string(p.threads) + " must be >= 0");
}

// Whether a view sees a sample (the rules of visible_from_any); the mesh's AABB tree built once.
class SampleTest {
 public:
  SampleTest(const TriangleMesh& mesh, const std::vector<Eigen::Vector3d>& samples,
             const std::vector<Eigen::Vector3d>& normals, const VisibilityParams& p)
      : tree_(mesh, DistanceHints::kNone, kName), samples_(samples), normals_(normals), p_(p),
        cos_max_(std::cos(p.max_incidence_deg * kPi / 180.0)) {}

  static ViewFrame frame(const Pose& view) { return {view.linear().transpose(), view.translation()}; }

  bool sees(std::size_t i, const ViewFrame& f) const {
    const CameraIntrinsics& k = p_.camera;
    const bool use_normals = !normals_.empty();
    const Eigen::Vector3d& x = samples_[i];
    const Eigen::Vector3d to_cam = f.centre - x;
    // Cheapest rejections first: facing away (max incidence <= 90 deg), then depth, then image.
    const double facing = use_normals ? normals_[i].dot(to_cam) : 0.0;
    if (facing < 0.0) return false;
    const Eigen::Vector3d xc = f.camera_R_object * (-to_cam);  // sample in the optical frame
    const double z = xc.z();
    if (!(z >= p_.range.min_m && z <= p_.range.max_m)) return false;
    const double u = k.fx * xc.x() / z + k.cx;
    const double v = k.fy * xc.y() / z + k.cy;
    // Pixel centres at integers: the image spans [-0.5, width - 0.5) x [-0.5, height - 0.5).
    if (!(u >= -0.5 && u < k.width - 0.5 && v >= -0.5 && v < k.height - 0.5)) return false;
    const double dist = to_cam.norm();
    if (use_normals && facing < cos_max_ * normals_[i].norm() * dist) return false;
    if (p_.surface_offset_m >= dist) return true;  // nothing left to test
    const Eigen::Vector3d s = x + (p_.surface_offset_m / dist) * to_cam;
    return !tree_.segment_hits(s, f.centre);
  }

 private:
  MeshTree tree_;
  const std::vector<Eigen::Vector3d>& samples_;
  const std::vector<Eigen::Vector3d>& normals_;
  const VisibilityParams& p_;
  double cos_max_;
};

}  // namespace

std::vector<uint8_t> visible_from_any(const TriangleMesh& mesh,
                                      const std::vector<Eigen::Vector3d>& samples,
                                      const std::vector<Eigen::Vector3d>& normals,
                                      const std::vector<Pose>& views, const VisibilityParams& p) {
  check_arguments(mesh, samples, normals, views, p);
  std::vector<uint8_t> mask(samples.size(), 0);
  if (samples.empty() || views.empty()) return mask;
  const SampleTest test(mesh, samples, normals, p);

  // Views are tried in a golden-ratio stride order rather than as given: view sets come ordered
  // by position (ring after ring), so consecutive views tend to see the same side and a sample on
  // the other side would wade through many of them; spread out, one of the first few tries
  // usually sees it. The order does not change the result.
  const std::size_t nv = views.size();
  std::size_t stride = std::max<std::size_t>(1, static_cast<std::size_t>(0.618034 * nv));
  while (std::gcd(stride, nv) != 1) ++stride;
  std::vector<ViewFrame> frames(nv);
  for (std::size_t j = 0; j < nv; ++j) frames[j] = SampleTest::frame(views[(j * stride) % nv]);

  // --- Samples in chunks of at least kBlock, handed out to the workers (core/base/parallel.hpp) ---
  constexpr std::size_t kBlock = 128;
  parallel_for(samples.size(), [&](std::size_t begin, std::size_t end, int) {
    for (std::size_t i = begin; i < end; ++i) {
      for (const ViewFrame& f : frames) {
        if (test.sees(i, f)) {
          mask[i] = 1;
          break;
        }
      }
    }
  }, kBlock, p.threads);
  return mask;
}

std::vector<int> count_newly_visible(const TriangleMesh& mesh,
                                     const std::vector<Eigen::Vector3d>& samples,
                                     const std::vector<Eigen::Vector3d>& normals,
                                     const std::vector<Pose>& views,
                                     const std::vector<uint8_t>& already_seen,
                                     const VisibilityParams& p) {
  check_arguments(mesh, samples, normals, views, p);
  if (!already_seen.empty() && already_seen.size() != samples.size()) {
    fail("already_seen has " + std::to_string(already_seen.size()) + " entries, samples has " +
         std::to_string(samples.size()) + " (need 0 or the same number)");
  }
  std::vector<int> counts(views.size(), 0);
  if (samples.empty() || views.empty()) return counts;
  const SampleTest test(mesh, samples, normals, p);
  // One view per task: each worker writes only its views' counts.
  parallel_for(views.size(), [&](std::size_t begin, std::size_t end, int) {
    for (std::size_t j = begin; j < end; ++j) {
      const ViewFrame f = SampleTest::frame(views[j]);
      int n = 0;
      for (std::size_t i = 0; i < samples.size(); ++i) {
        if ((already_seen.empty() || !already_seen[i]) && test.sees(i, f)) ++n;
      }
      counts[j] = n;
    }
  }, 1, p.threads);
  return counts;
}

}  // namespace pbnbv
