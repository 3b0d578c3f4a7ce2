#pragma once
// Cholesky kernels for the small m x m systems of one priority level (m = a level's task rows,
// at most a few dozen, usually 2 to 12). At these sizes the cost of Eigen's general LLT and
// blocked triangular solvers is mostly call overhead and division latency, so these are plain
// loops over column-major storage: the inner loops run down a column (contiguous, vectorisable)
// and every division is replaced by a multiplication with the diagonal's stored reciprocal.
// Private to ik (used by the solver and its tests).
#include <Eigen/Core>

#include <cmath>
#include <limits>

namespace embody::ik::detail {

// Factors the lower triangle of `a` (m x m, the upper triangle is not read) in place into L with
// a = L Lᵀ, and stores 1 / L(j, j) in inv_diag. Returns false, with `a` partly overwritten, when
// `a` is not numerically positive definite (a pivot ≤ 0 or not finite).
inline bool choleskyInPlace(Eigen::MatrixXd& a, Eigen::VectorXd& inv_diag) {
  const Eigen::Index m = a.rows();
  double* p = a.data();
  const Eigen::Index ld = a.outerStride();
  for (Eigen::Index j = 0; j < m; ++j) {
    double* cj = p + j * ld;
    const double d = cj[j];
    if (!(d > 0.0) || !(d < std::numeric_limits<double>::infinity())) return false;
    const double l = std::sqrt(d);
    const double inv = 1.0 / l;
    cj[j] = l;
    inv_diag[j] = inv;
    for (Eigen::Index i = j + 1; i < m; ++i) cj[i] *= inv;
    for (Eigen::Index k = j + 1; k < m; ++k) {  // trailing update, column by column
      double* ck = p + k * ld;
      const double c = cj[k];
      for (Eigen::Index i = k; i < m; ++i) ck[i] -= cj[i] * c;
    }
  }
  return true;
}

// x := L⁻¹ x.
inline void solveLower(const Eigen::MatrixXd& l, const Eigen::VectorXd& inv_diag, double* x) {
  const Eigen::Index m = l.rows();
  const double* p = l.data();
  const Eigen::Index ld = l.outerStride();
  for (Eigen::Index j = 0; j < m; ++j) {
    const double xj = (x[j] *= inv_diag[j]);
    const double* cj = p + j * ld;
    for (Eigen::Index i = j + 1; i < m; ++i) x[i] -= cj[i] * xj;
  }
}

// x := L⁻ᵀ x.
inline void solveLowerTransposed(const Eigen::MatrixXd& l, const Eigen::VectorXd& inv_diag, double* x) {
  const Eigen::Index m = l.rows();
  const double* p = l.data();
  const Eigen::Index ld = l.outerStride();
  for (Eigen::Index j = m; j-- > 0;) {
    const double* cj = p + j * ld;
    double v = x[j];
    for (Eigen::Index i = j + 1; i < m; ++i) v -= cj[i] * x[i];
    x[j] = v * inv_diag[j];
  }
}

// x := (L Lᵀ)⁻¹ x.
inline void choleskySolve(const Eigen::MatrixXd& l, const Eigen::VectorXd& inv_diag, double* x) {
  solveLower(l, inv_diag, x);
  solveLowerTransposed(l, inv_diag, x);
}

// B := B L⁻ᵀ for a block B with m columns (any row count, column-major, inner stride 1). Column
// j of the result is (B.col(j) - Σ_{i<j} L(j, i) result.col(i)) / L(j, j): every operation is an
// axpy down a column, so this layout vectorises where the row-wise L⁻¹ B would not. L⁻¹ B is
// this applied to Bᵀ.
template <typename Lower, typename Block>
void solveRightLowerTransposed(const Lower& l, const Eigen::VectorXd& inv_diag, Block&& b) {
  const Eigen::Index m = l.rows();
  const Eigen::Index rows = b.rows();
  for (Eigen::Index j = 0; j < m; ++j) {
    double* bj = &b.coeffRef(0, j);
    for (Eigen::Index i = 0; i < j; ++i) {
      const double c = l(j, i);
      const double* bi = &b.coeffRef(0, i);
      for (Eigen::Index r = 0; r < rows; ++r) bj[r] -= c * bi[r];
    }
    const double inv = inv_diag[j];
    for (Eigen::Index r = 0; r < rows; ++r) bj[r] *= inv;
  }
}

// inverse := (L Lᵀ)⁻¹ = L⁻ᵀ L⁻¹ (full symmetric), through L⁻ᵀ (in `scratch`).
inline void choleskyInverse(const Eigen::MatrixXd& l, const Eigen::VectorXd& inv_diag, Eigen::MatrixXd& scratch,
                            Eigen::MatrixXd& inverse) {
  scratch.setIdentity();
  solveRightLowerTransposed(l, inv_diag, scratch);  // L⁻ᵀ
  inverse.setZero();
  inverse.selfadjointView<Eigen::Lower>().rankUpdate(scratch);
  inverse.triangularView<Eigen::StrictlyUpper>() = inverse.transpose();
}

// Rank-revealing Cholesky with diagonal pivoting of a positive semidefinite g (m x m, lower
// triangle read): G(I, I) = L Lᵀ for the rows I = perm[0, rank) picked greatest remaining
// diagonal first, stopping when that diagonal is ≤ tol2 (or at max_rank). `work` (m x m) ends
// with L in its leading rank x rank lower triangle and inv_diag with its diagonal's reciprocals.
// The rows I of a matrix whose Gram matrix is g then span its row space (to the tolerance):
// a rank-deficient level's projector update needs this, not an eigen-decomposition. Returns rank.
inline int pivotedCholesky(const Eigen::MatrixXd& g, double tol2, int max_rank, Eigen::MatrixXd& work,
                           Eigen::VectorXi& perm, Eigen::VectorXd& inv_diag) {
  const Eigen::Index m = g.rows();
  work = g.selfadjointView<Eigen::Lower>();
  for (Eigen::Index i = 0; i < m; ++i) perm(i) = static_cast<int>(i);
  for (Eigen::Index j = 0; j < m; ++j) {
    Eigen::Index p = j;
    for (Eigen::Index i = j + 1; i < m; ++i)
      if (work(i, i) > work(p, p)) p = i;
    const double d = work(p, p);
    if (j >= max_rank || !(d > tol2) || !(d < std::numeric_limits<double>::infinity())) return static_cast<int>(j);
    if (p != j) {  // symmetric swap of j and p (rows and columns, factored part included)
      work.row(j).swap(work.row(p));
      work.col(j).swap(work.col(p));
      std::swap(perm(j), perm(p));
    }
    const double l = std::sqrt(work(j, j));
    work(j, j) = l;
    inv_diag(j) = 1.0 / l;
    work.col(j).tail(m - j - 1) *= inv_diag(j);
    for (Eigen::Index k = j + 1; k < m; ++k)  // trailing update, both triangles (the swaps read rows)
      work.col(k).tail(m - j - 1) -= work(k, j) * work.col(j).tail(m - j - 1);
    work.row(j).tail(m - j - 1) = work.col(j).tail(m - j - 1).transpose();
  }
  return static_cast<int>(m);
}

}  // namespace embody::ik::detail
