// Ellipsoids of occupied and frontier structure: Gaussian mixture by EM with T chosen by BIC,
// then the minimum-volume enclosing ellipsoid (Khachiyan) of each cluster's voxel corners.
#include "core/planning/ellipsoids.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <limits>
#include <numeric>
#include <random>
#include <thread>
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
// Log densities more than 50 below a point's best component are clamped (see exp_clamped).
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

// Runs fn(i) for every i in [0, count) on at most two threads (the caller's and one more),
// which take the indices in increasing order from a shared counter. Each fn(i) must write
// only its own results, so they do not depend on the scheduling.
template <class Fn>
void parallel_for(int count, const Fn& fn) {
  static const unsigned cores = std::thread::hardware_concurrency();
  if (count <= 1 || cores < 2) {
    for (int i = 0; i < count; ++i) fn(i);
    return;
  }
  std::atomic<int> next{0};
  std::exception_ptr helper_error;
  auto work = [&]() {
    for (int i = next.fetch_add(1); i < count; i = next.fetch_add(1)) fn(i);
  };
  std::thread helper([&]() {
    try {
      work();
    } catch (...) {
      helper_error = std::current_exception();
      next = count;
    }
  });
  std::exception_ptr own_error;
  try {
    work();
  } catch (...) {
    own_error = std::current_exception();
    next = count;
  }
  helper.join();
  if (own_error) std::rethrow_exception(own_error);
  if (helper_error) std::rethrow_exception(helper_error);
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
// the smaller T. The candidate T run on two threads (each T's fit depends only on T, so the
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
  // Largest T (the most work) first, for balance.
  parallel_for(hi, [&](int k) {
    const int T = hi - k;
    fits[static_cast<size_t>(T - 1)] = fit_gmm_seeded(X, F, seeds, T, min_variance, opt, false);
  });
  size_t best = 0;
  for (size_t t = 1; t < fits.size(); ++t)
    if (fits[t].bic < fits[best].bic) best = t;
  GaussianMixture g = std::move(fits[best]);
  if (want_labels) g.labels = most_probable(F, prepare_all(g.weights, g.means, g.covariances, min_variance));
  return g;
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
  Points3 X = to_matrix(points);
  const Vector3d offset = X.cols() ? Vector3d(X.rowwise().mean()) : Vector3d::Zero();
  X.colwise() -= offset;
  GaussianMixture g = bic_search_impl(X, t_max, seed, min_variance, EmOptions{}, true);
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

// The corners of the voxels that can be vertices of their convex hull, so the MVEE of the
// returned corners equals that of all corners. A corner on the +x side of its voxel lies
// strictly inside a segment between two other corners unless the voxel is the last of the
// set along its x line (likewise -x/first, and y, z): only corners whose voxel is extreme on
// the corner's side along all three axis lines are kept (shared ones once). If the centres
// are not on a common lattice of pitch `voxel`, all corners are returned.
std::vector<Vector3d> hull_candidate_corners(const std::vector<Vector3d>& centres, double voxel) {
  const double h = 0.5 * voxel;
  const size_t n = centres.size();
  std::vector<Eigen::Vector3i> idx(n);
  bool lattice = voxel > 0;
  const Vector3d c0 = centres.empty() ? Vector3d::Zero() : centres[0];
  for (size_t i = 0; i < n && lattice; ++i) {
    const Vector3d q = (centres[i] - c0) / voxel;
    const Vector3d r = q.array().round();
    if ((q - r).cwiseAbs().maxCoeff() > 1e-3 || r.cwiseAbs().maxCoeff() > 1e6) lattice = false;
    idx[i] = r.cast<int>();
  }
  std::vector<Vector3d> corners;
  if (!lattice) {
    corners.reserve(8 * n);
    for (const auto& c : centres)
      for (int m = 0; m < 8; ++m)
        corners.push_back(c + Vector3d((m & 1) ? h : -h, (m & 2) ? h : -h, (m & 4) ? h : -h));
    return corners;
  }

  Eigen::Vector3i lo = idx[0], hi = idx[0];
  for (const auto& v : idx) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const Eigen::Matrix<int64_t, 3, 1> dims = (hi - lo).cast<int64_t>().array() + 1;
  // ext[i] bit 2a: voxel i is the first along its axis-a line; bit 2a+1: the last.
  std::vector<uint8_t> ext(n, 0);
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    auto mark = [&](auto& range_of) {
      for (const auto& v : idx) {
        auto& r = range_of(v);
        r.first = std::min(r.first, v[axis]);
        r.second = std::max(r.second, v[axis]);
      }
      for (size_t i = 0; i < n; ++i) {
        const auto& r = range_of(idx[i]);
        if (idx[i][axis] == r.first) ext[i] |= static_cast<uint8_t>(1u << (2 * axis));
        if (idx[i][axis] == r.second) ext[i] |= static_cast<uint8_t>(2u << (2 * axis));
      }
    };
    const std::pair<int, int> empty(std::numeric_limits<int>::max(), std::numeric_limits<int>::min());
    const int64_t cells = dims[a1] * dims[a2];
    if (cells <= 8 * static_cast<int64_t>(n) + 4096) {
      std::vector<std::pair<int, int>> grid(static_cast<size_t>(cells), empty);
      auto range_of = [&](const Eigen::Vector3i& v) -> std::pair<int, int>& {
        return grid[static_cast<size_t>((v[a1] - lo[a1]) * dims[a2] + (v[a2] - lo[a2]))];
      };
      mark(range_of);
    } else {
      std::unordered_map<uint64_t, std::pair<int, int>> map;
      map.reserve(2 * n);
      auto range_of = [&](const Eigen::Vector3i& v) -> std::pair<int, int>& {
        const uint64_t key = (static_cast<uint64_t>(static_cast<uint32_t>(v[a1])) << 32) |
                             static_cast<uint32_t>(v[a2]);
        return map.emplace(key, empty).first->second;
      };
      mark(range_of);
    }
  }
  std::vector<std::array<int, 3>> ci;
  for (size_t i = 0; i < n; ++i) {
    for (int m = 0; m < 8; ++m) {
      bool keep = true;
      for (int a = 0; a < 3 && keep; ++a) keep = (ext[i] >> (2 * a + ((m >> a) & 1))) & 1u;
      if (keep) ci.push_back({idx[i][0] + (m & 1), idx[i][1] + ((m >> 1) & 1), idx[i][2] + ((m >> 2) & 1)});
    }
  }
  std::sort(ci.begin(), ci.end());
  ci.erase(std::unique(ci.begin(), ci.end()), ci.end());
  corners.reserve(ci.size());
  const Vector3d base = c0 - Vector3d::Constant(h);
  for (const auto& c : ci) corners.push_back(base + voxel * Vector3d(c[0], c[1], c[2]));
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
  GaussianMixture g = bic_search_impl(Xem, params.t_max, params.seed, min_variance, search, false);
  {
    EmOptions rest;
    rest.max_iterations = EmOptions{}.max_iterations - kSearchIterations;
    g = em_run(make_features(Xem), g.weights, g.means, g.covariances, min_variance, rest, false);
  }
  const int T = static_cast<int>(g.weights.size());
  if (components) *components = T;

  const std::vector<int> labels =
      most_probable(make_features(Xall), prepare_all(g.weights, g.means, g.covariances, min_variance));
  std::vector<std::vector<Vector3d>> members(static_cast<size_t>(T));
  for (size_t i = 0; i < n; ++i) members[static_cast<size_t>(labels[i])].push_back(voxel_centres[i]);
  members.erase(std::remove_if(members.begin(), members.end(),
                               [](const std::vector<Vector3d>& m) { return m.empty(); }),
                members.end());  // clusters that end up empty are dropped
  out.resize(members.size());
  parallel_for(static_cast<int>(members.size()), [&](int k) {
    const auto& m = members[static_cast<size_t>(k)];
    Ellipsoid e = minimum_volume_ellipsoid(hull_candidate_corners(m, voxel));
    e.cls = cls;
    e.num_points = static_cast<int>(m.size());
    out[static_cast<size_t>(k)] = e;
  });
  return out;
}

}  // namespace pbnbv
