#include "core/perception/cloud_filter.hpp"
#include "core/perception/registration.hpp"
#include "core/perception/index_search.hpp"
#include "core/perception/neighbours.hpp"
#include "core/base/format.hpp"
#include "core/base/units.hpp"

#include <Eigen/Eigenvalues>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/correspondence_rejection.h>
#include <pcl/registration/icp.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <limits>
#include <memory>
#include <string>
#include <unordered_set>
#include <vector>

namespace pbnbv {

namespace {

using Clock = std::chrono::steady_clock;
// Point-to-plane ICP (linear least squares, double precision estimation); exposes the
// iteration count pcl keeps protected.
class Icp : public pcl::IterativeClosestPointWithNormals<pcl::PointNormal, pcl::PointNormal,
                                                          double> {
 public:
  int iterations() const { return nr_iterations_; }
};
using Criteria = pcl::registration::DefaultConvergenceCriteria<double>;

// Drops correspondences whose surface normals disagree by more than an angle (unsigned: the
// normals are not oriented consistently). The source normals are turned by the pose at the start
// of the stage; the rotation within a stage is a few degrees at most, well inside the threshold.
class NormalCompatibilityRejector : public pcl::registration::CorrespondenceRejector {
 public:
  NormalCompatibilityRejector(pcl::PointCloud<pcl::PointNormal>::ConstPtr source,
                              pcl::PointCloud<pcl::PointNormal>::ConstPtr target, double max_deg)
      : source_(std::move(source)), target_(std::move(target)),
        min_cos_(static_cast<float>(std::cos(max_deg * 3.14159265358979323846 / 180.0))) {
    rejection_name_ = "NormalCompatibilityRejector";
  }
  void set_rotation(const Eigen::Matrix3f& r) { rotation_ = r; }
  void getRemainingCorrespondences(const pcl::Correspondences& in,
                                   pcl::Correspondences& out) override {
    out.clear();
    out.reserve(in.size());
    for (const auto& c : in) {
      const Eigen::Vector3f ns = rotation_ * (*source_)[c.index_query].getNormalVector3fMap();
      const float d = ns.dot((*target_)[c.index_match].getNormalVector3fMap());
      if (std::fabs(d) < min_cos_) continue;
      out.push_back(c);
    }
  }

 protected:
  void applyRejection(pcl::Correspondences& out) override {
    getRemainingCorrespondences(*input_correspondences_, out);
  }

 private:
  pcl::PointCloud<pcl::PointNormal>::ConstPtr source_, target_;
  Eigen::Matrix3f rotation_ = Eigen::Matrix3f::Identity();
  float min_cos_;
};

constexpr int kNormalNeighbours = 12;  // k-NN of the plane fits on the downsampled clouds
constexpr double kMaxNormalAngleDeg = 30.0;  // correspondences with normals further apart drop

// The indices of the points of `cloud` within `dist` of some point of `ref` (and some a little
// further: whole cells of a grid of dist/2, the cells of `ref` dilated by two), in order.
std::vector<std::size_t> near_points(const PointCloud& cloud, const PointCloud& ref, double dist) {
  const double cell = dist / 2;
  auto key = [cell](const Eigen::Vector3f& p, int64_t& k) {
    const Eigen::Vector3d q = (p.cast<double>() / cell).array().floor();
    if (!(q.cwiseAbs().maxCoeff() < 1e5)) return false;  // beyond 100,000 cells: not cropped
    k = ((static_cast<int64_t>(q.x()) + (1 << 20)) << 42) |
        ((static_cast<int64_t>(q.y()) + (1 << 20)) << 21) |
        (static_cast<int64_t>(q.z()) + (1 << 20));
    return true;
  };
  std::vector<std::size_t> out;
  out.reserve(cloud.size());
  std::unordered_set<int64_t> occupied;
  for (const auto& p : ref) {
    int64_t k;
    if (!key(p, k)) {  // not cropped: every point
      for (std::size_t i = 0; i < cloud.size(); ++i) out.push_back(i);
      return out;
    }
    occupied.insert(k);
  }
  std::unordered_set<int64_t> dilated;
  dilated.reserve(occupied.size() * 30);
  for (const int64_t k : occupied) {
    for (int64_t dx = -2; dx <= 2; ++dx) {
      for (int64_t dy = -2; dy <= 2; ++dy) {
        for (int64_t dz = -2; dz <= 2; ++dz) {
          dilated.insert(k + (dx << 42) + (dy << 21) + dz);
        }
      }
    }
  }
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    int64_t k;
    if (!key(cloud[i], k) || dilated.count(k)) out.push_back(i);
  }
  return out;
}

PointCloud finite_points(const PointCloud& in) {
  PointCloud out;
  out.reserve(in.size());
  for (const auto& p : in) {
    if (p.allFinite()) out.push_back(p);
  }
  return out;
}

// Points with usable normals, those of `pts` at `indices` (all: none given) with their normals
// fitted beforehand; points without a plane are dropped.
pcl::PointCloud<pcl::PointNormal>::Ptr with_normals(const PointCloud& pts, const SurfaceNormals& sn,
                                                    const std::vector<std::size_t>* indices = nullptr) {
  pcl::PointCloud<pcl::PointNormal>::Ptr out(new pcl::PointCloud<pcl::PointNormal>);
  const std::size_t n = indices ? indices->size() : pts.size();
  out->reserve(n);
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t i = indices ? (*indices)[j] : j;
    if (!sn.valid[i]) continue;
    pcl::PointNormal o;
    o.getVector3fMap() = pts[i];
    o.getNormalVector3fMap() = sn.normals[i];
    o.curvature = sn.curvature[i];
    out->push_back(o);
  }
  out->width = static_cast<uint32_t>(out->size());
  out->height = 1;
  out->is_dense = true;
  return out;
}

// The same with the normals fitted to `pts`' own nearest neighbours (estimate_normals).
pcl::PointCloud<pcl::PointNormal>::Ptr with_normals(const PointCloud& pts) {
  return with_normals(pts, estimate_normals(pts, kNormalNeighbours));
}

}  // namespace

PointCloud transform_cloud(const PointCloud& cloud, const Pose& transform) {
  PointCloud out;
  out.reserve(cloud.size());
  const Eigen::Matrix3d r = transform.linear();
  const Eigen::Vector3d t = transform.translation();
  for (const auto& p : cloud) {
    out.push_back((r * p.cast<double>() + t).cast<float>());
  }
  return out;
}

// How well an overlap pins the alignment down: the smallest eigenvalue of the point-to-plane
// information matrix H = mean(J J^T), J = [(x - c) x n / L; n] (c: centroid, L: RMS radius of
// the overlap, so rotations and translations are on one scale; eigenvalues in [0, 1]), and its
// eigenvector (the freest direction: rotation part first). Fewer than 6 pairs: 0.
double overlap_constraint(const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& pairs,
                          Eigen::Matrix<double, 6, 1>* weakest) {
  if (pairs.size() < 6) return 0.0;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& pr : pairs) c += pr.first;
  c /= static_cast<double>(pairs.size());
  double l2 = 0;
  for (const auto& pr : pairs) l2 += (pr.first - c).squaredNorm();
  const double L = std::sqrt(l2 / static_cast<double>(pairs.size()));
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  for (const auto& pr : pairs) {
    const Eigen::Vector3d n = pr.second.normalized();
    Eigen::Matrix<double, 6, 1> j;
    j << (pr.first - c).cross(n) / std::max(L, 1e-9), n;
    H += j * j.transpose();
  }
  H /= static_cast<double>(pairs.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(H);
  if (weakest) *weakest = eig.eigenvectors().col(0);
  return std::max(0.0, eig.eigenvalues()[0]);
}

namespace {

using Tree = IndexSearch<pcl::PointNormal>;
using Cloud = pcl::PointCloud<pcl::PointNormal>;

// Whether the overlap at the kinematic pose pins the alignment down: a plane or a sphere lets ICP
// slide until it runs out of iterations, so ICP is skipped then. Pairs within the coarsest
// correspondence distance (the kinematic pose may be off by several mm); a conservative threshold
// (half the gate's): the final gate decides.
bool overlap_pins_alignment(const Cloud& source, const Cloud& target, const Tree& tree, const RegistrationParams& params) {
  if (target.size() < 10 || source.size() < 10) return true;
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> near;
  const float r2 = static_cast<float>(params.max_correspondence_m * params.max_correspondence_m);
  for (const auto& p : source) {
    float d2;
    const pcl::index_t i = tree.index().nearest(p.getVector3fMap(), r2, d2);
    if (i >= 0) near.emplace_back(p.getVector3fMap().cast<double>(), target[i].getNormalVector3fMap().cast<double>());
  }
  return near.size() < 6 || overlap_constraint(near, nullptr) >= 0.5 * params.min_constraint;
}

// Point-to-plane ICP from the kinematic pose, coarse to fine. Returns the transform; sets
// res.iterations and res.converged, and `note` to why it did not converge.
Eigen::Matrix4d run_icp(const Cloud::Ptr& source, const Cloud::Ptr& target, Tree::Ptr tree, const RegistrationParams& params,
                        double voxel, RegistrationResult& res, std::string& note) {
  Eigen::Matrix4d t_final = Eigen::Matrix4d::Identity();
  Icp icp;
  icp.setInputSource(source);
  icp.setInputTarget(target);
  icp.setSearchMethodTarget(tree, true);
  icp.setMaximumIterations(std::max(params.max_iterations, 1));
  // A stage ends when a step moves less than 10 um and 0.001 deg (pcl compares the squared
  // translation and the rotation's cosine).
  icp.setTransformationEpsilon(1e-5 * 1e-5);
  icp.setTransformationRotationEpsilon(std::cos(1e-3 * kPi / 180.0));
  icp.setEuclideanFitnessEpsilon(1e-9);
  // Point-to-plane pulls only along the model's normal; a frame point on a surface the model
  // has not seen, matched to the edge of one it has, would pull sideways. Normal agreement
  // drops those pairs (it halved the rotation error on partial-overlap frames).
  auto rejector = std::make_shared<NormalCompatibilityRejector>(source, target, kMaxNormalAngleDeg);
  icp.addCorrespondenceRejector(rejector);
  // Coarse to fine: each stage halves the correspondence distance, from
  // max_correspondence_m down to the overlap distance (at least 1.5 voxels) so the part of
  // the frame the model has not seen does not pull. max_iterations is per stage.
  std::vector<double> stages;
  const double finest = std::max(params.overlap_distance_m, 1.5 * voxel);
  for (double d = params.max_correspondence_m; d > finest * 1.0001; d *= 0.5) stages.push_back(d);
  stages.push_back(std::min(finest, params.max_correspondence_m));
  pcl::PointCloud<pcl::PointNormal> aligned;
  bool converged = false;
  int state = Criteria::CONVERGENCE_CRITERIA_NOT_CONVERGED;
  for (double d : stages) {
    icp.setMaxCorrespondenceDistance(d);
    tree->set_k1_bound(d * 1.001);
    rejector->set_rotation(t_final.topLeftCorner<3, 3>().cast<float>());
    icp.align(aligned, t_final);
    res.iterations += icp.iterations();
    state = icp.getConvergeCriteria()->getConvergenceState();
    converged = icp.hasConverged();
    if (state == Criteria::CONVERGENCE_CRITERIA_NO_CORRESPONDENCES) {
      note = fmt::format("no correspondences within {:.1f} mm", d * 1e3);
      break;
    }
    t_final = icp.getFinalTransformation();
  }
  res.converged = converged && state != Criteria::CONVERGENCE_CRITERIA_ITERATIONS &&
                  state != Criteria::CONVERGENCE_CRITERIA_FAILURE_AFTER_MAX_ITERATIONS;
  if (!res.converged && note.empty()) {
    note = "ICP did not converge in the final stage's " + std::to_string(params.max_iterations) + " iterations";
  }
  return t_final;
}

// The rigid correction of ICP's estimate (a product of small rigid steps), orthonormalised; sets
// res.correction, its size, and, for a non-finite estimate, the identity and `note`.
void set_correction(const Eigen::Matrix4d& t_final, RegistrationResult& res, std::string& note) {
  Pose correction = Pose::Identity();
  Eigen::Quaterniond q(Eigen::Matrix3d(t_final.topLeftCorner<3, 3>()));
  q.normalize();
  correction.linear() = q.toRotationMatrix();
  correction.translation() = t_final.topRightCorner<3, 1>();
  if (!correction.matrix().allFinite()) {
    correction = Pose::Identity();
    res.converged = false;
    note = "ICP produced a non-finite transform";
  }
  res.correction = correction;
  res.translation_m = correction.translation().norm();
  res.rotation_deg = rad_to_deg(rotation_angle_rad(Eigen::Matrix3d::Identity(), correction.linear()));
}

// The fit after alignment, on the downsampled frame against the cropped model: res.overlap,
// res.rmse_m (point-to-plane) and res.constraint, and the overlap's pairs (aligned point, model
// normal); returns the overlap's weakest direction.
Eigen::Matrix<double, 6, 1> measure_fit(const PointCloud& frame_ds, const Cloud& target, const Tree& tree,
                                        const RegistrationParams& params, RegistrationResult& res,
                                        std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& pairs) {
  std::size_t n_overlap = 0;
  double sum_sq = 0;
  pairs.clear();  // aligned point, model normal
  if (target.size() >= 3) {
    const float r2 = static_cast<float>(params.overlap_distance_m * params.overlap_distance_m);
    const Eigen::Matrix3f r = res.correction.linear().cast<float>();
    const Eigen::Vector3f t = res.correction.translation().cast<float>();
    pcl::PointNormal q;
    for (const auto& p : frame_ds) {
      q.getVector3fMap() = r * p + t;
      float d2;
      const pcl::index_t i = tree.index().nearest(q.getVector3fMap(), r2, d2);
      if (i < 0) continue;
      ++n_overlap;
      // Point-to-plane distance to the model's local surface.
      const auto& m = target[i];
      const double e = (q.getVector3fMap() - m.getVector3fMap()).cast<double>().dot(m.getNormalVector3fMap().cast<double>());
      sum_sq += e * e;
      pairs.emplace_back(q.getVector3fMap().cast<double>(), m.getNormalVector3fMap().cast<double>());
    }
  }
  Eigen::Matrix<double, 6, 1> weakest = Eigen::Matrix<double, 6, 1>::Zero();
  res.constraint = overlap_constraint(pairs, &weakest);
  res.overlap = static_cast<double>(n_overlap) / static_cast<double>(frame_ds.size());
  res.rmse_m = n_overlap ? std::sqrt(sum_sq / static_cast<double>(n_overlap)) : 0.0;
  return weakest;
}

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Pairs = std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>;



}  // namespace

Eigen::Matrix3d skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d m;
  m << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return m;
}

namespace {

// The prior's covariance of a correction about c: the camera turned by dtheta about its own
// centre p and moved by dt moves c by dt + dtheta x (c - p). The correction is against the model,
// whose frame carries the kinematic errors of the views before (the first view's placed it): the
// difference of two poses each off by the prior, twice its variance.
Mat6 prior_covariance(const RegistrationParams& params, const Eigen::Vector3d& c, const std::optional<Eigen::Vector3d>& camera_m) {
  const Eigen::Vector3d a = camera_m ? Eigen::Vector3d(c - *camera_m) : Eigen::Vector3d::Zero();
  Mat6 j = Mat6::Identity();
  j.bottomLeftCorner<3, 3>() = -skew(a);
  const double sr = deg_to_rad(std::max(params.prior_rotation_deg, 1e-6));
  const double st = std::max(params.prior_translation_m, 1e-9);
  Vec6 var;
  var << sr * sr, sr * sr, sr * sr, st * st, st * st, st * st;
  return 2.0 * j * var.asDiagonal() * j.transpose();
}

// The covariance of ICP's correction about c: the inverse of the point-to-plane information
// (rows [(x - c) x n, n] over the overlap's pairs, divided by the residual's variance and by the
// pairs per independent one), plus a floor no fit is better than: min_residual_m in translation,
// and in rotation the angle it makes over the overlap's RMS radius. Called only where the overlap
// constrains every direction (the information is invertible).
Mat6 icp_covariance(const Pairs& pairs, const Eigen::Vector3d& c, double residual_m, const RegistrationParams& params) {
  Mat6 h = Mat6::Zero();
  double r2 = 0;
  for (const auto& [x, n] : pairs) {
    Vec6 j;
    j << (x - c).cross(n.normalized()), n.normalized();
    h += j * j.transpose();
    r2 += (x - c).squaredNorm();
  }
  const double sigma = std::max(residual_m, params.min_residual_m);
  h /= sigma * sigma * std::max(params.pairs_per_independent, 1.0);
  const double radius = std::sqrt(r2 / static_cast<double>(std::max<std::size_t>(pairs.size(), 1)));
  const double floor_t = params.min_residual_m, floor_r = params.min_residual_m / std::max(radius, 1e-3);
  Vec6 floor;
  floor << floor_r * floor_r, floor_r * floor_r, floor_r * floor_r, floor_t * floor_t, floor_t * floor_t, floor_t * floor_t;
  return Mat6(h.inverse()) + Mat6(floor.asDiagonal());
}

std::string direction_text(const Vec6& weakest) {
  const bool rotation = weakest.head<3>().norm() > weakest.tail<3>().norm();
  const Eigen::Vector3d axis = (rotation ? weakest.head<3>() : weakest.tail<3>()).normalized();
  return std::string(rotation ? "rotation about " : "translation along ") + fmt::format("({:.2f}, ", axis.x()) +
         fmt::format("{:.2f}, ", axis.y()) + fmt::format("{:.2f})", axis.z());
}

// Keeps the kinematic pose: the correction undone, its size zero.
void keep_kinematic(RegistrationResult& res) {
  res.refined = false;
  res.correction = Pose::Identity();
  res.translation_m = 0;
  res.rotation_deg = 0;
}

// The verdict. Is ICP's alignment to be trusted (does the view fit the model; did ICP settle on a
// plausible correction)? Where the overlap leaves a direction free, ICP's motion means nothing (it
// slides): the kinematic pose is kept, unflagged if the view fits the model. A trusted correction
// is weighed against the prior: beyond max_prior_sigmas it is not taken (flagged); else the one
// taken is the prior and ICP's estimate combined by their information. Every view is merged.
void judge(const RegistrationParams& params, const Vec6& weakest, const Pairs& pairs,
           const std::optional<Eigen::Vector3d>& camera_m, const std::string& icp_note, const std::string& dropped_note,
           RegistrationResult& res) {
  res.accepted = true;
  res.icp_translation_m = res.translation_m;
  res.icp_rotation_deg = res.rotation_deg;
  std::vector<std::string> fails, motion_fails;
  if (res.overlap < params.min_overlap) {
    fails.push_back(fmt::format("overlap {:.2f}", res.overlap) + fmt::format(" below {:.2f}", params.min_overlap));
  }
  if (res.overlap == 0 || res.rmse_m > params.max_rmse_m) {
    fails.push_back(res.overlap == 0 ? std::string("rmse undefined (no overlapping points)")
                                     : fmt::format("rmse {:.2f} mm", res.rmse_m * 1e3) +
                                           fmt::format(" exceeds {:.2f} mm", params.max_rmse_m * 1e3));
  }
  if (res.translation_m > params.max_translation_m) {
    motion_fails.push_back(fmt::format("correction {:.3f} m", res.translation_m) +
                           fmt::format(" exceeds {:.3f} m", params.max_translation_m));
  }
  if (res.rotation_deg > params.max_rotation_deg) {
    motion_fails.push_back(fmt::format("correction {:.2f} deg", res.rotation_deg) +
                           fmt::format(" exceeds {:.2f} deg", params.max_rotation_deg));
  }
  if (!res.converged) motion_fails.push_back("not converged: " + icp_note);
  const bool degenerate = res.constraint < params.min_constraint;
  if (!degenerate) fails.insert(fails.end(), motion_fails.begin(), motion_fails.end());
  const std::string icp_said =
      fmt::format("ICP {:.2f} mm, ", res.icp_translation_m * 1e3) + fmt::format("{:.3f} deg", res.icp_rotation_deg);

  if (!fails.empty()) {
    keep_kinematic(res);
    res.flagged = true;
    res.reason = "kinematic pose kept, flagged (alignment not trusted: ";
    for (std::size_t i = 0; i < fails.size(); ++i) res.reason += (i ? "; " : "") + fails[i];
    res.reason += ")" + dropped_note;
    return;
  }
  if (degenerate) {
    res.reason = "kinematic pose kept: the overlap does not constrain the alignment (weakest direction: " +
                 direction_text(weakest) + fmt::format(", constraint {:.4f}", res.constraint) +
                 fmt::format(" below {:.4f}", params.min_constraint) +
                 fmt::format("; ICP would have moved it {:.2f} mm)", res.icp_translation_m * 1e3) + dropped_note;
    keep_kinematic(res);
    return;
  }
  // ICP's correction about the overlap's centre (where the kinematic pose put it).
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& pr : pairs) centre += pr.first;
  centre = res.correction.inverse() * Eigen::Vector3d(centre / static_cast<double>(pairs.size()));
  const Vec6 icp = twist_about(res.correction, centre);
  // The innovation: ICP's proposal against the kinematic pose, each with its covariance.
  const Mat6 prior = prior_covariance(params, centre, camera_m);
  const Mat6 icp_cov = icp_covariance(pairs, centre, res.rmse_m, params);
  const Mat6 both = prior + icp_cov;
  const Eigen::LDLT<Mat6> both_ldlt(both);
  res.prior_sigmas = std::sqrt(std::max(0.0, icp.dot(both_ldlt.solve(icp))));
  const std::string prior_text = fmt::format("the kinematic pose's sigma {:.2f} mm, ", params.prior_translation_m * 1e3) +
                                 fmt::format("{:.3f} deg", params.prior_rotation_deg);
  if (res.prior_sigmas > params.max_prior_sigmas) {
    keep_kinematic(res);
    res.flagged = true;
    res.reason = "kinematic pose kept, flagged (" + icp_said + fmt::format(" is {:.1f} sigma", res.prior_sigmas) +
                 " of " + prior_text + fmt::format(", above {:.1f})", params.max_prior_sigmas) + dropped_note;
    return;
  }
  res.icp = IcpProposal{res.correction, centre, icp_cov};
  // The two combined (a Kalman update from the kinematic pose): prior (prior + icp)^-1 proposal.
  const Vec6 taken = prior * both_ldlt.solve(icp);
  res.correction = pose_from_twist(taken, centre);
  res.translation_m = res.correction.translation().norm();
  res.rotation_deg = rad_to_deg(rotation_angle_rad(Eigen::Matrix3d::Identity(), res.correction.linear()));
  res.refined = true;
  res.reason = "corrected " + fmt::format("{:.2f} mm, ", res.translation_m * 1e3) +
               fmt::format("{:.3f} deg (", res.rotation_deg) + icp_said + fmt::format(" at {:.1f} sigma of ", res.prior_sigmas) +
               prior_text + fmt::format("; overlap {:.2f}, ", res.overlap) + fmt::format("rmse {:.2f} mm", res.rmse_m * 1e3) +
               fmt::format(", constraint {:.4f})", res.constraint) + dropped_note;
}

// register_frame's steps after the inputs' checks; throws what PCL throws.
void align_and_judge(const RegistrationModel& model, const PointCloud& frame_ds, const RegistrationParams& params,
                     const std::optional<Eigen::Vector3d>& camera_m, const std::string& dropped_note, RegistrationResult& res) {
  const double voxel = params.voxel_m;
  // Only the part of the model the frame can reach matters: keep the model points within
  // `margin` (the largest correspondence distance plus room for the normals) of the frame,
  // via a grid of margin/2 cells: the frame's cells dilated by two.
  const double margin = std::max(params.max_correspondence_m, params.overlap_distance_m) + 4.0 * voxel;
  const std::vector<std::size_t> near = near_points(model.points, frame_ds, margin);
  // The model's normals fitted beforehand over all of it, else here over the part near the frame.
  pcl::PointCloud<pcl::PointNormal>::Ptr target;
  if (model.normals.valid.size() == model.points.size()) {
    target = with_normals(model.points, model.normals, &near);
  } else {
    PointCloud crop;
    crop.reserve(near.size());
    for (const std::size_t i : near) crop.push_back(model.points[i]);
    target = with_normals(crop);
  }
  const auto source = with_normals(frame_ds);
  Tree::Ptr tree(new Tree);
  if (target->size() >= 3) tree->setInputCloud(target);

  Eigen::Matrix4d t_final = Eigen::Matrix4d::Identity();
  std::string icp_note;
  if (!overlap_pins_alignment(*source, *target, *tree, params)) {
    res.converged = true;
    icp_note = "skipped: the overlap does not constrain the alignment";
  } else if (target->size() >= 10 && source->size() >= 10) {
    t_final = run_icp(source, target, tree, params, voxel, res, icp_note);
  } else {
    icp_note = "no model points near the frame";
  }
  set_correction(t_final, res, icp_note);
  Pairs pairs;
  const Vec6 weakest = measure_fit(frame_ds, *target, *tree, params, res, pairs);
  judge(params, weakest, pairs, camera_m, icp_note, dropped_note, res);
}

}  // namespace

RegistrationModel registration_model(const PointCloud& model, const RegistrationParams& params, bool fit_normals) {
  RegistrationModel m;
  m.voxel_m = params.voxel_m;
  try {
    const PointCloud finite = finite_points(model);
    m.finite = finite.size();
    m.dropped = model.size() - finite.size();
    if (!finite.empty()) m.points = voxel_downsample(finite, params.voxel_m);
    if (fit_normals && m.points.size() >= 3) m.normals = estimate_normals(m.points, kNormalNeighbours);
  } catch (const std::exception& e) {
    m.error = e.what();
  } catch (...) {
    m.error = "preparing the model failed";
  }
  if (fit_normals) {  // one entry per point whatever happened (none fitted: every point without a plane)
    m.normals.normals.resize(m.points.size(), Eigen::Vector3f::Zero());
    m.normals.curvature.resize(m.points.size(), 0.0f);
    m.normals.valid.resize(m.points.size(), 0);
  }
  return m;
}

RegistrationResult register_frame(const RegistrationModel& model, const PointCloud& frame, const RegistrationParams& params,
                                  const std::optional<Eigen::Vector3d>& camera_m) {
  if (model.voxel_m != params.voxel_m) {
    throw std::invalid_argument(fmt::format("register_frame: the model was prepared for {:.1f} mm voxels, not {:.1f} mm",
                                            model.voxel_m * 1e3, params.voxel_m * 1e3));
  }
  const auto t0 = Clock::now();
  RegistrationResult res;
  const std::size_t frame_finite = static_cast<std::size_t>(
      std::count_if(frame.begin(), frame.end(), [](const Eigen::Vector3f& p) { return p.allFinite(); }));
  // What is left when ICP cannot run: the view at its kinematic pose, flagged (none: no view).
  auto kinematic_only = [&](const std::string& why) {
    res = RegistrationResult{};
    res.accepted = frame_finite > 0;
    res.flagged = true;
    res.reason = (res.accepted ? "kinematic pose kept, flagged (" : "not merged (") + why + ")";
  };
  try {
    if (!model.error.empty()) throw std::runtime_error(model.error);
    const PointCloud frame_f = finite_points(frame);
    const std::size_t dropped = model.dropped + (frame.size() - frame_f.size());
    const std::string dropped_note = dropped ? " (" + std::to_string(dropped) + " non-finite points dropped)" : "";
    const PointCloud frame_ds = model.finite == 0 ? PointCloud() : voxel_downsample(frame_f, params.voxel_m);
    const std::size_t min_points = static_cast<std::size_t>(std::max(params.min_points, 3));
    if (frame_f.empty()) {
      kinematic_only("no finite point in the view" + dropped_note);
    } else if (model.finite == 0) {
      res.accepted = true;
      res.converged = true;
      res.reason = "first frame: defines the model" + dropped_note;
    } else if (frame_ds.size() < min_points || model.points.size() < min_points) {
      kinematic_only("too few points to align: frame " + std::to_string(frame_ds.size()) + ", model " +
                     std::to_string(model.points.size()) + " after " + fmt::format("{:.1f}", params.voxel_m * 1e3) +
                     " mm downsampling (of " + std::to_string(frame_f.size()) + " and " + std::to_string(model.finite) +
                     " finite points), need " + std::to_string(min_points) + dropped_note);
    } else {
      align_and_judge(model, frame_ds, params, camera_m, dropped_note, res);
    }
  } catch (const std::exception& e) {
    kinematic_only(std::string("registration failed: ") + e.what());
  } catch (...) {
    kinematic_only("registration failed");
  }
  res.time_s = std::chrono::duration<double>(Clock::now() - t0).count();
  return res;
}

RegistrationResult register_frame(const PointCloud& model, const PointCloud& frame, const RegistrationParams& params,
                                  const std::optional<Eigen::Vector3d>& camera_m) {
  const auto t0 = Clock::now();
  RegistrationResult res = register_frame(registration_model(model, params, false), frame, params, camera_m);
  res.time_s = std::chrono::duration<double>(Clock::now() - t0).count();  // the model's preparing too
  return res;
}

Twist twist_about(const Pose& t, const Eigen::Vector3d& c) {
  const Eigen::AngleAxisd aa(t.linear());
  Twist d;
  d << aa.angle() * aa.axis(), t * c - c;
  return d;
}

Pose pose_from_twist(const Twist& d, const Eigen::Vector3d& c) {
  const Eigen::Vector3d w = d.head<3>();
  const double angle = w.norm();
  Pose t = Pose::Identity();
  if (angle > 0) t.linear() = Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
  t.translation() = c + d.tail<3>() - t.linear() * c;
  return t;
}

}  // namespace pbnbv
