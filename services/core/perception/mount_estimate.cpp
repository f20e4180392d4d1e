#include "core/perception/mount_estimate.hpp"

#include "core/perception/neighbours.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>

namespace pbnbv {

namespace {

constexpr double kPi = 3.14159265358979323846;

// E from its twist about the camera centre (the origin of the camera frame).
Pose error_of(const Twist& e) { return pose_from_twist(e, Eigen::Vector3d::Zero()); }

}  // namespace

double MountEstimate::translation_m() const { return error.translation().norm(); }
double MountEstimate::rotation_deg() const { return Eigen::AngleAxisd(error.linear()).angle() * 180.0 / kPi; }

Pose mount_correction(const Pose& first, const Pose& kinematic, const Pose& error) {
  return first * error.inverse() * first.inverse() * kinematic * error * kinematic.inverse();
}

MountEstimator::MountEstimator(double prior_translation_m, double prior_rotation_deg)
    : prior_t_(std::max(prior_translation_m, 1e-6)), prior_r_(std::max(prior_rotation_deg, 1e-4) * kPi / 180.0) {
  refit();
}

void MountEstimator::set_first(const Pose& kinematic) {
  first_ = kinematic;
  observations_.clear();
  from_views_.reset();
  refit();
}

void MountEstimator::set_from_views(const MountEstimate& e) {
  from_views_ = e;
  refit();
}

void MountEstimator::add(const MountObservation& o) {
  if (!first_) return;
  observations_.push_back(o);
  refit();
}

Pose MountEstimator::predicted_correction(const Pose& kinematic) const {
  if (!first_) return Pose::Identity();
  return mount_correction(*first_, kinematic, estimate_.error);
}

std::optional<Pose> MountEstimator::fitted_correction(int view, const Pose& kinematic) const {
  if (!first_ || !from_views_) return std::nullopt;
  for (const auto& [id, own] : estimate_.view_errors) {
    if (id == view) return mount_correction(*first_, kinematic, estimate_.error) * kinematic * own * kinematic.inverse();
  }
  return std::nullopt;
}

Pose MountEstimator::object_T_model() const {
  if (!first_) return Pose::Identity();
  return *first_ * estimate_.error * first_->inverse();
}

// Gauss-Newton on E's twist e: residual per view twist_about(C_obs C(e)^-1, c) (ICP's proposal
// against the one predicted, about the overlap's centre), weighed by ICP's covariance there;
// the prior N(0, diag(r^2, t^2)) on e. Jacobians by central differences.
bool MountEstimator::trusted(int min_views) const {
  if (!first_ || estimate_.views < min_views) return false;
  const double sigma_r = estimate_.sigma_deg * kPi / 180.0;
  return (estimate_.sigma_m <= 1e-3 && estimate_.sigma_deg <= 0.2) ||
         (estimate_.sigma_m <= 0.5 * prior_t_ && sigma_r <= 0.5 * prior_r_);
}

// Sigma per axis of a twist covariance: the largest over rotation (degrees) and translation (m).
static void set_sigmas(MountEstimate& e) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> rot(e.covariance.topLeftCorner<3, 3>());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> tra(e.covariance.bottomRightCorner<3, 3>());
  e.sigma_deg = std::sqrt(std::max(0.0, rot.eigenvalues().maxCoeff())) * 180.0 / kPi;
  e.sigma_m = std::sqrt(std::max(0.0, tra.eigenvalues().maxCoeff()));
}

void MountEstimator::refit() {
  if (from_views_ && first_) {
    // The clouds' fit is the estimate; a proposal more than 4 sigma from what it predicts slid.
    estimate_ = *from_views_;
    estimate_.outliers = 0;
    outlier_views_.clear();
    for (const MountObservation& o : observations_) {
      const Pose d = mount_correction(*first_, o.kinematic, estimate_.error);
      const Twist r = twist_about(o.proposal.correction * d.inverse(), o.proposal.centre);
      const TwistCovariance c = o.proposal.covariance;
      if (std::sqrt(std::max(0.0, r.dot(c.ldlt().solve(r)))) > 4.0) {
        outlier_views_.push_back(o.view);
        ++estimate_.outliers;
      }
    }
    return;
  }
  Twist prior_var;
  prior_var << prior_r_ * prior_r_, prior_r_ * prior_r_, prior_r_ * prior_r_, prior_t_ * prior_t_, prior_t_ * prior_t_,
      prior_t_ * prior_t_;
  const TwistCovariance prior_info = prior_var.cwiseInverse().asDiagonal();
  std::vector<TwistCovariance> weights;
  for (const MountObservation& o : observations_) weights.push_back(o.proposal.covariance.inverse());
  const auto residual = [&](const MountObservation& o, const Twist& x) -> Twist {
    const Pose d = mount_correction(*first_, o.kinematic, error_of(x));
    return twist_about(o.proposal.correction * d.inverse(), o.proposal.centre);
  };
  std::vector<char> used(observations_.size(), 1);
  Twist e = Twist::Zero();
  TwistCovariance h = prior_info;
  int outliers = 0;
  for (;;) {
    e = Twist::Zero();
    for (int iteration = 0; iteration < 8 && first_; ++iteration) {
      h = prior_info;
      Twist g = prior_info * e;  // gradient of the prior's term
      for (std::size_t i = 0; i < observations_.size(); ++i) {
        if (!used[i]) continue;
        const Twist r = residual(observations_[i], e);
        Eigen::Matrix<double, 6, 6> j;
        for (int k = 0; k < 6; ++k) {
          const double step = k < 3 ? 1e-6 : 1e-7;
          Twist plus = e, minus = e;
          plus[k] += step;
          minus[k] -= step;
          j.col(k) = (residual(observations_[i], plus) - residual(observations_[i], minus)) / (2 * step);
        }
        h += j.transpose() * weights[i] * j;
        g += j.transpose() * weights[i] * r;
      }
      const Twist delta = -h.ldlt().solve(g);
      e += delta;
      if (delta.head<3>().norm() < 1e-9 && delta.tail<3>().norm() < 1e-9) break;
    }
    // The worst observation beyond 4 sigma (its residual against its own covariance) is left out
    // and the rest fitted again; at least two are kept.
    int used_count = 0, worst = -1;
    double worst_sigmas = 4.0;
    for (std::size_t i = 0; i < observations_.size(); ++i) {
      if (!used[i]) continue;
      ++used_count;
      const Twist r = residual(observations_[i], e);
      const double sigmas = std::sqrt(std::max(0.0, r.dot(weights[i] * r)));
      if (sigmas > worst_sigmas) {
        worst_sigmas = sigmas;
        worst = static_cast<int>(i);
      }
    }
    if (worst < 0 || used_count <= 2) break;
    used[static_cast<std::size_t>(worst)] = 0;
    ++outliers;
  }
  estimate_.error = error_of(e);
  estimate_.covariance = h.inverse();
  estimate_.views = static_cast<int>(std::count(used.begin(), used.end(), 1));
  estimate_.outliers = outliers;
  outlier_views_.clear();
  for (std::size_t i = 0; i < observations_.size(); ++i) {
    if (!used[i]) outlier_views_.push_back(observations_[i].view);
  }
  set_sigmas(estimate_);
}

namespace {

// A view thinned for the fit: every k-th point with a normal, and an index over its points.
struct FitView {
  int view = -1;
  Pose kinematic;
  PointCloud points;
  std::vector<Eigen::Vector3f> normals;
  std::unique_ptr<NeighbourIndex> index;
};

}  // namespace

// Residual of a pair (p of view i, q with normal n of view j, both in their camera frames):
// r = n . (M p - q) with M = T_j^-1 T_i, T_i = K_i E D_i (D_i: view i's own error). A step on the
// right of T_i moves M p by R_M (-[p]x w + v), one on the right of T_j by [M p]x w - v (xi = (w,
// v), twists about the camera centre); E's step moves both views (D_i is small: the step is taken
// as the same on the right of E D_i as of E).
MountEstimate mount_from_views(const std::vector<MountView>& views, const Pose& start, double prior_translation_m,
                               double prior_rotation_deg, const MountFitParams& params) {
  const double prior_t = std::max(prior_translation_m, 1e-6);
  const double prior_r = std::max(prior_rotation_deg, 1e-4) * kPi / 180.0;
  Twist prior_var;
  prior_var << prior_r * prior_r, prior_r * prior_r, prior_r * prior_r, prior_t * prior_t, prior_t * prior_t,
      prior_t * prior_t;
  const TwistCovariance prior_info = prior_var.cwiseInverse().asDiagonal();

  std::vector<FitView> fit;
  for (const MountView& v : views) {
    if (v.normals.size() != v.points.size()) continue;
    std::size_t usable = 0;
    for (std::size_t i = 0; i < v.points.size(); ++i) usable += v.points[i].allFinite() && v.normals[i].squaredNorm() > 0.25f;
    if (usable < static_cast<std::size_t>(std::max(params.min_points, 3))) continue;
    const std::size_t step = std::max<std::size_t>(1, usable / static_cast<std::size_t>(std::max(params.points_per_view, 1)));
    FitView f;
    f.view = v.view;
    f.kinematic = v.kinematic;
    std::size_t k = 0;
    for (std::size_t i = 0; i < v.points.size(); ++i) {
      if (!v.points[i].allFinite() || v.normals[i].squaredNorm() <= 0.25f) continue;
      if (k++ % step) continue;
      f.points.push_back(v.points[i]);
      f.normals.push_back(v.normals[i].normalized());
    }
    f.index = std::make_unique<NeighbourIndex>(f.points);
    fit.push_back(std::move(f));
  }

  // E and each view's own small pose error (joints, backlash: view i sits at K_i E D_i, D_i with
  // the per-view prior) are fitted together. Fitted alone, E took up what single views' errors
  // leave between the clouds: on turned parts, whose clouds slide along each other, it went 3-6 mm
  // from a mount 0.5 mm off (d435, calibrated, tune half), 0.5-1.2 mm on the others. E's
  // covariance is the joint fit's, the views' own errors marginalised out.
  const std::size_t n = fit.size();
  const int dim = 6 + 6 * static_cast<int>(n);
  const double view_t = std::max(params.per_view_translation_m, 1e-7);
  const double view_r = std::max(params.per_view_rotation_deg, 1e-5) * kPi / 180.0;
  Twist view_var;
  view_var << view_r * view_r, view_r * view_r, view_r * view_r, view_t * view_t, view_t * view_t, view_t * view_t;
  const TwistCovariance view_info = view_var.cwiseInverse().asDiagonal();
  const double cos_max = std::cos(params.max_normal_angle_deg * kPi / 180.0);
  Pose error = start;
  std::vector<Pose> own(n, Pose::Identity());  // D_i
  std::vector<char> paired(n, 0);
  // The point-to-plane normal equations over E's step and every view's own (6 + 6 n) at the
  // current E and D_i, for pairs closer than `max_m`. Returns the pairs' count and their mean
  // weighted squared residual.
  const auto accumulate = [&](double max_m, Eigen::MatrixXd& h, Eigen::VectorXd& g, double& mean_r2) {
    h = Eigen::MatrixXd::Zero(dim, dim);
    g = Eigen::VectorXd::Zero(dim);
    const float max_d2 = static_cast<float>(max_m * max_m);
    const double huber = max_m / 3;  // beyond it a pair pulls less
    double sum_r2 = 0;
    long pairs = 0;
    std::fill(paired.begin(), paired.end(), 0);
    const Pose e_inv = error.inverse();
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < n; ++j) {
        if (i == j) continue;
        // camera i -> camera j
        const Pose m = own[j].inverse() * e_inv * fit[j].kinematic.inverse() * fit[i].kinematic * error * own[i];
        const Eigen::Matrix3d rm = m.linear();
        const int at[3] = {0, 6 + 6 * static_cast<int>(i), 6 + 6 * static_cast<int>(j)};
        long found = 0;
        for (std::size_t k = 0; k < fit[i].points.size(); ++k) {
          const Eigen::Vector3d p = fit[i].points[k].cast<double>();
          const Eigen::Vector3d y = m * p;
          float d2 = 0;
          const int b = fit[j].index->nearest(y.cast<float>(), max_d2, d2);
          if (b < 0) continue;
          const Eigen::Vector3d nj = fit[j].normals[static_cast<std::size_t>(b)].cast<double>();
          if (nj.dot(rm * fit[i].normals[k].cast<double>()) < cos_max) continue;
          const double r = nj.dot(y - fit[j].points[static_cast<std::size_t>(b)].cast<double>());
          Eigen::Matrix<double, 18, 1> jac;  // E's step, view i's, view j's
          jac.segment<3>(6) = (-(rm * skew(p))).transpose() * nj;
          jac.segment<3>(9) = rm.transpose() * nj;
          jac.segment<3>(12) = skew(y).transpose() * nj;
          jac.segment<3>(15) = -nj;
          jac.head<6>() = jac.segment<6>(6) + jac.segment<6>(12);
          const double w = std::abs(r) <= huber ? 1.0 : huber / std::abs(r);
          for (int u = 0; u < 3; ++u) {
            g.segment<6>(at[u]) += w * r * jac.segment<6>(6 * u);
            for (int v = 0; v < 3; ++v) {
              h.block<6, 6>(at[u], at[v]) += w * jac.segment<6>(6 * u) * jac.segment<6>(6 * v).transpose();
            }
          }
          sum_r2 += w * r * r;
          ++pairs;
          ++found;
        }
        if (found > 0) paired[i] = paired[j] = 1;
      }
    }
    mean_r2 = pairs > 0 ? sum_r2 / static_cast<double>(pairs) : 0;
    return pairs;
  };
  // The pairs' information at their residual sigma (neighbouring pairs counted as one in
  // pairs_per_independent), with the priors on E and on every D_i.
  const auto with_priors = [&](Eigen::MatrixXd& h, Eigen::VectorXd& g, double mean_r2) {
    const double scale =
        1.0 / (std::max(mean_r2, params.min_residual_m * params.min_residual_m) * params.pairs_per_independent);
    h *= scale;
    g *= scale;
    h.topLeftCorner<6, 6>() += prior_info;
    g.head<6>() += prior_info * twist_about(error, Eigen::Vector3d::Zero());
    for (std::size_t i = 0; i < n; ++i) {
      const int at = 6 + 6 * static_cast<int>(i);
      h.block<6, 6>(at, at) += view_info;
      g.segment<6>(at) += view_info * twist_about(own[i], Eigen::Vector3d::Zero());
    }
  };
  Eigen::MatrixXd h;
  Eigen::VectorXd g;
  double mean_r2 = 0;
  double last_m = 0;
  for (std::size_t stage = 0; stage < params.correspondence_m.size() && n >= 2; ++stage) {
    for (int iteration = 0; iteration < params.iterations_per_stage; ++iteration) {
      if (accumulate(params.correspondence_m[stage], h, g, mean_r2) < 6) break;
      last_m = params.correspondence_m[stage];
      with_priors(h, g, mean_r2);
      const Eigen::VectorXd delta = -h.ldlt().solve(g);
      if (!delta.allFinite()) break;
      error = error * pose_from_twist(delta.head<6>(), Eigen::Vector3d::Zero());
      for (std::size_t i = 0; i < n; ++i) {
        own[i] = own[i] * pose_from_twist(delta.segment<6>(6 + 6 * static_cast<int>(i)), Eigen::Vector3d::Zero());
      }
      if (delta.cwiseAbs().maxCoeff() < 1e-7) break;
    }
  }
  MountEstimate out;
  out.error = error;
  out.covariance = prior_info.inverse();
  if (last_m > 0 && accumulate(last_m, h, g, mean_r2) >= 6) {
    with_priors(h, g, mean_r2);
    out.covariance = h.inverse().topLeftCorner<6, 6>();  // E's, the views' own errors marginalised
  } else {
    std::fill(paired.begin(), paired.end(), 0);
  }
  out.views = static_cast<int>(std::count(paired.begin(), paired.end(), 1));
  for (std::size_t i = 0; i < n; ++i) {
    if (paired[i]) out.view_errors.emplace_back(fit[i].view, own[i]);
  }
  set_sigmas(out);
  return out;
}

}  // namespace pbnbv
