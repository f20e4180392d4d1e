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

Pose MountEstimator::object_T_model() const {
  if (!first_) return Pose::Identity();
  return *first_ * estimate_.error * first_->inverse();
}

// Gauss-Newton on E's twist e: residual per view twist_about(D_obs D(e)^-1, c) (ICP's proposal
// against the one predicted, about the overlap's centre), weighed by ICP's covariance there;
// the prior N(0, diag(r^2, t^2)) on e. Jacobians by central differences.
bool MountEstimator::trusted(int min_views) const {
  return first_ && estimate_.views >= min_views && estimate_.sigma_m <= 1e-3 && estimate_.sigma_deg <= 0.2;
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
  Pose kinematic;
  PointCloud points;
  std::vector<Eigen::Vector3f> normals;
  std::unique_ptr<NeighbourIndex> index;
};

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace

// Residual of a pair (p of view i, q with normal n of view j, both in their camera frames):
// r = n . (M p - q) with M = E^-1 K_j^-1 K_i E. E moved by exp(xi) on its right: M p moves by
// -R_M [p]x w + [M p]x w + (R_M - I) v to first order (xi = (w, v), a twist about the camera centre).
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

  MountEstimate out;
  out.error = start;
  out.covariance = prior_info.inverse();
  const double cos_max = std::cos(params.max_normal_angle_deg * kPi / 180.0);
  TwistCovariance info_pairs = TwistCovariance::Zero();
  double residual_var = params.min_residual_m * params.min_residual_m;
  std::vector<char> paired(fit.size(), 0);
  for (std::size_t stage = 0; stage < params.correspondence_m.size() && fit.size() >= 2; ++stage) {
    const float max_d2 = static_cast<float>(params.correspondence_m[stage] * params.correspondence_m[stage]);
    for (int iteration = 0; iteration < params.iterations_per_stage; ++iteration) {
      TwistCovariance h = TwistCovariance::Zero();
      Twist g = Twist::Zero();
      double sum_r2 = 0;
      long pairs = 0;
      std::fill(paired.begin(), paired.end(), 0);
      const Pose e_inv = out.error.inverse();
      for (std::size_t i = 0; i < fit.size(); ++i) {
        for (std::size_t j = 0; j < fit.size(); ++j) {
          if (i == j) continue;
          const Pose m = e_inv * fit[j].kinematic.inverse() * fit[i].kinematic * out.error;
          const Eigen::Matrix3d rm = m.linear();
          const Eigen::Matrix3d rm_minus_i = rm - Eigen::Matrix3d::Identity();
          long found = 0;
          for (std::size_t a = 0; a < fit[i].points.size(); ++a) {
            const Eigen::Vector3d p = fit[i].points[a].cast<double>();
            const Eigen::Vector3d y = m * p;
            float d2 = 0;
            const int b = fit[j].index->nearest(y.cast<float>(), max_d2, d2);
            if (b < 0) continue;
            const Eigen::Vector3d n = fit[j].normals[static_cast<std::size_t>(b)].cast<double>();
            if (n.dot(rm * fit[i].normals[a].cast<double>()) < cos_max) continue;
            const double r = n.dot(y - fit[j].points[static_cast<std::size_t>(b)].cast<double>());
            Twist jac;
            jac.head<3>() = (-(rm * skew(p)) + skew(y)).transpose() * n;
            jac.tail<3>() = rm_minus_i.transpose() * n;
            // Huber weight beyond a third of the stage's distance: a wrong pair pulls less.
            const double k = params.correspondence_m[stage] / 3;
            const double w = std::abs(r) <= k ? 1.0 : k / std::abs(r);
            h += w * jac * jac.transpose();
            g += w * jac * r;
            sum_r2 += w * r * r;
            ++pairs;
            ++found;
          }
          if (found > 0) paired[i] = paired[j] = 1;
        }
      }
      if (pairs < 6) break;
      residual_var = std::max(sum_r2 / static_cast<double>(pairs), params.min_residual_m * params.min_residual_m);
      const double scale = 1.0 / (residual_var * params.pairs_per_independent);
      info_pairs = h * scale;
      const Twist now = twist_about(out.error, Eigen::Vector3d::Zero());
      const TwistCovariance total = info_pairs + prior_info;
      const Twist delta = -total.ldlt().solve(g * scale + prior_info * now);
      out.error = out.error * pose_from_twist(delta, Eigen::Vector3d::Zero());
      if (delta.head<3>().norm() < 1e-7 && delta.tail<3>().norm() < 1e-7) break;
    }
  }
  out.covariance = (info_pairs + prior_info).inverse();
  out.views = static_cast<int>(std::count(paired.begin(), paired.end(), 1));
  set_sigmas(out);
  return out;
}

}  // namespace pbnbv
