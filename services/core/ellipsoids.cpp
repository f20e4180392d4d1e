// Ellipsoids of occupied and frontier structure: Gaussian mixture by EM with T chosen by BIC,
// then the minimum-volume enclosing ellipsoid (Khachiyan) of each cluster's voxel corners.
#include "core/ellipsoids.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <random>
#include <unordered_map>

namespace pbnbv {

namespace {

using Points3 = Eigen::Matrix<double, 3, Eigen::Dynamic>;
using Eigen::Matrix3d;
using Eigen::Matrix4d;
using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;

constexpr double kLog2Pi = 1.8378770664093454835606594728112;  // ln(2 pi)
// Components whose log density is this far below the best one get responsibility 0
// (exp(-50) ~ 2e-22): it saves the exp, the result is unchanged to double precision.
constexpr double kLogCut = -50.0;

struct EmOptions {
  int max_iterations = 200;
  double tol_per_point = 1e-6;  // stop when the log-likelihood gain < tol_per_point * n
};

Points3 to_matrix(const std::vector<Vector3d>& pts) {
  Points3 X(3, static_cast<Eigen::Index>(pts.size()));
  for (size_t i = 0; i < pts.size(); ++i) X.col(static_cast<Eigen::Index>(i)) = pts[i];
  return X;
}

// One component's Gaussian in the form the E-step uses: ln N = cst - |Linv (x - mu)|^2 / 2.
struct CompEval {
  double mu[3];
  double l00, l10, l11, l20, l21, l22;  // lower-triangular inverse Cholesky factor
  double cst;                           // ln w - (3 ln 2pi + ln det S) / 2
};

// Prepares the evaluation of component j; a covariance that is not positive definite gets
// extra diagonal regularisation (written back).
CompEval prepare(double w, const Vector3d& mu, Matrix3d& cov, double min_variance) {
  Eigen::LLT<Matrix3d> llt(cov);
  double extra = std::max(min_variance, 1e-12);
  while (llt.info() != Eigen::Success) {
    cov += extra * Matrix3d::Identity();
    extra *= 10;
    llt.compute(cov);
  }
  const Matrix3d L = llt.matrixL();
  const double log_det = 2.0 * L.diagonal().array().log().sum();
  const Matrix3d Li = L.triangularView<Eigen::Lower>().solve(Matrix3d::Identity());
  CompEval c;
  c.mu[0] = mu[0];
  c.mu[1] = mu[1];
  c.mu[2] = mu[2];
  c.l00 = Li(0, 0);
  c.l10 = Li(1, 0);
  c.l11 = Li(1, 1);
  c.l20 = Li(2, 0);
  c.l21 = Li(2, 1);
  c.l22 = Li(2, 2);
  c.cst = std::log(std::max(w, 1e-300)) - 0.5 * (3.0 * kLog2Pi + log_det);
  return c;
}

inline double log_joint(const CompEval& c, const double* x) {
  const double d0 = x[0] - c.mu[0], d1 = x[1] - c.mu[1], d2 = x[2] - c.mu[2];
  const double y0 = c.l00 * d0;
  const double y1 = c.l10 * d0 + c.l11 * d1;
  const double y2 = c.l20 * d0 + c.l21 * d1 + c.l22 * d2;
  return c.cst - 0.5 * (y0 * y0 + y1 * y1 + y2 * y2);
}

// Sufficient statistics of one component from the responsibilities.
struct CompStats {
  double n = 0;
  double s1[3] = {0, 0, 0};
  double s2[6] = {0, 0, 0, 0, 0, 0};  // xx, xy, xz, yy, yz, zz
};

// One pass over the points: the E-step for the current parameters (log-sum-exp per point),
// returning the log-likelihood of the data under the mixture; optionally accumulates the
// M-step statistics and the most probable component per point.
double em_pass(const Points3& X, const std::vector<CompEval>& ce, std::vector<CompStats>* stats,
               std::vector<int>* labels) {
  const Eigen::Index n = X.cols();
  const int T = static_cast<int>(ce.size());
  if (stats) stats->assign(static_cast<size_t>(T), CompStats{});
  if (labels) labels->resize(static_cast<size_t>(n));
  double lp[64];
  std::vector<double> lp_heap;
  double* l = lp;
  if (T > 64) {
    lp_heap.resize(static_cast<size_t>(T));
    l = lp_heap.data();
  }
  double ll = 0, prod = 1.0;
  int in_prod = 0;
  const int chunk = T <= 1 ? 1024 : std::max(1, std::min(1024, static_cast<int>(690.0 / std::log(static_cast<double>(T)))));
  for (Eigen::Index i = 0; i < n; ++i) {
    const double* x = X.col(i).data();
    double mx = -std::numeric_limits<double>::infinity();
    int arg = 0;
    for (int j = 0; j < T; ++j) {
      l[j] = log_joint(ce[static_cast<size_t>(j)], x);
      if (l[j] > mx) {
        mx = l[j];
        arg = j;
      }
    }
    double s = 0;
    for (int j = 0; j < T; ++j) {
      const double dlt = l[j] - mx;
      l[j] = dlt > kLogCut ? std::exp(dlt) : 0.0;
      s += l[j];
    }
    // ln s is accumulated as the log of a running product (s in [1, T]; `chunk` factors
    // stay below e^690): one log per chunk of points instead of one per point.
    ll += mx;
    prod *= s;
    if (++in_prod == chunk) {
      ll += std::log(prod);
      prod = 1.0;
      in_prod = 0;
    }
    if (labels) (*labels)[static_cast<size_t>(i)] = arg;
    if (stats) {
      const double inv = 1.0 / s;
      for (int j = 0; j < T; ++j) {
        if (l[j] == 0.0) continue;
        const double r = l[j] * inv;
        CompStats& st = (*stats)[static_cast<size_t>(j)];
        const double rx = r * x[0], ry = r * x[1], rz = r * x[2];
        st.n += r;
        st.s1[0] += rx;
        st.s1[1] += ry;
        st.s1[2] += rz;
        st.s2[0] += rx * x[0];
        st.s2[1] += rx * x[1];
        st.s2[2] += rx * x[2];
        st.s2[3] += ry * x[1];
        st.s2[4] += ry * x[2];
        st.s2[5] += rz * x[2];
      }
    }
  }
  return ll + std::log(prod);
}

// k-means++ seeding (D^2 sampling from mt19937_64(seed)) and a few Lloyd iterations; initial
// weights, means and covariances from the resulting hard assignment.
void kmeanspp_init(const Points3& X, int T, uint64_t seed, double min_variance,
                   std::vector<double>& w, std::vector<Vector3d>& mu, std::vector<Matrix3d>& cov) {
  const Eigen::Index n = X.cols();
  std::mt19937_64 rng(seed);
  std::vector<Vector3d> centres;
  centres.reserve(static_cast<size_t>(T));
  {
    std::uniform_int_distribution<Eigen::Index> pick(0, n - 1);
    centres.push_back(X.col(pick(rng)));
  }
  std::vector<double> d2(static_cast<size_t>(n));
  std::vector<int> assign(static_cast<size_t>(n), 0);
  for (Eigen::Index i = 0; i < n; ++i) d2[static_cast<size_t>(i)] = (X.col(i) - centres[0]).squaredNorm();
  std::uniform_real_distribution<double> unif(0.0, 1.0);
  while (static_cast<int>(centres.size()) < T) {
    const double total = std::accumulate(d2.begin(), d2.end(), 0.0);
    Eigen::Index chosen = n - 1;
    if (!(total > 0)) {
      std::uniform_int_distribution<Eigen::Index> pick(0, n - 1);
      chosen = pick(rng);
    } else {
      const double r = unif(rng) * total;
      double acc = 0;
      for (Eigen::Index i = 0; i < n; ++i) {
        acc += d2[static_cast<size_t>(i)];
        if (acc >= r && d2[static_cast<size_t>(i)] > 0) {
          chosen = i;
          break;
        }
      }
    }
    centres.push_back(X.col(chosen));
    const int j = static_cast<int>(centres.size()) - 1;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double d = (X.col(i) - centres.back()).squaredNorm();
      if (d < d2[static_cast<size_t>(i)]) {
        d2[static_cast<size_t>(i)] = d;
        assign[static_cast<size_t>(i)] = j;
      }
    }
  }

  // Lloyd refinement (assignments start from the seeding's nearest centres).
  std::vector<Vector3d> sum(static_cast<size_t>(T));
  std::vector<int> cnt(static_cast<size_t>(T));
  for (int it = 0; it < 3; ++it) {
    std::fill(sum.begin(), sum.end(), Vector3d::Zero());
    std::fill(cnt.begin(), cnt.end(), 0);
    for (Eigen::Index i = 0; i < n; ++i) {
      sum[static_cast<size_t>(assign[static_cast<size_t>(i)])] += X.col(i);
      ++cnt[static_cast<size_t>(assign[static_cast<size_t>(i)])];
    }
    for (int j = 0; j < T; ++j)
      if (cnt[static_cast<size_t>(j)] > 0)
        centres[static_cast<size_t>(j)] = sum[static_cast<size_t>(j)] / cnt[static_cast<size_t>(j)];
    bool changed = false;
    for (Eigen::Index i = 0; i < n; ++i) {
      int best = 0;
      double bd = std::numeric_limits<double>::infinity();
      for (int j = 0; j < T; ++j) {
        const double d = (X.col(i) - centres[static_cast<size_t>(j)]).squaredNorm();
        if (d < bd) {
          bd = d;
          best = j;
        }
      }
      if (best != assign[static_cast<size_t>(i)]) {
        assign[static_cast<size_t>(i)] = best;
        changed = true;
      }
    }
    if (!changed) break;
  }

  // Hard-assignment statistics.
  const Vector3d gmean = X.rowwise().mean();
  const Matrix3d gcov = (X.colwise() - gmean) * (X.colwise() - gmean).transpose() / static_cast<double>(n);
  w.assign(static_cast<size_t>(T), 0.0);
  mu.assign(static_cast<size_t>(T), Vector3d::Zero());
  cov.assign(static_cast<size_t>(T), Matrix3d::Zero());
  std::fill(cnt.begin(), cnt.end(), 0);
  for (Eigen::Index i = 0; i < n; ++i) {
    mu[static_cast<size_t>(assign[static_cast<size_t>(i)])] += X.col(i);
    ++cnt[static_cast<size_t>(assign[static_cast<size_t>(i)])];
  }
  for (int j = 0; j < T; ++j)
    mu[static_cast<size_t>(j)] = cnt[static_cast<size_t>(j)] > 0
                                     ? Vector3d(mu[static_cast<size_t>(j)] / cnt[static_cast<size_t>(j)])
                                     : centres[static_cast<size_t>(j)];
  for (Eigen::Index i = 0; i < n; ++i) {
    const int j = assign[static_cast<size_t>(i)];
    const Vector3d d = X.col(i) - mu[static_cast<size_t>(j)];
    cov[static_cast<size_t>(j)] += d * d.transpose();
  }
  for (int j = 0; j < T; ++j) {
    const size_t sj = static_cast<size_t>(j);
    if (cnt[sj] > 0) {
      cov[sj] /= cnt[sj];
      w[sj] = static_cast<double>(cnt[sj]) / static_cast<double>(n);
    } else {
      cov[sj] = gcov;
      w[sj] = 1.0 / static_cast<double>(n);
    }
    cov[sj] += min_variance * Matrix3d::Identity();
  }
  const double wsum = std::accumulate(w.begin(), w.end(), 0.0);
  for (double& v : w) v /= wsum;
}

GaussianMixture em_run(const Points3& X, std::vector<double> w, std::vector<Vector3d> mu,
                       std::vector<Matrix3d> cov, double min_variance, const EmOptions& opt);

// EM on data already centred (the caller adds the offset back to the means).
GaussianMixture fit_gmm_centred(const Points3& X, int components, uint64_t seed, double min_variance,
                                const EmOptions& opt) {
  GaussianMixture g;
  const Eigen::Index n = X.cols();
  if (n == 0) return g;
  const int T = std::max(1, std::min<int>(components, static_cast<int>(n)));
  min_variance = std::max(min_variance, 0.0);

  std::vector<double> w;
  std::vector<Vector3d> mu;
  std::vector<Matrix3d> cov;
  kmeanspp_init(X, T, seed, min_variance, w, mu, cov);
  return em_run(X, std::move(w), std::move(mu), std::move(cov), min_variance, opt);
}

// EM from the given parameters until the log-likelihood gain < tol_per_point * n or
// max_iterations M-steps.
GaussianMixture em_run(const Points3& X, std::vector<double> w, std::vector<Vector3d> mu,
                       std::vector<Matrix3d> cov, double min_variance, const EmOptions& opt) {
  GaussianMixture g;
  const Eigen::Index n = X.cols();
  const int T = static_cast<int>(w.size());
  std::vector<CompEval> ce(static_cast<size_t>(T));
  std::vector<CompStats> stats;
  std::vector<int> labels;
  const double tol = opt.tol_per_point * static_cast<double>(n);
  double ll = -std::numeric_limits<double>::infinity();
  // Each pass evaluates the current parameters (log-likelihood, labels) and gathers the
  // statistics of the next ones; on stopping, the parameters of the last pass are returned,
  // so `log_likelihood` is exactly theirs.
  for (int it = 0;; ++it) {
    for (int j = 0; j < T; ++j)
      ce[static_cast<size_t>(j)] = prepare(w[static_cast<size_t>(j)], mu[static_cast<size_t>(j)],
                                           cov[static_cast<size_t>(j)], min_variance);
    const double ll_new = em_pass(X, ce, &stats, &labels);
    const double gain = ll_new - ll;
    ll = ll_new;
    if (gain < tol || it >= opt.max_iterations) break;
    // M-step.
    for (int j = 0; j < T; ++j) {
      const size_t sj = static_cast<size_t>(j);
      const CompStats& st = stats[sj];
      w[sj] = st.n / static_cast<double>(n);
      if (st.n < 1e-10) continue;  // dead component: keeps its mean and covariance, weight ~0
      const Vector3d m(st.s1[0] / st.n, st.s1[1] / st.n, st.s1[2] / st.n);
      Matrix3d S;
      S << st.s2[0], st.s2[1], st.s2[2], st.s2[1], st.s2[3], st.s2[4], st.s2[2], st.s2[4], st.s2[5];
      mu[sj] = m;
      cov[sj] = S / st.n - m * m.transpose() + min_variance * Matrix3d::Identity();
    }
  }

  g.weights = std::move(w);
  g.means = std::move(mu);
  g.covariances = std::move(cov);
  g.log_likelihood = ll;
  const double k = static_cast<double>((T - 1) + 3 * T + 6 * T);
  g.bic = k * std::log(static_cast<double>(n)) - 2.0 * ll;
  g.labels = std::move(labels);
  return g;
}

void uncentre(GaussianMixture& g, const Vector3d& offset) {
  for (auto& m : g.means) m += offset;
}

// BIC search over T in [1, min(t_max, n)] on centred data, each T fitted with `opt`; ties keep
// the smaller T.
GaussianMixture bic_search_impl(const Points3& X, int t_max, uint64_t seed, double min_variance,
                                const EmOptions& opt) {
  const Eigen::Index n = X.cols();
  if (n == 0) return GaussianMixture{};
  const int hi = std::max(1, std::min<int>(t_max, static_cast<int>(n)));
  GaussianMixture best;
  int best_t = 0;
  for (int T = 1; T <= hi; ++T) {
    GaussianMixture g = fit_gmm_centred(X, T, seed, min_variance, opt);
    if (best_t == 0 || g.bic < best.bic) {
      best = std::move(g);
      best_t = T;
    }
  }
  return best;
}

// ---- MVEE ----

Ellipsoid ellipsoid_from_shape(const Vector3d& c, const Matrix3d& A) {
  Ellipsoid e;
  e.centre = c;
  Eigen::SelfAdjointEigenSolver<Matrix3d> es(0.5 * (A + A.transpose()));
  // Eigenvalues ascending -> semi-axes descending.
  for (int i = 0; i < 3; ++i) {
    const double ev = std::max(es.eigenvalues()[i], 1e-300);
    e.semi_axes[i] = 1.0 / std::sqrt(ev);
    e.axes.col(i) = es.eigenvectors().col(i).normalized();
  }
  if (e.axes.determinant() < 0) e.axes.col(2) = -e.axes.col(2);
  return e;
}

// Degenerate input (fewer than 4 points or affinely dependent): the principal frame of the
// points, semi-axes sqrt(3) x the half extents (the box's MVEE), thin directions 1e-9 m.
Ellipsoid degenerate_ellipsoid(const Points3& P) {
  const Vector3d mean = P.rowwise().mean();
  const Points3 D = P.colwise() - mean;
  Eigen::SelfAdjointEigenSolver<Matrix3d> es(D * D.transpose());
  Matrix3d R = es.eigenvectors().rowwise().reverse();  // largest first
  if (R.determinant() < 0) R.col(2) = -R.col(2);
  const Points3 L = R.transpose() * D;
  const Vector3d lo = L.rowwise().minCoeff(), hi = L.rowwise().maxCoeff();
  Ellipsoid e;
  e.centre = mean + R * (0.5 * (lo + hi));
  e.axes = R;
  e.semi_axes = (0.5 * (hi - lo) * std::sqrt(3.0)).cwiseMax(1e-9);
  return e;
}

using Lifted = Eigen::Matrix<double, 4, Eigen::Dynamic>;

// Khachiyan's algorithm with Todd-Yildirim away steps on the lifted points Q (4 x N), from
// the weights u (sum 1); rank-one updates of X^-1 = (Q U Q^T)^-1 and of M_i = q_i^T X^-1 q_i,
// recomputed from scratch every 64 steps. Stops when max M <= (d+1)(1+tol) and min M over
// the support >= (d+1)(1-tol). Returns false if X is singular (affinely dependent points).
bool khachiyan(const Lifted& Q, VectorXd& u, double tol, Matrix4d& Xinv) {
  constexpr double d = 3.0;
  const Eigen::Index N = Q.cols();
  VectorXd M(N);
  auto recompute = [&]() {
    const Matrix4d X = Q * u.asDiagonal() * Q.transpose();
    const Eigen::LDLT<Matrix4d> ldlt(X);
    const Eigen::Vector4d D = ldlt.vectorD();
    if (ldlt.info() != Eigen::Success || !(D.minCoeff() > 1e-14 * D.cwiseAbs().maxCoeff())) return false;
    Xinv = ldlt.solve(Matrix4d::Identity());
    M = (Q.array() * (Xinv * Q).array()).colwise().sum().transpose();
    return true;
  };
  if (!recompute()) return false;
  const int max_iter = 100000;
  for (int it = 0; it < max_iter; ++it) {
    Eigen::Index j;
    const double mj = M.maxCoeff(&j);
    Eigen::Index k = -1;
    double mk = std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < N; ++i)
      if (u[i] > 0 && M[i] < mk) {
        mk = M[i];
        k = i;
      }
    const double eps_plus = mj / (d + 1) - 1;
    const double eps_minus = 1 - mk / (d + 1);
    if (eps_plus <= tol && eps_minus <= tol) break;
    Eigen::Index idx;
    double tau;  // X <- (1 - tau) X + tau q q^T
    if (eps_plus >= eps_minus || u[k] >= 1 - 1e-12) {
      idx = j;
      tau = (mj - (d + 1)) / ((d + 1) * (mj - 1));
    } else {
      idx = k;
      const double cap = u[k] / (1 - u[k]);
      double step = cap;
      if (mk - 1 > 1e-12) step = std::min(cap, (d + 1 - mk) / ((d + 1) * (mk - 1)));
      tau = -step;
    }
    const Eigen::Vector4d wv = Xinv * Q.col(idx);
    const double denom = (1 - tau) + tau * M[idx];
    const VectorXd qw = Q.transpose() * wv;
    M = (M.array() - tau * qw.array().square() / denom) / (1 - tau);
    Xinv = (Xinv - (tau / denom) * wv * wv.transpose()) / (1 - tau);
    u *= (1 - tau);
    u[idx] += tau;
    if (u[idx] < 1e-15) u[idx] = 0;
    if (it % 64 == 63 && !recompute()) return false;
  }
  return recompute();
}

}  // namespace

Eigen::Matrix4d Ellipsoid::quadric() const {
  // T = [R c; 0 1], T^-1 = [R^T, -R^T c; 0 1]; Q = T^-T diag(1/a^2, 1/b^2, 1/c^2, -1) T^-1.
  Matrix4d Tinv = Matrix4d::Identity();
  Tinv.topLeftCorner<3, 3>() = axes.transpose();
  Tinv.topRightCorner<3, 1>() = -axes.transpose() * centre;
  Eigen::Vector4d d;
  d << 1.0 / (semi_axes[0] * semi_axes[0]), 1.0 / (semi_axes[1] * semi_axes[1]),
      1.0 / (semi_axes[2] * semi_axes[2]), -1.0;
  return Tinv.transpose() * d.asDiagonal() * Tinv;
}

Eigen::Matrix4d Ellipsoid::dual_quadric() const {
  Matrix4d T = Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = axes;
  T.topRightCorner<3, 1>() = centre;
  Eigen::Vector4d d;
  d << semi_axes[0] * semi_axes[0], semi_axes[1] * semi_axes[1], semi_axes[2] * semi_axes[2], -1.0;
  return T * d.asDiagonal() * T.transpose();
}

GaussianMixture fit_gaussian_mixture(const std::vector<Eigen::Vector3d>& points, int components,
                                     uint64_t seed, double min_variance) {
  Points3 X = to_matrix(points);
  const Vector3d offset = X.cols() ? Vector3d(X.rowwise().mean()) : Vector3d::Zero();
  X.colwise() -= offset;
  GaussianMixture g = fit_gmm_centred(X, components, seed, min_variance, EmOptions{});
  uncentre(g, offset);
  return g;
}

GaussianMixture fit_mixture_by_bic(const std::vector<Eigen::Vector3d>& points, int t_max,
                                   uint64_t seed, double min_variance) {
  Points3 X = to_matrix(points);
  const Vector3d offset = X.cols() ? Vector3d(X.rowwise().mean()) : Vector3d::Zero();
  X.colwise() -= offset;
  GaussianMixture g =
      bic_search_impl(X, t_max, seed, min_variance, EmOptions{});
  uncentre(g, offset);
  return g;
}

Ellipsoid minimum_volume_ellipsoid(const std::vector<Eigen::Vector3d>& points, double tol) {
  const Points3 P = to_matrix(points);
  const Eigen::Index N = P.cols();
  if (N == 0) return Ellipsoid{};
  if (N < 4) return degenerate_ellipsoid(P);
  {
    const Vector3d mean = P.rowwise().mean();
    const Points3 D = P.colwise() - mean;
    Eigen::SelfAdjointEigenSolver<Matrix3d> es(D * D.transpose() / static_cast<double>(N),
                                               Eigen::EigenvaluesOnly);
    const double emax = es.eigenvalues()[2];
    if (!(emax > 0) || es.eigenvalues()[0] <= 1e-12 * emax) return degenerate_ellipsoid(P);
  }
  // Work in coordinates centred and scaled to O(1) for conditioning.
  const Vector3d shift = P.rowwise().mean();
  const double scale = std::max(1e-300, (P.colwise() - shift).cwiseAbs().maxCoeff());
  Lifted Q(4, N);
  Q.topRows<3>() = (P.colwise() - shift) / scale;
  Q.row(3).setOnes();

  // Active set: start from the extreme points along 13 directions, solve on the core, add
  // the points that the core's ellipsoid leaves out, repeat (the result satisfies the same
  // criterion over all points as a run on all of them).
  std::vector<Eigen::Index> core;
  {
    static const double dirs[13][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}, {1, -1, 0},
                                       {1, 0, 1}, {1, 0, -1}, {0, 1, 1}, {0, 1, -1}, {1, 1, 1},
                                       {1, 1, -1}, {1, -1, 1}, {-1, 1, 1}};
    for (const auto& dv : dirs) {
      const Eigen::RowVectorXd proj = Vector3d(dv[0], dv[1], dv[2]).transpose() * Q.topRows<3>();
      Eigen::Index lo, hi;
      proj.minCoeff(&lo);
      proj.maxCoeff(&hi);
      core.push_back(lo);
      core.push_back(hi);
    }
    std::sort(core.begin(), core.end());
    core.erase(std::unique(core.begin(), core.end()), core.end());
  }
  std::vector<double> u(core.size(), 1.0 / static_cast<double>(core.size()));
  constexpr double d = 3.0;
  Matrix4d Xinv;
  for (int round = 0;; ++round) {
    Lifted Qc(4, static_cast<Eigen::Index>(core.size()));
    for (size_t i = 0; i < core.size(); ++i) Qc.col(static_cast<Eigen::Index>(i)) = Q.col(core[i]);
    VectorXd uc = Eigen::Map<const VectorXd>(u.data(), static_cast<Eigen::Index>(u.size()));
    if (!khachiyan(Qc, uc, tol, Xinv)) {
      if (static_cast<Eigen::Index>(core.size()) == N) return degenerate_ellipsoid(P);
      core.resize(static_cast<size_t>(N));
      std::iota(core.begin(), core.end(), Eigen::Index{0});
      u.assign(core.size(), 1.0 / static_cast<double>(N));
      continue;
    }
    u.assign(uc.data(), uc.data() + uc.size());
    if (static_cast<Eigen::Index>(core.size()) == N) break;
    const VectorXd M = (Q.array() * (Xinv * Q).array()).colwise().sum().transpose();
    const double limit = (d + 1) * (1 + tol);
    std::vector<std::pair<double, Eigen::Index>> out;
    for (Eigen::Index i = 0; i < N; ++i)
      if (M[i] > limit) out.emplace_back(-M[i], i);
    if (out.empty()) break;
    std::vector<char> in_core(static_cast<size_t>(N), 0);
    for (Eigen::Index i : core) in_core[static_cast<size_t>(i)] = 1;
    const size_t add = std::min<size_t>(out.size(), 32);
    std::partial_sort(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(add), out.end());
    size_t added = 0;
    for (size_t k = 0; k < add; ++k)
      if (!in_core[static_cast<size_t>(out[k].second)]) {
        core.push_back(out[k].second);
        u.push_back(0.0);
        ++added;
      }
    if (added == 0) break;  // only core points (within the core tolerance) remain outside
  }
  // Centre and shape in the scaled frame, from the core's weights.
  Vector3d c = Vector3d::Zero();
  Matrix3d S = Matrix3d::Zero();
  for (size_t i = 0; i < core.size(); ++i) {
    const Vector3d q = Q.col(core[i]).head<3>();
    c += u[i] * q;
    S += u[i] * q * q.transpose();
  }
  S -= c * c.transpose();
  Matrix3d A = S.ldlt().solve(Matrix3d::Identity()) / d;
  // Make it enclosing exactly (the tolerance leaves points up to (1 + tol)-ish outside).
  const Points3 D = Q.topRows<3>().colwise() - c;
  const double worst = (D.array() * (A * D).array()).colwise().sum().maxCoeff();
  if (worst > 1) A /= worst;
  return ellipsoid_from_shape(shift + scale * c, A / (scale * scale));
}

namespace {

// The corners of the voxels that can be vertices of their convex hull (so the MVEE of the
// returned corners equals that of all corners). A voxel that has other voxels of the set on
// both sides along some axis line contributes no hull vertex; if the centres are not on a
// common lattice of pitch `voxel`, all corners are returned.
std::vector<Vector3d> hull_candidate_corners(const std::vector<Vector3d>& centres, double voxel) {
  const double h = 0.5 * voxel;
  std::vector<Eigen::Vector3i> idx(centres.size());
  bool lattice = voxel > 0;
  const Vector3d c0 = centres.empty() ? Vector3d::Zero() : centres[0];
  for (size_t i = 0; i < centres.size() && lattice; ++i) {
    const Vector3d q = (centres[i] - c0) / voxel;
    const Vector3d r = q.array().round();
    if ((q - r).cwiseAbs().maxCoeff() > 1e-3 || r.cwiseAbs().maxCoeff() > 1e6) lattice = false;
    idx[i] = r.cast<int>();
  }
  std::vector<char> keep(centres.size(), 1);
  if (lattice && centres.size() > 8) {
    auto key2 = [](int a, int b) {
      return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b);
    };
    for (int axis = 0; axis < 3; ++axis) {
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      std::unordered_map<uint64_t, std::pair<int, int>> ext;
      ext.reserve(centres.size() * 2);
      for (const auto& v : idx) {
        auto it = ext.emplace(key2(v[a1], v[a2]), std::make_pair(v[axis], v[axis])).first;
        it->second.first = std::min(it->second.first, v[axis]);
        it->second.second = std::max(it->second.second, v[axis]);
      }
      for (size_t i = 0; i < idx.size(); ++i) {
        const auto& e = ext[key2(idx[i][a1], idx[i][a2])];
        if (idx[i][axis] != e.first && idx[i][axis] != e.second) keep[i] = 0;
      }
    }
  }
  std::vector<Vector3d> corners;
  if (lattice) {
    // Deduplicate shared corners via their lattice index.
    std::vector<std::array<int, 3>> ci;
    for (size_t i = 0; i < idx.size(); ++i) {
      if (!keep[i]) continue;
      for (int m = 0; m < 8; ++m)
        ci.push_back({idx[i][0] + (m & 1), idx[i][1] + ((m >> 1) & 1), idx[i][2] + ((m >> 2) & 1)});
    }
    std::sort(ci.begin(), ci.end());
    ci.erase(std::unique(ci.begin(), ci.end()), ci.end());
    corners.reserve(ci.size());
    const Vector3d base = c0 - Vector3d::Constant(h);
    for (const auto& c : ci) corners.push_back(base + voxel * Vector3d(c[0], c[1], c[2]));
  } else {
    for (const auto& c : centres)
      for (int m = 0; m < 8; ++m)
        corners.push_back(c + Vector3d((m & 1) ? h : -h, (m & 2) ? h : -h, (m & 4) ? h : -h));
  }
  return corners;
}

}  // namespace

std::vector<Ellipsoid> fit_ellipsoids(const std::vector<Eigen::Vector3d>& voxel_centres,
                                      EllipsoidClass cls, const EllipsoidParams& params,
                                      int* components) {
  std::vector<Ellipsoid> out;
  const size_t n = voxel_centres.size();
  if (components) *components = 0;
  if (n == 0) return out;
  const double voxel = params.voxel_m;
  if (n <= 3) {
    Ellipsoid e = minimum_volume_ellipsoid(hull_candidate_corners(voxel_centres, voxel));
    e.cls = cls;
    e.num_points = static_cast<int>(n);
    out.push_back(e);
    if (components) *components = 1;
    return out;
  }

  // EM on at most kMaxEmPoints centres (a seeded random subsample). The BIC search runs at
  // most kSearchIterations EM iterations per T; the chosen mixture is then continued with the
  // full stopping rule, and every voxel is labelled by its most probable component.
  constexpr size_t kMaxEmPoints = 500;
  constexpr int kSearchIterations = 10;
  const double min_variance = voxel * voxel / 12.0;  // variance of a uniform voxel
  std::vector<size_t> perm(n);
  std::iota(perm.begin(), perm.end(), size_t{0});
  const size_t m_em = std::min(n, kMaxEmPoints);
  if (n > m_em) {
    std::mt19937_64 rng(params.seed ^ 0x9e3779b97f4a7c15ULL);
    for (size_t i = 0; i < m_em; ++i) {
      std::uniform_int_distribution<size_t> pick(i, n - 1);
      std::swap(perm[i], perm[pick(rng)]);
    }
  }
  Points3 Xall = to_matrix(voxel_centres);
  const Vector3d offset = Xall.rowwise().mean();
  Xall.colwise() -= offset;
  Points3 Xem(3, static_cast<Eigen::Index>(m_em));
  for (size_t i = 0; i < m_em; ++i) Xem.col(static_cast<Eigen::Index>(i)) = Xall.col(static_cast<Eigen::Index>(perm[i]));
  EmOptions search;
  search.max_iterations = kSearchIterations;
  GaussianMixture g = bic_search_impl(Xem, params.t_max, params.seed, min_variance, search);
  {
    EmOptions rest;
    rest.max_iterations = EmOptions{}.max_iterations - kSearchIterations;
    g = em_run(Xem, g.weights, g.means, g.covariances, min_variance, rest);
  }
  const int T = static_cast<int>(g.weights.size());
  if (components) *components = T;

  std::vector<int> labels;
  {
    std::vector<CompEval> ce(static_cast<size_t>(T));
    for (int j = 0; j < T; ++j)
      ce[static_cast<size_t>(j)] = prepare(g.weights[static_cast<size_t>(j)], g.means[static_cast<size_t>(j)],
                                           g.covariances[static_cast<size_t>(j)], min_variance);
    em_pass(Xall, ce, nullptr, &labels);
  }

  std::vector<std::vector<Vector3d>> members(static_cast<size_t>(T));
  for (size_t i = 0; i < n; ++i) members[static_cast<size_t>(labels[i])].push_back(voxel_centres[i]);
  for (const auto& m : members) {
    if (m.empty()) continue;  // clusters that end up empty are dropped
    Ellipsoid e = minimum_volume_ellipsoid(hull_candidate_corners(m, voxel));
    e.cls = cls;
    e.num_points = static_cast<int>(m.size());
    out.push_back(e);
  }
  return out;
}

}  // namespace pbnbv
