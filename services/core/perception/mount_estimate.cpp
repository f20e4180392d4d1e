#include "core/perception/mount_estimate.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

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

void MountEstimator::refit() {
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
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> rot(estimate_.covariance.topLeftCorner<3, 3>());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> tra(estimate_.covariance.bottomRightCorner<3, 3>());
  estimate_.sigma_deg = std::sqrt(std::max(0.0, rot.eigenvalues().maxCoeff())) * 180.0 / kPi;
  estimate_.sigma_m = std::sqrt(std::max(0.0, tra.eigenvalues().maxCoeff()));
}

}  // namespace pbnbv
