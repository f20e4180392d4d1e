// The minimum-volume enclosing ellipsoid: Khachiyan's algorithm with Todd-Yildirim away steps
// and rank-one updates, on an active set of extreme points grown until every point is enclosed.
#include "core/planning/mvee.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

namespace pbnbv {

namespace {

using Points3 = Eigen::Matrix3Xd;
using Eigen::Matrix3d;
using Eigen::Matrix4d;
using Eigen::Vector3d;
using Eigen::VectorXd;

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

Ellipsoid minimum_volume_ellipsoid(const std::vector<Eigen::Vector3d>& points, double tol) {
  const Points3 P = Eigen::Map<const Points3>(points.empty() ? nullptr : points[0].data(), 3,
                                              static_cast<Eigen::Index>(points.size()));
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

}  // namespace pbnbv
