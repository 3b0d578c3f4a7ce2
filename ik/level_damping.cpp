// One priority level's damping (the smooth iTaSC rule from an estimate of σ_min), its undamped
// truncated solve on a rank-deficient level, and the per-level trust region.
#include <cmath>

#include <Eigen/Cholesky>

#include "ik/small_cholesky.h"
#include "ik/solver_detail.h"
#include "ik/solver_internal.h"

namespace embody::ik::detail {

namespace {

constexpr int kInverseIterations = 3;  // see levelDamping

double smoothDampingSquared(double sigma, const SolveOptions& o) {
  if (sigma >= o.damping_eps) return 0.0;
  const double x = sigma / o.damping_eps;
  return (1.0 - x * x) * o.damping_max * o.damping_max;
}

}  // namespace

bool levelActive(const Model::Level& level, const Workspace& w) {
  for (TaskId t : level.tasks)
    if (w.enabled[t]) return true;
  return false;
}

// The level's damping λ² from the smallest singular value of Ĵ, computed on G = Ĵ Ĵᵀ (the same
// m x m matrix in both paths up to round-off: the reference path forms it from J P, the fast
// path as J̃J̃ᵀ - (J̃W)(J̃W)ᵀ). Cheap in the common cases:
//   G - eps² I positive definite      -> σ_min > eps, λ = 0;
//   G not positive definite           -> σ_min = 0, λ = λmax;
//   otherwise inverse iteration on G (Cholesky) for σ_min² = λ_min(G).
// Leaves the Cholesky factor of G in w.level_factor[k] (valid when gram_pd); sigma_min is eps when
// undamped (a lower bound) and 0 when G is singular. Three inverse-iteration steps from G⁻¹'s
// largest column match the converged σ_min to 5 digits on random 12-row levels whose smallest
// singular value is separated (8 steps from a fixed vector did not always); with two nearly equal
// smallest values the estimate lies between them, which is all the smooth rule needs.
LevelDamping levelDamping(const Eigen::MatrixXd& gram, Workspace& w, size_t k, const SolveOptions& o) {
  LevelDamping d;
  Eigen::MatrixXd& l = w.level_factor[k];
  Eigen::VectorXd& lInv = w.level_factor_inv[k];
  l = gram;
  d.gram_pd = detail::choleskyInPlace(l, lInv);
  if (!d.gram_pd) {
    d.lambda2 = o.damping_max * o.damping_max;
    return d;
  }
  Eigen::MatrixXd& shifted = w.level_factor2[k];
  shifted = gram;
  shifted.diagonal().array() -= o.damping_eps * o.damping_eps;
  if (detail::choleskyInPlace(shifted, w.level_factor2_inv[k])) {
    d.sigma_min = o.damping_eps;
    return d;
  }
  // Inverse iteration: the Rayleigh quotient of G⁻¹ converges to 1/λ_min(G) as (σ1/σ2)^(2k).
  // A fixed number of steps (no round-off-dependent stopping test) keeps both paths identical;
  // the estimate lies between σ1 and σ2, and the rule only needs it to grow smoothly. G⁻¹ is
  // formed once, so each step is one (vectorised) matrix-vector product, and the start is its
  // column with the largest diagonal entry: G⁻¹ e_i, one step ahead of the best unit vector.
  Eigen::VectorXd& x = w.level_coef[k];
  Eigen::VectorXd& z = w.level_tmp[k];
  Eigen::MatrixXd& inverse = w.level_inverse[k];
  detail::choleskyInverse(l, lInv, w.level_factor2[k], inverse);
  Eigen::Index start = 0;
  inverse.diagonal().maxCoeff(&start);
  x = inverse.col(start);
  double mu = 0.0;
  for (int it = 0; it < kInverseIterations; ++it) {
    const double xn = x.norm();
    if (!(xn > 0) || !std::isfinite(xn)) break;
    x *= 1.0 / xn;
    z.noalias() = inverse * x;
    mu = x.dot(z);
    x.swap(z);
  }
  d.sigma_min = mu > 0 ? std::sqrt(1.0 / mu) : 0.0;
  d.lambda2 = smoothDampingSquared(d.sigma_min, o);
  return d;
}


// The undamped step on a rank-deficient level (damping_max = 0): y := G⁺ y, so that Ĵᵀ y = Ĵ⁺ res
// (least squares, minimum norm), as the reference path's SVD with σ ≤ rank_tolerance dropped.
// A pivoted Cholesky gives G's rank and, with C the m x rank lower-trapezoidal factor of the
// permuted G ≈ C Cᵀ, G⁺ = C (CᵀC)⁻² Cᵀ. Without it the plain solve divides by a round-off pivot
// (|Δq| ~ 1e7 on two copies of one task).
void truncatedSolve(const Eigen::MatrixXd& gram, Workspace& w, size_t k, const SolveOptions& o, Eigen::VectorXd& y) {
  const auto m = gram.rows();
  Eigen::MatrixXd& work = w.level_factor2[k];
  const Eigen::VectorXi& perm = w.level_perm[k];
  const int a = detail::pivotedCholesky(gram, o.rank_tolerance * o.rank_tolerance, static_cast<int>(m), work,
                                        w.level_perm[k], w.level_factor2_inv[k]);
  if (a == 0) {
    y.setZero();
    return;
  }
  work.topLeftCorner(a, a).triangularView<Eigen::StrictlyUpper>().setZero();
  const auto c = work.leftCols(a);
  Eigen::VectorXd& t = w.level_tmp[k];
  for (Eigen::Index i = 0; i < m; ++i) t(i) = y(perm(i));
  auto u = w.level_coef[k].head(a);
  u.noalias() = c.transpose() * t;
  auto gram_c = w.level_solve.topLeftCorner(a, a);
  gram_c.noalias() = c.transpose() * c;
  Eigen::internal::llt_inplace<double, Eigen::Lower>::blocked(gram_c);
  for (int twice = 0; twice < 2; ++twice) {
    gram_c.triangularView<Eigen::Lower>().solveInPlace(u);
    gram_c.triangularView<Eigen::Lower>().transpose().solveInPlace(u);
  }
  t.noalias() = c * u;
  for (Eigen::Index i = 0; i < m; ++i) y(perm(i)) = t(i);
}


// Scale for one level's contribution to Δq of norm `norm` (1 when within the trust region).
double levelStepScale(double norm, const SolveOptions& o) {
  if (!(o.max_level_step > 0) || !std::isfinite(o.max_level_step) || !(norm > o.max_level_step)) return 1.0;
  return o.max_level_step / norm;
}

}  // namespace embody::ik::detail
