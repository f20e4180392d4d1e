// Gaussian mixtures by EM with T chosen by BIC: k-means++ seeding and a few Lloyd steps, then
// EM whose E-step is one vectorised kernel (compiled for AVX2 + FMA where the CPU has them).
#include "core/planning/gmm.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>

#include "core/base/parallel.hpp"

namespace pbnbv {

namespace {

using Points3 = Eigen::Matrix3Xd;
using Eigen::Matrix3d;
using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;

constexpr double kLog2Pi = 1.8378770664093454835606594728112;  // ln(2 pi)
// Log densities more than 50 below a point's best component are clamped (see exp_clamped).
constexpr double kLogCut = -50.0;

// The points as the columns of a matrix (a copy).
Points3 as_matrix(const std::vector<Vector3d>& pts) {
  return Eigen::Map<const Points3>(pts.empty() ? nullptr : pts[0].data(), 3, static_cast<Eigen::Index>(pts.size()));
}

// Per point, the columns [1, x, y, z, xx, xy, xz, yy, yz, zz] of the (centred) data: the
// M-step statistics of all components are then one product F^T R with the responsibilities.
using Features = Eigen::Matrix<double, Eigen::Dynamic, 10>;
using Stats = Eigen::Matrix<double, 10, Eigen::Dynamic>;

Features make_features(const Points3& X) {
  Features F(X.cols(), 10);
  F.col(0).setOnes();
  for (int a = 0; a < 3; ++a) F.col(1 + a) = X.row(a).transpose();
  int c = 4;
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b) F.col(c++) = X.row(a).transpose().cwiseProduct(X.row(b).transpose());
  return F;
}

// One component's Gaussian in the form the E-step uses: ln(w N) = cst - |Li x + b|^2 / 2,
// Li the inverse Cholesky factor of the covariance and b = -Li mu.
struct CompEval {
  double l00, l10, l11, l20, l21, l22;  // lower-triangular inverse Cholesky factor
  double b0, b1, b2;
  double cst;  // ln w - (3 ln 2pi + ln det S) / 2
};

// Prepares the evaluation of one component; a covariance that is not positive definite gets
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
  const Vector3d b = -(Li.triangularView<Eigen::Lower>() * mu);
  CompEval c;
  c.l00 = Li(0, 0);
  c.l10 = Li(1, 0);
  c.l11 = Li(1, 1);
  c.l20 = Li(2, 0);
  c.l21 = Li(2, 1);
  c.l22 = Li(2, 2);
  c.b0 = b[0];
  c.b1 = b[1];
  c.b2 = b[2];
  c.cst = std::log(std::max(w, 1e-300)) - 0.5 * (3.0 * kLog2Pi + log_det);
  return c;
}

std::vector<CompEval> prepare_all(const std::vector<double>& w, const std::vector<Vector3d>& mu,
                                  std::vector<Matrix3d>& cov, double min_variance) {
  std::vector<CompEval> ce(w.size());
  for (size_t j = 0; j < w.size(); ++j) ce[j] = prepare(w[j], mu[j], cov[j], min_variance);
  return ce;
}

// Column j of L: ln(w_j N(x_i | mu_j, S_j)) for every point i (vectorised over the points).
void log_joint_all(const Features& F, const std::vector<CompEval>& ce, MatrixXd& L) {
  L.resize(F.rows(), static_cast<Eigen::Index>(ce.size()));
  const auto x = F.col(1).array(), y = F.col(2).array(), z = F.col(3).array();
  for (size_t j = 0; j < ce.size(); ++j) {
    const CompEval& c = ce[j];
    L.col(static_cast<Eigen::Index>(j)).array() =
        c.cst - 0.5 * ((c.l00 * x + c.b0).square() + (c.l10 * x + c.l11 * y + c.b1).square() +
                       (c.l20 * x + c.l21 * y + c.l22 * z + c.b2).square());
  }
}

// The E-step kernel is compiled twice where the compiler supports it: for AVX2 + FMA and for
// the baseline ISA, chosen once by the CPU (the results then differ only by the rounding of
// fused multiply-adds, never between runs on one machine).
#if defined(__GNUC__)
#define PBNBV_ALWAYS_INLINE __attribute__((always_inline)) inline
#else
#define PBNBV_ALWAYS_INLINE inline
#endif
#if defined(__GNUC__) && defined(__x86_64__)
#define PBNBV_ESTEP_DISPATCH 1
#else
#define PBNBV_ESTEP_DISPATCH 0
#endif

// Four doubles added and multiplied lane-wise (one AVX register, or two SSE2 ones, where
// the compiler has vector extensions), for sums in a fixed order that still vectorise.
struct Lanes {
#if defined(__GNUC__)
  typedef double V __attribute__((vector_size(32)));
  V v = {0, 0, 0, 0};
  PBNBV_ALWAYS_INLINE static Lanes load(const double* p) {
    Lanes r;
    std::memcpy(&r.v, p, sizeof r.v);
    return r;
  }
  PBNBV_ALWAYS_INLINE static Lanes splat(double a) {
    Lanes r;
    r.v = V{a, a, a, a};
    return r;
  }
  PBNBV_ALWAYS_INLINE Lanes& operator+=(const Lanes& o) {
    v += o.v;
    return *this;
  }
  PBNBV_ALWAYS_INLINE Lanes& operator*=(const Lanes& o) {
    v *= o.v;
    return *this;
  }
  PBNBV_ALWAYS_INLINE Lanes operator*(const Lanes& o) const {
    Lanes r;
    r.v = v * o.v;
    return r;
  }
#else
  double v[4] = {0, 0, 0, 0};
  static Lanes load(const double* p) {
    Lanes r;
    for (int q = 0; q < 4; ++q) r.v[q] = p[q];
    return r;
  }
  static Lanes splat(double a) {
    Lanes r;
    for (int q = 0; q < 4; ++q) r.v[q] = a;
    return r;
  }
  Lanes& operator+=(const Lanes& o) {
    for (int q = 0; q < 4; ++q) v[q] += o.v[q];
    return *this;
  }
  Lanes& operator*=(const Lanes& o) {
    for (int q = 0; q < 4; ++q) v[q] *= o.v[q];
    return *this;
  }
  Lanes operator*(const Lanes& o) const {
    Lanes r;
    for (int q = 0; q < 4; ++q) r.v[q] = v[q] * o.v[q];
    return r;
  }
#endif
  PBNBV_ALWAYS_INLINE double operator[](int q) const { return v[q]; }
  PBNBV_ALWAYS_INLINE double sum() const { return (v[0] + v[1]) + (v[2] + v[3]); }
};

// exp(max(x, kLogCut)) for x <= 0 to ~1 ulp, written so that loops over it vectorise:
// x = k ln2 + r (|r| <= ln2 / 2, Cody-Waite), exp(r) by its degree-13 Taylor polynomial,
// 2^k assembled in the exponent bits. Components whose log density is more than |kLogCut|
// below the best one get responsibility e^-50 ~ 2e-22 instead of a tiny or subnormal value
// (subnormals are very slow to multiply): relative to the best (exactly 1) this is below
// double precision, so sums and statistics are unchanged.
PBNBV_ALWAYS_INLINE double exp_clamped(double x) {
  constexpr double kShift = 6755399441055744.0;  // 1.5 * 2^52: adding it rounds to an integer
  const double xc = std::max(x, kLogCut);
  const double t = xc * 1.4426950408889634074 + kShift;  // k + kShift
  const double k = t - kShift;
  const double r = (xc - k * 0.693147180369123816490) - k * 1.90821492927058770002e-10;
  double p = 1.0 / 6227020800.0;
  p = p * r + 1.0 / 479001600.0;
  p = p * r + 1.0 / 39916800.0;
  p = p * r + 1.0 / 3628800.0;
  p = p * r + 1.0 / 362880.0;
  p = p * r + 1.0 / 40320.0;
  p = p * r + 1.0 / 5040.0;
  p = p * r + 1.0 / 720.0;
  p = p * r + 1.0 / 120.0;
  p = p * r + 1.0 / 24.0;
  p = p * r + 1.0 / 6.0;
  p = p * r + 0.5;
  p = p * r + 1.0;
  p = p * r + 1.0;
  uint64_t bits;
  std::memcpy(&bits, &t, sizeof bits);  // the low bits hold k (two's complement)
  bits = (bits + 1023) << 52;           // 2^k
  double scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}

// One E-step over n points (coordinate arrays x, y, z and the second moments xx..zz, i.e.
// the columns 1..9 of the features) for the T components `ce`: L (n x T, column-major) gets
// the responsibilities, mx and s (n) are scratch. Returns the log-likelihood of the mixture.
// If `stats` (10 x T, column-major), it gets F^T R: per component sum r, sum r x, ...,
// sum r zz. Sums run in fixed lanes, so the result does not depend on anything but the input.
PBNBV_ALWAYS_INLINE double estep_body(int n, int T, const double* const* f, const CompEval* ce,
                                      double* L, double* mx, double* s, double* stats) {
  const double* x = f[1];
  const double* y = f[2];
  const double* z = f[3];
  for (int j = 0; j < T; ++j) {
    const CompEval c = ce[j];
    double* l = L + static_cast<size_t>(j) * n;
    for (int i = 0; i < n; ++i) {
      const double y0 = c.l00 * x[i] + c.b0;
      const double y1 = c.l10 * x[i] + c.l11 * y[i] + c.b1;
      const double y2 = c.l20 * x[i] + c.l21 * y[i] + c.l22 * z[i] + c.b2;
      l[i] = c.cst - 0.5 * (y0 * y0 + y1 * y1 + y2 * y2);
    }
  }
  for (int i = 0; i < n; ++i) mx[i] = L[i];
  for (int j = 1; j < T; ++j) {
    const double* l = L + static_cast<size_t>(j) * n;
    for (int i = 0; i < n; ++i) mx[i] = std::max(mx[i], l[i]);
  }
  for (int i = 0; i < n; ++i) s[i] = 0.0;
  for (int j = 0; j < T; ++j) {
    double* l = L + static_cast<size_t>(j) * n;
    for (int i = 0; i < n; ++i) {
      l[i] = exp_clamped(l[i] - mx[i]);
      s[i] += l[i];
    }
  }
  // ln L = sum mx + sum ln s; s in [1, T], so the logs are taken of products of `chunk`
  // factors per lane (each below e^690). Sums run in 4 fixed lanes, so the result depends
  // only on the input.
  const int chunk = T <= 1 ? 1 << 20 : std::max(1, static_cast<int>(690.0 / std::log(static_cast<double>(T))));
  Lanes msum, prod = Lanes::splat(1.0);
  double ll = 0;
  int i = 0;
  for (int in_prod = 0; i + 4 <= n; i += 4) {
    msum += Lanes::load(mx + i);
    prod *= Lanes::load(s + i);
    if (++in_prod == chunk) {
      for (int q = 0; q < 4; ++q) ll += std::log(prod[q]);
      prod = Lanes::splat(1.0);
      in_prod = 0;
    }
  }
  for (; i < n; ++i) ll += mx[i] + std::log(s[i]);
  for (int q = 0; q < 4; ++q) ll += std::log(prod[q]);
  ll += msum.sum();
  if (stats) {
    for (i = 0; i < n; ++i) s[i] = 1.0 / s[i];
    const double *xx = f[4], *xy = f[5], *xz = f[6], *yy = f[7], *yz = f[8], *zz = f[9];
    for (int j = 0; j < T; ++j) {
      const double* l = L + static_cast<size_t>(j) * n;
      Lanes a0, a1, a2, a3, a4, a5, a6, a7, a8, a9;
      for (i = 0; i + 4 <= n; i += 4) {
        const Lanes r = Lanes::load(l + i) * Lanes::load(s + i);
        a0 += r;
        a1 += r * Lanes::load(x + i);
        a2 += r * Lanes::load(y + i);
        a3 += r * Lanes::load(z + i);
        a4 += r * Lanes::load(xx + i);
        a5 += r * Lanes::load(xy + i);
        a6 += r * Lanes::load(xz + i);
        a7 += r * Lanes::load(yy + i);
        a8 += r * Lanes::load(yz + i);
        a9 += r * Lanes::load(zz + i);
      }
      double* out = stats + static_cast<size_t>(j) * 10;
      out[0] = a0.sum();
      out[1] = a1.sum();
      out[2] = a2.sum();
      out[3] = a3.sum();
      out[4] = a4.sum();
      out[5] = a5.sum();
      out[6] = a6.sum();
      out[7] = a7.sum();
      out[8] = a8.sum();
      out[9] = a9.sum();
      for (; i < n; ++i) {
        const double r = l[i] * s[i];
        out[0] += r;
        for (int c = 1; c < 10; ++c) out[c] += r * f[c][i];
      }
    }
  }
  return ll;
}

#if PBNBV_ESTEP_DISPATCH
__attribute__((target("avx2,fma"))) double estep_avx2(int n, int T, const double* const* f,
                                                      const CompEval* ce, double* L, double* mx,
                                                      double* s, double* stats) {
  return estep_body(n, T, f, ce, L, mx, s, stats);
}
#endif

double estep_kernel(int n, int T, const double* const* f, const CompEval* ce, double* L, double* mx,
                    double* s, double* stats) {
#if PBNBV_ESTEP_DISPATCH
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  if (avx2) return estep_avx2(n, T, f, ce, L, mx, s, stats);
#endif
  return estep_body(n, T, f, ce, L, mx, s, stats);
}

struct EmWork {
  MatrixXd L;  // log joint densities, then responsibilities (n x T)
  VectorXd mx, s;
};

// The E-step for the current parameters (log-sum-exp per point): returns the log-likelihood
// of the data under the mixture and, if `stats`, the M-step statistics F^T R (10 x T).
double em_pass(const Features& F, const std::vector<CompEval>& ce, EmWork& wk, Stats* stats) {
  const Eigen::Index n = F.rows(), T = static_cast<Eigen::Index>(ce.size());
  wk.L.resize(n, T);
  wk.mx.resize(n);
  wk.s.resize(n);
  if (stats) stats->resize(10, T);
  const double* f[10];
  for (int c = 0; c < 10; ++c) f[c] = F.col(c).data();
  return estep_kernel(static_cast<int>(n), static_cast<int>(T), f, ce.data(), wk.L.data(), wk.mx.data(),
                      wk.s.data(), stats ? stats->data() : nullptr);
}

// The most probable component of every point (the first on ties).
std::vector<int> most_probable(const Features& F, const std::vector<CompEval>& ce) {
  MatrixXd L;
  log_joint_all(F, ce, L);
  std::vector<int> labels(static_cast<size_t>(F.rows()));
  for (Eigen::Index i = 0; i < L.rows(); ++i) {
    int arg = 0;
    double mx = L(i, 0);
    for (Eigen::Index j = 1; j < L.cols(); ++j)
      if (L(i, j) > mx) {
        mx = L(i, j);
        arg = static_cast<int>(j);
      }
    labels[static_cast<size_t>(i)] = arg;
  }
  return labels;
}

// k-means++ seeding: D^2 sampling from mt19937_64(seed). The first T centres do not depend
// on how many are drawn, so one draw of the largest T serves every smaller one.
std::vector<Vector3d> kmeanspp_seeds(const Points3& X, int count, uint64_t seed) {
  const Eigen::Index n = X.cols();
  std::mt19937_64 rng(seed);
  std::vector<Vector3d> centres;
  centres.reserve(static_cast<size_t>(count));
  {
    std::uniform_int_distribution<Eigen::Index> pick(0, n - 1);
    centres.push_back(X.col(pick(rng)));
  }
  std::vector<double> d2(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) d2[static_cast<size_t>(i)] = (X.col(i) - centres[0]).squaredNorm();
  std::uniform_real_distribution<double> unif(0.0, 1.0);
  while (static_cast<int>(centres.size()) < count) {
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
    for (Eigen::Index i = 0; i < n; ++i)
      d2[static_cast<size_t>(i)] = std::min(d2[static_cast<size_t>(i)], (X.col(i) - centres.back()).squaredNorm());
  }
  return centres;
}

// The nearest of the first T centres for every point (the first on ties), from the
// coordinate columns of the features; true if any assignment changed.
bool assign_nearest(const Features& F, const std::vector<Vector3d>& centres, int T, std::vector<int>& assign) {
  const Eigen::Index n = F.rows();
  const double* x = F.col(1).data();
  const double* y = F.col(2).data();
  const double* z = F.col(3).data();
  // Written as selects on doubles so that the loop vectorises.
  std::vector<double> bd(static_cast<size_t>(n), std::numeric_limits<double>::infinity());
  std::vector<double> best(static_cast<size_t>(n), 0.0);
  for (int j = 0; j < T; ++j) {
    const double cx = centres[static_cast<size_t>(j)].x(), cy = centres[static_cast<size_t>(j)].y(),
                 cz = centres[static_cast<size_t>(j)].z();
    const double jd = j;
    double* b = bd.data();
    double* bj = best.data();
    for (Eigen::Index i = 0; i < n; ++i) {
      const double dx = x[i] - cx, dy = y[i] - cy, dz = z[i] - cz;
      const double d = dx * dx + dy * dy + dz * dz;
      const double bi = b[i];
      bj[i] = d < bi ? jd : bj[i];
      b[i] = std::min(d, bi);
    }
  }
  bool changed = false;
  for (size_t i = 0; i < assign.size(); ++i) {
    const int a = static_cast<int>(best[i]);
    changed |= a != assign[i];
    assign[i] = a;
  }
  return changed;
}

// From the first T k-means++ seeds, a few Lloyd iterations; initial weights, means and
// covariances from the resulting hard assignment.
void kmeans_init(const Points3& X, const Features& F, const std::vector<Vector3d>& seeds, int T,
                 double min_variance,
                 std::vector<double>& w, std::vector<Vector3d>& mu, std::vector<Matrix3d>& cov) {
  const Eigen::Index n = X.cols();
  std::vector<Vector3d> centres(seeds.begin(), seeds.begin() + T);
  std::vector<int> assign(static_cast<size_t>(n), 0);
  assign_nearest(F, centres, T, assign);

  // Lloyd refinement (assignments start from the seeds' nearest centres).
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
    if (!assign_nearest(F, centres, T, assign)) break;
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

// EM from the given parameters until the log-likelihood gain < tol_per_point * n or
// max_iterations M-steps; `labels` (the most probable component per point) only if asked.
GaussianMixture em_run(const Features& F, std::vector<double> w, std::vector<Vector3d> mu,
                       std::vector<Matrix3d> cov, double min_variance, const EmOptions& opt,
                       bool want_labels) {
  GaussianMixture g;
  const Eigen::Index n = F.rows();
  const int T = static_cast<int>(w.size());
  EmWork wk;
  Stats st;
  std::vector<CompEval> ce;
  const double tol = opt.tol_per_point * static_cast<double>(n);
  double ll = -std::numeric_limits<double>::infinity();
  // Each pass evaluates the current parameters (log-likelihood) and gathers the statistics
  // of the next ones; on stopping, the parameters of the last pass are returned, so
  // `log_likelihood` is exactly theirs.
  for (int it = 0;; ++it) {
    ce = prepare_all(w, mu, cov, min_variance);
    const double ll_new = em_pass(F, ce, wk, &st);
    const double gain = ll_new - ll;
    ll = ll_new;
    if (gain < tol || it >= opt.max_iterations) break;
    // M-step.
    for (int j = 0; j < T; ++j) {
      const size_t sj = static_cast<size_t>(j);
      const double nj = st(0, j);
      w[sj] = nj / static_cast<double>(n);
      if (nj < 1e-10) continue;  // dead component: keeps its mean and covariance, weight ~0
      const Vector3d m = st.block<3, 1>(1, j) / nj;
      Matrix3d S;
      S << st(4, j), st(5, j), st(6, j), st(5, j), st(7, j), st(8, j), st(6, j), st(8, j), st(9, j);
      mu[sj] = m;
      cov[sj] = S / nj - m * m.transpose() + min_variance * Matrix3d::Identity();
    }
  }

  if (want_labels) g.labels = most_probable(F, ce);
  g.weights = std::move(w);
  g.means = std::move(mu);
  g.covariances = std::move(cov);
  g.log_likelihood = ll;
  const double k = static_cast<double>((T - 1) + 3 * T + 6 * T);
  g.bic = k * std::log(static_cast<double>(n)) - 2.0 * ll;
  return g;
}

// EM with T components on data already centred (the caller adds the offset back to the
// means), initialised from the first T of `seeds`.
GaussianMixture fit_gmm_seeded(const Points3& X, const Features& F, const std::vector<Vector3d>& seeds, int T,
                               double min_variance, const EmOptions& opt, bool want_labels) {
  std::vector<double> w;
  std::vector<Vector3d> mu;
  std::vector<Matrix3d> cov;
  kmeans_init(X, F, seeds, T, min_variance, w, mu, cov);
  return em_run(F, std::move(w), std::move(mu), std::move(cov), min_variance, opt, want_labels);
}

void uncentre(GaussianMixture& g, const Vector3d& offset) {
  for (auto& m : g.means) m += offset;
}

// BIC search over T in [1, min(t_max, n)] on centred data, each T fitted with `opt`; ties keep
// the smaller T. The candidate T run in parallel (each T's fit depends only on T, so the
// result does not depend on the scheduling). `labels` only if asked.
GaussianMixture bic_search_impl(const Points3& X, int t_max, uint64_t seed, double min_variance,
                                const EmOptions& opt, bool want_labels) {
  const Eigen::Index n = X.cols();
  if (n == 0) return GaussianMixture{};
  min_variance = std::max(min_variance, 0.0);
  const int hi = std::max(1, std::min<int>(t_max, static_cast<int>(n)));
  const Features F = make_features(X);
  const std::vector<Vector3d> seeds = kmeanspp_seeds(X, hi, seed);
  std::vector<GaussianMixture> fits(static_cast<size_t>(hi));
  // Largest T (the most work) first, for balance; each fit writes only its own slot.
  parallel_for(static_cast<size_t>(hi), [&](size_t begin, size_t end, int) {
    for (size_t k = begin; k < end; ++k) {
      const int T = hi - static_cast<int>(k);
      fits[static_cast<size_t>(T - 1)] = fit_gmm_seeded(X, F, seeds, T, min_variance, opt, false);
    }
  });
  size_t best = 0;
  for (size_t t = 1; t < fits.size(); ++t)
    if (fits[t].bic < fits[best].bic) best = t;
  GaussianMixture g = std::move(fits[best]);
  if (want_labels) g.labels = most_probable(F, prepare_all(g.weights, g.means, g.covariances, min_variance));
  return g;
}

}  // namespace

GaussianMixture fit_gaussian_mixture(const std::vector<Eigen::Vector3d>& points, int components,
                                     uint64_t seed, double min_variance) {
  Points3 X = as_matrix(points);
  if (X.cols() == 0) return GaussianMixture{};
  const Vector3d offset = X.rowwise().mean();
  X.colwise() -= offset;
  const int T = std::max(1, std::min<int>(components, static_cast<int>(X.cols())));
  GaussianMixture g = fit_gmm_seeded(X, make_features(X), kmeanspp_seeds(X, T, seed), T,
                                     std::max(min_variance, 0.0), EmOptions{}, true);
  uncentre(g, offset);
  return g;
}

GaussianMixture fit_mixture_by_bic(const std::vector<Eigen::Vector3d>& points, int t_max,
                                   uint64_t seed, double min_variance) {
  Points3 X = as_matrix(points);
  const Vector3d offset = X.cols() ? Vector3d(X.rowwise().mean()) : Vector3d::Zero();
  X.colwise() -= offset;
  GaussianMixture g = bic_search_impl(X, t_max, seed, min_variance, EmOptions{}, true);
  uncentre(g, offset);
  return g;
}

GaussianMixture mixture_by_bic(const Eigen::Matrix3Xd& X, int t_max, uint64_t seed, double min_variance,
                               const EmOptions& opt, bool want_labels) {
  return bic_search_impl(X, t_max, seed, min_variance, opt, want_labels);
}

GaussianMixture continue_em(const Eigen::Matrix3Xd& X, const GaussianMixture& start, double min_variance,
                            const EmOptions& opt) {
  return em_run(make_features(X), start.weights, start.means, start.covariances, min_variance, opt, false);
}

std::vector<int> most_probable_components(const Eigen::Matrix3Xd& X, const GaussianMixture& g,
                                          double min_variance) {
  std::vector<Matrix3d> cov = g.covariances;  // prepare_all may regularise them
  return most_probable(make_features(X), prepare_all(g.weights, g.means, cov, min_variance));
}

}  // namespace pbnbv
