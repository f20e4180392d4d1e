#pragma once
// Gaussian mixtures of 3-d points (docs/method.md "Ellipsoids", paper section III-C): EM from a
// k-means++ start, the number of components T chosen by BIC. The E-step is tuned for the planner
// step (vectorised, fixed summation order: the result depends only on the input).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace pbnbv {

struct GaussianMixture {
  std::vector<double> weights;
  std::vector<Eigen::Vector3d> means;
  std::vector<Eigen::Matrix3d> covariances;
  double log_likelihood = 0;  // of the data under the mixture
  double bic = 0;             // k ln(n) - 2 ln L, k = free parameters (T-1 + 3T + 6T)
  std::vector<int> labels;    // most probable component per point
};

// Fits a T-component full-covariance Gaussian mixture by EM (k-means++ initialisation,
// deterministic for `seed`; covariances regularised by `min_variance` on the diagonal).
GaussianMixture fit_gaussian_mixture(const std::vector<Eigen::Vector3d>& points, int components,
                                     uint64_t seed, double min_variance);

// Chooses T in [1, t_max] by the lowest BIC (T never above the number of points) and returns
// that mixture. The candidate T are fitted in parallel (same result as one after another).
GaussianMixture fit_mixture_by_bic(const std::vector<Eigen::Vector3d>& points, int t_max,
                                   uint64_t seed, double min_variance);

// ---- The steps of the above, for callers that centre the data themselves and stop EM early
// (fit_ellipsoids): the points are the columns of X.

// EM stops after max_iterations M-steps, or when the log-likelihood gains less than
// tol_per_point * n.
struct EmOptions {
  int max_iterations = 200;
  double tol_per_point = 1e-6;
};

// T in [1, min(t_max, n)] by the lowest BIC (ties keep the smaller T), each T fitted with `opt`
// from the first T of the k-means++ seeds of `seed`; `labels` only if `want_labels`. The
// candidate T are fitted in parallel; each depends only on T, so the result does not depend on
// the scheduling.
GaussianMixture mixture_by_bic(const Eigen::Matrix3Xd& X, int t_max, uint64_t seed, double min_variance,
                               const EmOptions& opt, bool want_labels);

// EM continued from the weights, means and covariances of `start` with `opt` (no labels).
GaussianMixture continue_em(const Eigen::Matrix3Xd& X, const GaussianMixture& start, double min_variance,
                            const EmOptions& opt);

// The most probable component of `g` for every column of X (the first on ties).
std::vector<int> most_probable_components(const Eigen::Matrix3Xd& X, const GaussianMixture& g,
                                          double min_variance);

}  // namespace pbnbv
